"""The Hertz sphere: the lower half of a ball of radius 0.4 centred at (0, 0, 0.4),
its flat top z = 0.4 displaced by (0, 0, -D), pressed onto the rigid plane z = 0; and Hertz's formulas
for a sphere on a half space."""
from __future__ import annotations

import math

import numpy as np

from ..model.friction import Coulomb, Frictionless
from ..mesh.generators_3d import BALL_SURFACE, BALL_TOP, ball_projector, half_ball
from ..mesh.hierarchy import MeshHierarchy
from ..model.material import Material
from ..model.obstacle import PlaneObstacle
from ..solve.adaptivity import adaptive_hierarchy
from ..model.problem import Body, Dirichlet, Problem
from ..solve.options import with_cycle

E, NU = 2000.0, 0.28
CENTER, RADIUS = (0.0, 0.0, 0.4), 0.4
# The approach for a contact radius of about 0.1 (6 elements of the default level 3 across it):
# Hertz's a^2 / R is 0.025; the ball's own compression above the contact takes part of D.
DISPLACEMENT = 0.02
DEFAULT_LEVELS = 3
# the coarse mesh: a block of 2K x 2K x K cubes of half-width INNER * R, two ring layers
K, INNER = 3, 0.5


def element_width(levels: int) -> float:
    """The width of the cells at the bottom of the ball on the finest of `levels` levels."""
    return INNER * RADIUS / K / 2 ** (levels - 1)


HIERARCHIES = ("uniform", "adaptive")
# bulk parameter of the adaptive sphere hierarchy (Doerfler). Measured from the default coarse mesh
# (2,286 dofs), levels 1-5: theta = 0.5 gives 2,286 / 2,382 / 3,009 ... (a level adds 5-30 %, too
# little for a multigrid level), 0.7 gives 2,286 / 2,532 / 3,345 / 10,881 / 61,269 (estimate 0.187 ->
# 0.020), 0.85 gives 2,286 / 2,571 / 4,734 / 25,005 / 156,141 (-> 0.016).
ADAPTIVE_THETA = 0.7
ADAPTIVE_MAX_CYCLES = 2000


def sphere_problem(cell: str = "hexahedron", levels: int = DEFAULT_LEVELS, friction: float = 0.4,
                   displacement: float = DISPLACEMENT, coulomb_at_zero: bool = False, cycle: str = "F",
                   nu1: int = 3, nu2: int = 3, material: Material = None, hierarchy="uniform",
                   memory_fraction: float = 0.8) -> Problem:
    """The half ball (tetra or hexahedron cells) pushed by u = (0, 0, -displacement) on its top onto
    z = 0, with Coulomb friction F (frictionless for F = 0 unless coulomb_at_zero). `hierarchy`:
    "uniform" (refinement of the coarse mesh), "adaptive" (sphere_adaptive_hierarchy for this
    friction; tetrahedra only) or a MeshHierarchy of the half ball. memory_fraction: of the available memory that the
    hierarchy's estimate may take (MeshHierarchy.build)."""
    _check_friction(friction)
    _check_displacement(displacement)
    if isinstance(hierarchy, MeshHierarchy):
        h = hierarchy
    elif hierarchy == "uniform":
        h = MeshHierarchy.build(half_ball(cell, CENTER, RADIUS, k=K, inner=INNER), levels,
                                projector=ball_projector(CENTER, RADIUS), memory_fraction=memory_fraction)
    elif hierarchy == "adaptive":
        h = sphere_adaptive_hierarchy(levels, friction, displacement, cell=cell, material=material)
    else:
        raise ValueError(f"hierarchy must be one of {HIERARCHIES} or a MeshHierarchy, got {hierarchy!r}")
    return sphere_problem_on(h, friction, displacement, coulomb_at_zero, cycle, nu1, nu2, material)


