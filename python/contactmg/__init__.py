"""contactmg: nonlinear monotone multigrid for elastic contact with Coulomb friction."""
import os as _os

# Threads that wait at a barrier sleep rather than spin: the machine may be shared (a spinning
# waiter on an occupied core made a 2-thread solve many times slower than 1 thread there).
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
from . import _core  # noqa: F401,E402
from .model.friction import Coulomb, Frictionless, Tresca
from .model.frames import contact_frames
from .mesh.generators import (HERTZ_ARC, HERTZ_TOP, RECT_BOTTOM, RECT_LEFT, RECT_RIGHT, RECT_TOP, CircleProjector,
                         hertz_half_disk, hertz_projector, rectangle)
from .mesh.hierarchy import MeshHierarchy, Transfer
from .mesh.io import read_mesh, to_meshio, write_mesh
from .model.material import Material
from .mesh.mesh import Mesh
from .model.obstacle import NodalObstacle, PlaneObstacle
from .model.loads import PointLoad
from .model.problem import Body, ContactBoundary, ContactPair, Dirichlet, ObstacleContact, Problem
from .solve.options import SolverOptions, resolve_options
from .solve.solver import Solver
from .solve.loadpath import LoadPath, PathResult
from .solve.adaptivity import adaptive_hierarchy
from .solve.contact_problem import ContactProblem, MultiBodyProblem, TwoBodyProblem
from .results.result import ContactResult

from .mesh.generators_3d import (BALL_SURFACE, BALL_TOP, CORK_BOTTOM, CORK_SIDE, CORK_TOP, CylinderProjector,  # noqa: E402
                            SphereProjector, ball_projector, box, cylinder, half_ball)
from .model.obstacle import CylinderObstacle, MeshObstacle, RevolutionObstacle, SphereObstacle  # noqa: E402

__version__ = "0.2.0"

__all__ = ["Coulomb", "Frictionless", "Tresca", "contact_frames", "HERTZ_ARC", "HERTZ_TOP", "RECT_BOTTOM",
           "RECT_LEFT", "RECT_RIGHT", "RECT_TOP", "CircleProjector", "hertz_half_disk", "hertz_projector",
           "rectangle", "MeshHierarchy", "Transfer", "read_mesh", "to_meshio", "write_mesh", "Material", "Mesh",
           "NodalObstacle", "PlaneObstacle", "ContactBoundary", "Problem", "Body", "ContactPair", "Dirichlet", "ObstacleContact", "PointLoad",
           "Solver", "SolverOptions", "resolve_options", "LoadPath", "PathResult", "adaptive_hierarchy",
           "ContactProblem", "MultiBodyProblem", "TwoBodyProblem", "ContactResult",
           "BALL_SURFACE", "BALL_TOP", "CORK_BOTTOM", "CORK_SIDE", "CORK_TOP", "CylinderProjector", "SphereProjector",
           "ball_projector", "box", "cylinder", "half_ball", "RevolutionObstacle", "SphereObstacle", "CylinderObstacle", "MeshObstacle"]
