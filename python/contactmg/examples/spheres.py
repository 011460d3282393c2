"""Two elastic hemispheres pressed together (the two-body Hertz problem in 3D) and `contactmg spheres`.

The upper body is the Hertz half ball of `contactmg sphere` (centre (0, 0, 0.4), radius 0.4, its
dome below, the nonmortar side); the lower one is its mirror image below z = 0 (centre (0, 0, -0.4),
dome on top, the mortar side), meshed differently (its coarse block of 2k x 2k x k cubes is 0.4 R
wide instead of 0.5 R), so the interface does not match. Their flat faces are moved towards each other by D
each: for equal materials the interface stays on z = 0 and each body is the one-body sphere with
displacement D against a frictionless plane."""
from __future__ import annotations

import math

import numpy as np

from ..model.friction import Coulomb, Frictionless
from ..mesh.generators_3d import BALL_SURFACE, BALL_TOP, SphereProjector, half_ball
from ..mesh.hierarchy import MeshHierarchy
from ..model.material import Material
from ..mesh.mesh import Mesh
from ..model.problem import Body, ContactPair, Dirichlet, Problem
from ..solve.options import with_cycle

E, NU, RADIUS = 2000.0, 0.28, 0.4
UPPER_CENTER, LOWER_CENTER = (0.0, 0.0, RADIUS), (0.0, 0.0, -RADIUS)
DISPLACEMENT = 0.02  # each flat face; with equal materials the contact radius of `contactmg sphere`
DEFAULT_LEVELS = 3
# the coarse meshes (half_ball's k and inner): the lower block is narrower, so the element widths at
# the contact differ by a quarter and no node of one dome meets one of the other except at the
# pole. (k = 4 below gave a coarsest level of 1,261 nodes whose factorization dominated the cycle.)
UPPER_K, LOWER_K = 3, 3
UPPER_INNER, LOWER_INNER = 0.5, 0.4
# the possible contact zone: the nonmortar dome within this distance of the axis (Hertz radius ~0.1).
# Not larger: the normal of the upper dome at angle theta from the axis passes the lower centre at
# 2 R sin(theta); from theta = 30 degrees (r = R/2) on it misses the lower dome, which then cannot
# cover the nonmortar supports there.
ZONE = 0.375 * RADIUS
SEARCH = 0.5 * RADIUS


def lower_half_ball(cell: str = "hexahedron", k: int = LOWER_K, inner: float = LOWER_INNER) -> Mesh:
    """The upper half of the ball (LOWER_CENTER, RADIUS): the mirror image in z = 0 of the half ball
    of `contactmg sphere` with a k-block core; tags BALL_SURFACE (dome) and BALL_TOP (its flat face
    z = -R, kept as the name of the face that is driven)."""
    m = half_ball(cell, UPPER_CENTER, RADIUS, k=k, inner=inner)
    pts = m.points * [1.0, 1.0, -1.0]
    # the mirror reverses every cell's orientation: swap its two halves (hexahedra) or two nodes (tetrahedra)
    cells = m.cells[:, [4, 5, 6, 7, 0, 1, 2, 3]] if cell == "hexahedron" else m.cells[:, [0, 2, 1, 3]]
    cz = LOWER_CENTER[2]

    def tagger(mid):
        return np.where(np.abs(mid[:, 2] - cz) < 1e-9 * RADIUS, BALL_TOP, BALL_SURFACE)

    return Mesh.from_cells(pts, np.ascontiguousarray(cells), cell, tagger)


def spheres_problem(cell: str = "hexahedron", levels: int = DEFAULT_LEVELS, friction: float = 0.4, E2: float = E,
                    nu2: float = NU, displacement: float = DISPLACEMENT, coulomb_at_zero: bool = False,
                    cycle: str = "F", nu1: int = 3, nu2_sweeps: int = 3, upper_k: int = UPPER_K,
                    lower_k: int = LOWER_K, lower_inner: float = LOWER_INNER) -> Problem:
    """The two hemispheres, the upper (E, NU) nonmortar, the lower (E2, nu2) mortar, each flat face
    moved by `displacement` towards the other; Coulomb friction F on the relative tangential
    displacement (frictionless for F = 0 unless coulomb_at_zero)."""
    if isinstance(friction, bool) or not isinstance(friction, (int, float)) or not math.isfinite(friction) or friction < 0:
        raise ValueError(f"the friction coefficient must be a finite number >= 0, got {friction!r}")
    if isinstance(displacement, bool) or not isinstance(displacement, (int, float)) or not math.isfinite(displacement) \
            or not 0 < displacement < 0.25 * RADIUS:
        raise ValueError(f"the displacement D must lie in (0, {0.25 * RADIUS}) (small deformations), got {displacement!r}")
    if cell not in ("tetra", "hexahedron"):
        raise ValueError(f"cell must be 'tetra' or 'hexahedron', got {cell!r}")

    upper = MeshHierarchy.build(half_ball(cell, UPPER_CENTER, RADIUS, k=upper_k, inner=UPPER_INNER), levels,
                                projector=SphereProjector(UPPER_CENTER, RADIUS, (BALL_SURFACE,)))
    lower = MeshHierarchy.build(lower_half_ball(cell, lower_k, lower_inner), levels,
                                projector=SphereProjector(LOWER_CENTER, RADIUS, (BALL_SURFACE,)))
    bodies = [Body(upper, Material(E, NU), [Dirichlet([BALL_TOP], (0.0, 0.0, -displacement))]),
              Body(lower, Material(E2, nu2), [Dirichlet([BALL_TOP], (0.0, 0.0, displacement))])]
    pair = ContactPair(0, 1, [BALL_SURFACE], [BALL_SURFACE], search=SEARCH,
                       region=lambda mid: np.hypot(mid[:, 0], mid[:, 1]) < ZONE)
    law = Coulomb(friction) if (friction > 0 or coulomb_at_zero) else Frictionless()
    return with_cycle(Problem(bodies, friction=law, pairs=pair), cycle, nu1, nu2_sweeps)


def effective_radius(R1: float, R2: float) -> float:
    """R* with 1/R* = 1/R1 + 1/R2."""
    return 1.0 / (1.0 / R1 + 1.0 / R2)


def effective_modulus(m1: Material, m2: Material) -> float:
    """E* with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    return 1.0 / ((1 - m1.nu ** 2) / m1.E + (1 - m2.nu ** 2) / m2.E)


def two_body_radius(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """Hertz's contact radius of two spheres: a = (3 P R* / (4 E*))^(1/3)."""
    return (3 * load * effective_radius(R1, R2) / (4 * effective_modulus(m1, m2))) ** (1.0 / 3.0)


def two_body_p0(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """Peak pressure p0 = 3 P / (2 pi a^2)."""
    return 3 * load / (2 * math.pi * two_body_radius(load, R1, R2, m1, m2) ** 2)


def relative_displacement(problem: Problem, result) -> np.ndarray:
    """w = T^{-1} u = u - N u: at the nonmortar nodes the displacement relative to the mortar side's
    (D^{-1} M u_m), the unknowns the nodal conditions are posed on."""
    return problem.relative_displacement(np.asarray(result.displacement))


def check_conditions(problem: Problem, result) -> dict:
    """checks.contact_conditions of `result`: it poses the conditions of the nonmortar nodes on the
    transformed problem (T^T A T, T^T f, the relative displacement w)."""
    from ..results.checks import contact_conditions

    return contact_conditions(problem, result)