def sphere_problem_on(hierarchy: MeshHierarchy, friction: float = 0.4, displacement: float = DISPLACEMENT,
                      coulomb_at_zero: bool = False, cycle: str = "F", nu1: int = 3, nu2: int = 3,
                      material: Material = None) -> Problem:
    """The sphere problem on a given hierarchy of the half ball."""
    law = Coulomb(friction) if (friction > 0 or coulomb_at_zero) else Frictionless()
    body = Body(hierarchy, material or Material(E, NU), [Dirichlet([BALL_TOP], (0.0, 0.0, -displacement))],
                contact_tags=[BALL_SURFACE])
    return with_cycle(Problem(body, obstacle=PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)), friction=law), cycle, nu1, nu2)


def sphere_adaptive_hierarchy(levels: int, friction: float = 0.4, displacement: float = DISPLACEMENT,
                              theta: float = ADAPTIVE_THETA, cell: str = "tetra", material: Material = None,
                              coarse=None, progress=None) -> MeshHierarchy:
    """The adaptive sphere hierarchy: the coarse tetrahedral half ball refined by the hierarchical
    estimator of the sphere problem with friction F, bulk marking with `theta` and newest-vertex
    bisection of tetrahedra (MeshHierarchy.adaptive); new nodes on the ball's surface projected onto
    the sphere. Adaptivity is for simplices: cell must be "tetra"."""
    if cell != "tetra":
        raise ValueError(f"the adaptive hierarchy is for simplices (bisection of tetrahedra): use cell 'tetra', "
                         f"got {cell!r}")
    _check_friction(friction)
    _check_displacement(displacement)
    mesh = half_ball("tetra", CENTER, RADIUS, k=K, inner=INNER) if coarse is None else coarse
    # level 1 alone has no coarse correction: its solve contracts by about 0.93 per cycle (measured:
    # 230 cycles frictionless, 190 at F = 0.4 on the default coarse mesh), hence the cycle budget
    return adaptive_hierarchy(mesh, levels, lambda h: sphere_problem_on(h, friction, displacement, material=material),
                                  projector=ball_projector(CENTER, RADIUS), theta=theta, progress=progress,
                                  solve_options={"max_cycles": ADAPTIVE_MAX_CYCLES})


def _check_friction(friction):
    if isinstance(friction, bool) or not isinstance(friction, (int, float)) or not math.isfinite(friction) or friction < 0:
        raise ValueError(f"the friction coefficient must be a finite number >= 0, got {friction!r}")


def _check_displacement(displacement):
    if isinstance(displacement, bool) or not isinstance(displacement, (int, float)) or not math.isfinite(displacement) \
            or not 0 < displacement < 0.25 * RADIUS:
        raise ValueError(f"the displacement D must lie in (0, {0.25 * RADIUS}) (small deformations), got {displacement!r}")


def contact_modulus(material: Material = Material(E, NU)) -> float:
    """E* = E / (1 - nu^2) for an elastic sphere on a rigid plane."""
    return material.E / (1 - material.nu ** 2)


def hertz_radius(load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> float:
    """a = (3 P R / (4 E*))^(1/3)."""
    return (3 * load * radius / (4 * contact_modulus(material))) ** (1.0 / 3.0)


def hertz_p0(load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> float:
    """Peak pressure p0 = 3 P / (2 pi a^2)."""
    return 3 * load / (2 * math.pi * hertz_radius(load, radius, material) ** 2)


def hertz_pressure(r: np.ndarray, load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> np.ndarray:
    """p0 sqrt(1 - (r/a)^2) inside the contact disc, 0 outside."""
    a = hertz_radius(load, radius, material)
    return hertz_p0(load, radius, material) * np.sqrt(np.clip(1 - (np.asarray(r) / a) ** 2, 0, None))


def radial_distance(result, center=CENTER) -> np.ndarray:
    """Distance from the ball's axis of each contact node of `result`."""
    x = result.mesh.points[result.contact_nodes]
    return np.hypot(x[:, 0] - center[0], x[:, 1] - center[1])


def radius_of(result, states) -> float:
    """Largest distance from the axis of a contact node in one of `states` (0 if none)."""
    sel = np.isin(result.contact_state, states)
    return float(radial_distance(result)[sel].max()) if np.any(sel) else 0.0


def central_pressure(result) -> float:
    """The normal contact stress at the node on the axis (the bottom point)."""
    r = radial_distance(result)
    return float(-result.normal_stress[np.argmin(r)])
