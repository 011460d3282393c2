"""The Hertz benchmark of the seed paper (DESIGN section 6) and Hertz's plane-strain formulas."""
from __future__ import annotations

import math

import numpy as np

from .friction import Coulomb, Frictionless
from .generators import HERTZ_ARC, HERTZ_TOP, hertz_half_disk, hertz_projector
from .hierarchy import MeshHierarchy
from .material import Material
from .obstacle import PlaneObstacle
from .problem import ContactProblem, Dirichlet

E, NU = 2000.0, 0.28
CENTER, RADIUS = (0.0, 0.4), 0.4
TOP_DISPLACEMENT = -0.005
PAPER_FRICTIONS = (0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0)


def hertz_problem(cell: str = "triangle", levels: int = 6, friction: float = 0.4, coulomb_at_zero: bool = False,
                  cycle: str = "F", nu1: int = 3, nu2: int = 3, material: Material = None) -> ContactProblem:
    """Lower half disk (centre (0, 0.4), radius 0.4) pushed by u = (0, -0.005) on its top edge onto
    the rigid plane y = 0, with Coulomb friction F (frictionless for F = 0 unless
    coulomb_at_zero, which the fixed-point method needs)."""
    if isinstance(friction, bool) or not isinstance(friction, (int, float)) or not math.isfinite(friction) or friction < 0:
        raise ValueError(f"the friction coefficient must be a finite number >= 0, got {friction!r}")
    mesh = hertz_half_disk(cell)
    hierarchy = MeshHierarchy.build(mesh, levels, projector=hertz_projector(CENTER, RADIUS))
    law = Coulomb(friction) if (friction > 0 or coulomb_at_zero) else Frictionless()
    problem = ContactProblem(hierarchy, material or Material(E, NU), [Dirichlet([HERTZ_TOP], (0.0, TOP_DISPLACEMENT))],
                             contact_tags=[HERTZ_ARC], obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=law,
                             cycle=cycle, nu1=nu1, nu2=nu2)
    problem.benchmark = "hertz"  # zones centred on x = 0: results have contact_halfwidth, stick_halfwidth
    return problem


def halfwidth(load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> float:
    """Contact half-width a = sqrt(4 P R / (pi E*)) for the load P per unit thickness."""
    return math.sqrt(4 * load * radius / (math.pi * material.plane_strain_modulus))


def peak_pressure(load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> float:
    """p0 = 2 P / (pi a)."""
    return 2 * load / (math.pi * halfwidth(load, radius, material))


def pressure(x: np.ndarray, load: float, radius: float = RADIUS, material: Material = Material(E, NU)) -> np.ndarray:
    """Hertz's pressure profile p0 sqrt(1 - (x/a)^2) inside the contact zone, 0 outside."""
    a = halfwidth(load, radius, material)
    return peak_pressure(load, radius, material) * np.sqrt(np.clip(1 - (np.asarray(x) / a) ** 2, 0, None))
