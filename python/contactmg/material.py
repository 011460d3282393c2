"""Linear elastic material (plane strain in 2D)."""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    E: float
    nu: float

    def __post_init__(self):
        for name in ("E", "nu"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise TypeError(f"{name} must be a number, got {type(v).__name__}")
        if not (math.isfinite(self.E) and self.E > 0):
            raise ValueError(f"Young's modulus E must be positive and finite, got {self.E}")
        if not (-1.0 < self.nu < 0.5):
            raise ValueError(f"Poisson ratio nu must lie in (-1, 0.5), got {self.nu}")

    @property
    def lam(self) -> float:
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))

    @property
    def mu(self) -> float:
        return self.E / (2 * (1 + self.nu))

    @property
    def plane_strain_modulus(self) -> float:
        """E* = E / (1 - nu^2), the modulus of Hertz's plane-strain formulas."""
        return self.E / (1 - self.nu ** 2)
