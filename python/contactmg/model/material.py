"""Linear elastic material (plane strain in 2D)."""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Material:
    E: float
    nu: float

    def __post_init__(self):
        for name in ("E", "nu"):
            v = getattr(self, name)
            # any real number (numpy scalars and 0-d arrays too), stored as a float
            if isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind in "iuf":
                v = v[()]
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise TypeError(f"{name} must be a number, got {type(v).__name__}")
            object.__setattr__(self, name, float(v))
        if not (math.isfinite(self.E) and self.E > 0):
            raise ValueError(f"Young's modulus E must be positive and finite, got {self.E}")
        if not (-1.0 < self.nu < 0.5):
            raise ValueError(f"Poisson ratio nu must lie in (-1, 0.5), got {self.nu}")

    @property
    def lam(self) -> float:
        """The first Lame parameter."""
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))

    @property
    def mu(self) -> float:
        """The shear modulus (second Lame parameter)."""
        return self.E / (2 * (1 + self.nu))

    @property
    def plane_strain_modulus(self) -> float:
        """E* = E / (1 - nu^2), the modulus of Hertz's plane-strain formulas."""
        return self.E / (1 - self.nu ** 2)


def cell_moduli(mesh, material) -> tuple:
    """Young's modulus E (ncells,) and Poisson ratio nu (ncells,) of every cell of `mesh` (a
    Mesh): a Material holds one pair for every cell."""
    if not isinstance(material, Material):
        raise TypeError(f"material must be a Material, got {type(material).__name__}")
    m = mesh.num_cells
    return np.full(m, material.E), np.full(m, material.nu)
