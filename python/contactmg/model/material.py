"""Linear elastic material (plane strain in 2D), one per body or one per region of a body."""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Dict, Optional, Union

import numpy as np


@dataclass(frozen=True)
class Material:
    """Isotropic linear elasticity: Young's modulus E, Poisson ratio nu and, for gravity loads, the
    density (mass per volume), all in the model's units."""

    E: float
    nu: float
    density: Optional[float] = None

    def __post_init__(self):
        if self.density is not None:
            d = self.density
            if isinstance(d, (bool, np.bool_)) or not isinstance(d, numbers.Real) or not (math.isfinite(d) and d >= 0):
                raise ValueError(f"density must be a non-negative number, got {d!r}")
            object.__setattr__(self, "density", float(d))
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


# One material for a body, or one per region: {cell tag: Material}.
Materials = Union[Material, Dict[int, Material]]


def check_materials(mesh, material: Materials) -> None:
    """Every region (cell tag) of `mesh` has a material, and every material a region."""
    if isinstance(material, Material):
        return
    if not isinstance(material, dict) or not material:
        raise TypeError(f"material must be a Material or a non-empty dict {{region tag: Material}}, got "
                        f"{type(material).__name__}")
    for tag, m in material.items():
        if isinstance(tag, (bool, np.bool_)) or not isinstance(tag, (int, np.integer)):
            raise TypeError(f"the regions of a material dict are integer cell tags, got {tag!r}")
        if not isinstance(m, Material):
            raise TypeError(f"the material of region {tag} must be a Material, got {type(m).__name__}")
    present = set(np.unique(mesh.cell_tags).tolist())
    missing = sorted(present - set(material))
    if missing:
        raise ValueError(f"cells of region(s) {missing} have no material (materials are given for regions "
                         f"{sorted(material)}; the mesh's regions are {sorted(present)})")
    unused = sorted(set(material) - present)
    if unused:
        raise ValueError(f"no cell carries the region tag(s) {unused} of the materials (the mesh's regions are "
                         f"{sorted(present)})")


def cell_materials(mesh, material: Materials) -> list:
    """(Material, cell mask) per region of `mesh` (one for a single Material)."""
    check_materials(mesh, material)
    if isinstance(material, Material):
        return [(material, np.ones(mesh.num_cells, bool))]
    return [(m, mesh.cell_tags == tag) for tag, m in sorted(material.items())]


def cell_moduli(mesh, material: Materials) -> tuple:
    """Young's modulus E (ncells,) and Poisson ratio nu (ncells,) of every cell of `mesh` (a
    Mesh): a Material holds one pair for every cell, a dict {region tag: Material} one per region."""
    if not isinstance(material, (Material, dict)):
        raise TypeError(f"material must be a Material or a dict {{region tag: Material}}, got {type(material).__name__}")
    m = mesh.num_cells
    E, nu = np.empty(m), np.empty(m)
    for mat, sel in cell_materials(mesh, material):
        E[sel], nu[sel] = mat.E, mat.nu
    return E, nu


def core_moduli(mesh, material: Materials) -> tuple:
    """E and nu as the core's assembly takes them: numbers for one material (the same bits as
    always), arrays per cell for several."""
    if isinstance(material, Material):
        return material.E, material.nu
    return cell_moduli(mesh, material)
