"""Two elastic half-disks pressed together (the two-body Hertz problem) and `contactmg cylinders`.

The upper body is the Hertz half-disk of the seed paper (centre (0, 0.4), radius 0.4, its arc
below, the nonmortar side); the lower one is its mirror image below y = 0 (centre (0, -0.4)),
meshed differently (5 k instead of 4 k arc segments on ring k) so the interface does not match,
the mortar side. Their flat faces are moved towards each other by 0.005 each."""
from __future__ import annotations

import math

import numpy as np

from ..model.friction import Coulomb, Frictionless
from ..mesh.generators import HERTZ_ARC, HERTZ_TOP, hertz_projector, polar_half_disk
from ..mesh.hierarchy import MeshHierarchy
from ..model.material import Material
from ..mesh.mesh import Mesh
from ..model.problem import Body, ContactPair, Dirichlet, Problem
from ..solve.options import with_cycle

E, NU, RADIUS = 2000.0, 0.28, 0.4
FACE_DISPLACEMENT = 0.005
# the possible contact zone: the nonmortar arc within |x| < ZONE (the Hertz half-width is ~0.03)
ZONE = 0.5 * RADIUS
SEARCH = RADIUS


def lower_half_disk(segments: int = 5) -> Mesh:
    """The mirror image of the polar Hertz half-disk below y = 0: centre (0, -0.4), arc on top."""
    m = polar_half_disk((0.0, 0.4), RADIUS, rings=3, segments=segments)
    pts = m.points * [1.0, -1.0]
    cy = -0.4

    def tagger(mid):
        return np.where(np.abs(mid[:, 1] - cy) < 1e-12 * RADIUS, HERTZ_TOP, HERTZ_ARC)

    return Mesh.from_cells(pts, m.cells[:, ::-1].copy(), "triangle", tagger)


def cylinders_problem(levels: int = 5, friction: float = 0.4, E2: float = E, nu2: float = NU, coulomb_at_zero=False,
                      cycle: str = "F", smooth: int = 3, upper_segments: int = 4, lower_segments: int = 5,
                      tied_correction: bool = True) -> Problem:
    """Two elastic half cylinders pressed together (the two-body Hertz problem) with `levels` uniform levels and Coulomb friction `friction`."""
    if isinstance(friction, bool) or not isinstance(friction, (int, float)) or not math.isfinite(friction) or friction < 0:
        raise ValueError(f"the friction coefficient must be a finite number >= 0, got {friction!r}")

    upper = MeshHierarchy.build(polar_half_disk((0.0, 0.4), RADIUS, rings=3, segments=upper_segments), levels,
                                projector=hertz_projector((0.0, 0.4), RADIUS))
    lower = MeshHierarchy.build(lower_half_disk(lower_segments), levels, projector=hertz_projector((0.0, -0.4), RADIUS))
    bodies = [Body(upper, Material(E, NU), [Dirichlet([HERTZ_TOP], (0.0, -FACE_DISPLACEMENT))]),
              Body(lower, Material(E2, nu2), [Dirichlet([HERTZ_TOP], (0.0, FACE_DISPLACEMENT))])]
    pair = ContactPair(0, 1, [HERTZ_ARC], [HERTZ_ARC], search=SEARCH, region=lambda mid: np.abs(mid[:, 0]) < ZONE)
    law = Coulomb(friction) if (friction > 0 or coulomb_at_zero) else Frictionless()
    p = with_cycle(Problem(bodies, friction=law, pairs=pair, tied_correction=tied_correction), cycle, smooth, smooth)
    p.benchmark = "hertz"  # zones centred on x = 0
    return p


def effective_modulus(m1: Material, m2: Material) -> float:
    """E* with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (plane strain)."""
    return 1.0 / ((1 - m1.nu ** 2) / m1.E + (1 - m2.nu ** 2) / m2.E)


def two_body_halfwidth(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """a = sqrt(4 P R* / (pi E*)), 1/R* = 1/R1 + 1/R2."""
    Rs = 1.0 / (1.0 / R1 + 1.0 / R2)
    return math.sqrt(4 * load * Rs / (math.pi * effective_modulus(m1, m2)))


def two_body_peak_pressure(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """p0 = 2 P / (pi a)."""
    return 2 * load / (math.pi * two_body_halfwidth(load, R1, R2, m1, m2))
