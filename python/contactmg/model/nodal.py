"""Per-node data given by mesh node ids: friction coefficients, Tresca bounds and nodal obstacles
can be given for the nodes a user knows (ids of the finest mesh) instead of in the internal order
of the contact nodes (ascending node id), which is fixed only once the problem is built."""
from __future__ import annotations

from typing import Optional

import numpy as np


def node_ids(nodes, name: str) -> np.ndarray:
    """`nodes` as a 1D array of distinct non-negative integer node ids."""
    ids = np.asarray(nodes)
    if ids.ndim != 1 or (ids.size and not np.issubdtype(ids.dtype, np.integer)):
        raise ValueError(f"{name} must be a 1D sequence of integer node ids, got {ids.dtype} of shape {ids.shape}")
    ids = ids.astype(np.int64)
    if np.any(ids < 0):
        raise ValueError(f"{name} holds a negative node id ({int(ids.min())})")
    if len(np.unique(ids)) != len(ids):
        raise ValueError(f"{name} repeats a node id")
    return ids


def rows_for(given: Optional[np.ndarray], wanted: np.ndarray, name: str) -> Optional[np.ndarray]:
    """Row of each `wanted` node id in the ids `given` (None when no ids are given: the arrays are
    then in the order of `wanted`). Raises naming the first node the given ids do not cover."""
    if given is None:
        return None
    order = np.argsort(given, kind="stable")
    pos = np.searchsorted(given[order], wanted)
    pos = np.minimum(pos, max(len(given) - 1, 0))
    found = (len(given) > 0) & (given[order][pos] == wanted) if len(given) else np.zeros(len(wanted), bool)
    if not np.all(found):
        missing = wanted[~found]
        raise ValueError(f"{name} gives no value for contact node {int(missing[0])} ({len(missing)} contact nodes "
                         "missing); the contact nodes are result.contact_nodes / problem.contact.nodes")
    return order[pos]
