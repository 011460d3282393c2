"""Local friction laws on the contact boundary."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Union

import numpy as np

ArrayLike = Union[float, np.ndarray]


def _per_node(value: ArrayLike, n: int, name: str) -> np.ndarray:
    if isinstance(value, bool):
        raise TypeError(f"{name} must be a number or an array, got bool")
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have one value per contact node ({n}), got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name} must be finite and >= 0")
    return a


@dataclass(frozen=True)
class Frictionless:
    law = "frictionless"

    def coefficients(self, n: int, measure: np.ndarray) -> np.ndarray:
        return np.zeros(n)


@dataclass(frozen=True)
class Tresca:
    """Given friction bound, as a stress (force per unit boundary measure), scalar or per node;
    the nodal bound is this stress times the lumped boundary measure of the node."""

    bound: ArrayLike
    law = "tresca"

    def coefficients(self, n: int, measure: np.ndarray) -> np.ndarray:
        return _per_node(self.bound, n, "Tresca bound") * measure


@dataclass(frozen=True)
class Coulomb:
    """Coulomb friction |s_T| <= F |s_n| with coefficient F, scalar or per node."""

    coefficient: ArrayLike
    law = "coulomb"

    def coefficients(self, n: int, measure: np.ndarray) -> np.ndarray:
        return _per_node(self.coefficient, n, "friction coefficient")
