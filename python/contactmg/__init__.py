"""contactmg: nonlinear monotone multigrid for elastic contact with Coulomb friction."""
import os as _os

# Threads that wait at a barrier sleep rather than spin: the machine may be shared (a spinning
# waiter on an occupied core made a 2-thread solve many times slower than 1 thread there).
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
from . import _core  # noqa: F401,E402
from .friction import Coulomb, Frictionless, Tresca
from .frames import contact_frames
from .generators import (HERTZ_ARC, HERTZ_TOP, RECT_BOTTOM, RECT_LEFT, RECT_RIGHT, RECT_TOP, CircleProjector,
                         hertz_half_disk, hertz_projector, rectangle)
from .hierarchy import MeshHierarchy, Transfer
from .io import read_mesh, to_meshio, write_mesh
from .material import Material
from .mesh import Mesh
from .obstacle import NodalObstacle, PlaneObstacle
from .problem import ContactBoundary, ContactProblem, CycleOptions, Dirichlet
from .results import ContactResult

# 3D (issue 10)
from .generators_3d import (BALL_SURFACE, BALL_TOP, CORK_BOTTOM, CORK_SIDE, CORK_TOP, CylinderProjector,  # noqa: E402
                            SphereProjector, ball_projector, box, cylinder, half_ball)
from .obstacle import RevolutionObstacle, SphereObstacle  # noqa: E402

__version__ = "0.1.0"

__all__ = ["Coulomb", "Frictionless", "Tresca", "contact_frames", "HERTZ_ARC", "HERTZ_TOP", "RECT_BOTTOM",
           "RECT_LEFT", "RECT_RIGHT", "RECT_TOP", "CircleProjector", "hertz_half_disk", "hertz_projector",
           "rectangle", "MeshHierarchy", "Transfer", "read_mesh", "to_meshio", "write_mesh", "Material", "Mesh",
           "NodalObstacle", "PlaneObstacle", "ContactBoundary", "ContactProblem", "CycleOptions", "Dirichlet",
           "ContactResult",
           "BALL_SURFACE", "BALL_TOP", "CORK_BOTTOM", "CORK_SIDE", "CORK_TOP", "CylinderProjector", "SphereProjector",
           "ball_projector", "box", "cylinder", "half_ball", "RevolutionObstacle", "SphereObstacle"]
