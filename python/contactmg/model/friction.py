"""Local friction laws on the contact boundary.

A per-node value (friction coefficient, Tresca bound) is a scalar, or an array with `nodes`: the
mesh node ids (finest mesh) it belongs to, covering every contact node (more nodes are fine).
Without `nodes` an array follows the order of the contact nodes, ascending node id
(problem.contact.nodes, result.contact_nodes)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Union

import numpy as np

from ..model.nodal import node_ids, rows_for

ArrayLike = Union[float, np.ndarray]


def _per_node(value: ArrayLike, ids: Optional[Sequence[int]], contact_nodes: np.ndarray, name: str) -> np.ndarray:
    if isinstance(value, bool):
        raise TypeError(f"{name} must be a number or an array, got bool")
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number or an array of numbers, got {value!r}") from None
    n = len(contact_nodes)
    if a.ndim == 0:
        a = np.full(n, float(a))
    elif ids is not None:
        given = node_ids(ids, f"{name} nodes")
        if a.shape != given.shape:
            raise ValueError(f"{name} has shape {a.shape} but {len(given)} node ids")
        a = a[rows_for(given, contact_nodes, name)]
    if a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have one value per contact node ({n}), got shape {a.shape}; "
                         "or give the mesh node ids of the values as nodes=")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name} must be finite and >= 0")
    return a


@dataclass(frozen=True)
class Frictionless:
    law = "frictionless"

    def coefficients(self, contact_nodes: np.ndarray, measure: np.ndarray) -> np.ndarray:
        """The law's coefficient per contact node (the core's `coefficients` argument)."""
        return np.zeros(len(contact_nodes))


@dataclass(frozen=True)
class Tresca:
    """Given friction bound, as a stress (force per unit boundary measure), scalar or per node
    (with `nodes`, the mesh node ids of the values); the nodal bound is this stress times the
    lumped boundary measure of the node."""

    bound: ArrayLike
    nodes: Optional[Sequence[int]] = None
    law = "tresca"

    def coefficients(self, contact_nodes: np.ndarray, measure: np.ndarray) -> np.ndarray:
        """The law's coefficient per contact node (the core's `coefficients` argument)."""
        return _per_node(self.bound, self.nodes, contact_nodes, "Tresca bound") * measure


@dataclass(frozen=True)
class Coulomb:
    """Coulomb friction |s_T| <= F |s_n| with coefficient F, scalar or per node (with `nodes`, the
    mesh node ids of the values)."""

    coefficient: ArrayLike
    nodes: Optional[Sequence[int]] = None
    law = "coulomb"

    def coefficients(self, contact_nodes: np.ndarray, measure: np.ndarray) -> np.ndarray:
        """The law's coefficient per contact node (the core's `coefficients` argument)."""
        return _per_node(self.coefficient, self.nodes, contact_nodes, "friction coefficient")
