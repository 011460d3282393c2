"""The Hertz half disk and the Hertz sphere as distributed problems: the meshes, loads and obstacles
of contactmg.examples.hertz and .sphere, on a DistributedHierarchy of the same coarse mesh (so their
solutions are those of the serial examples' uniform hierarchies, node for node). `friction` is the
contact's friction law: Frictionless() (None), Tresca(bound) or Coulomb(coefficient)."""
from __future__ import annotations

from . import hertz as _hertz
from . import sphere as _sphere
from ..mesh.generators import HERTZ_ARC, HERTZ_TOP, hertz_half_disk, hertz_projector
from ..mesh.generators_3d import BALL_SURFACE, BALL_TOP, ball_projector, half_ball
from ..model.friction import Coulomb, Frictionless, Tresca
from ..model.material import Material
from ..model.obstacle import PlaneObstacle
from ..model.problem import Dirichlet
from ..distributed.comm import get_comm
from ..distributed.hierarchy import DistributedHierarchy
from ..distributed.problem import DistributedProblem


def _friction(friction):
    if friction is None:
        return Frictionless()
    if not isinstance(friction, (Frictionless, Tresca, Coulomb)):
        raise TypeError(f"friction must be Frictionless(), Tresca(bound) or Coulomb(coefficient), got {friction!r}")
    return friction


def hertz(levels: int = 6, cell: str = "triangle", friction=None, comm=None, part=None) -> DistributedProblem:
    """The Hertz half disk (contactmg.examples.hertz) on `levels` uniform levels."""
    comm = get_comm(comm)
    h = DistributedHierarchy.build(hertz_half_disk(cell), levels, comm, part=part,
                                   projector=hertz_projector(_hertz.CENTER, _hertz.RADIUS))
    return DistributedProblem(h, Material(_hertz.E, _hertz.NU), [Dirichlet([HERTZ_TOP], (0.0, _hertz.TOP_DISPLACEMENT))],
                              contact_tags=[HERTZ_ARC], obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)),
                              friction=_friction(friction))


def sphere(levels: int = 3, cell: str = "hexahedron", friction=None, comm=None, part=None) -> DistributedProblem:
    """The Hertz sphere (contactmg.examples.sphere) on `levels` uniform levels."""
    comm = get_comm(comm)
    coarse = half_ball(cell, _sphere.CENTER, _sphere.RADIUS, k=_sphere.K, inner=_sphere.INNER)
    h = DistributedHierarchy.build(coarse, levels, comm, part=part, projector=ball_projector(_sphere.CENTER, _sphere.RADIUS))
    return DistributedProblem(h, Material(_sphere.E, _sphere.NU),
                              [Dirichlet([BALL_TOP], (0.0, 0.0, -_sphere.DISPLACEMENT))], contact_tags=[BALL_SURFACE],
                              obstacle=PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)), friction=_friction(friction))
