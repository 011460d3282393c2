"""Prolongation between the levels of a DistributedHierarchy: each rank computes the rows of its owned
fine nodes from the coarse values it holds (the parents of an owned node are nodes of an owned
cell, so they are local, owned or ghost), then the fine ghosts take their owners' values. Every row
is summed in the serial transfer's order: the result is the serial prolongation's, bit for bit."""
from __future__ import annotations

import numpy as np


def prolong(hierarchy, level: int, coarse: np.ndarray) -> np.ndarray:
    """The fine values on level `level` (1 .. levels - 1; rows: that level's local nodes) of the
    coarse values `coarse` (rows: level - 1's local nodes, any trailing shape; ghost rows are
    refreshed from their owners first). Collective."""
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or not 1 <= level < len(hierarchy.levels):
        raise ValueError(f"level must lie in 1..{len(hierarchy.levels) - 1}, got {level!r}")
    below, fine = hierarchy.levels[level - 1], hierarchy.levels[level]
    coarse = np.array(coarse, dtype=float, order="C")  # a copy: its ghost rows are overwritten
    if coarse.shape[0] != len(below.gid):
        raise ValueError(f"coarse values need one row per local node of level {level - 1} ({len(below.gid)}), "
                         f"got {coarse.shape[0]}")
    below.halo.update(coarse)
    t = fine.transfer
    out = np.zeros((len(fine.gid),) + coarse.shape[1:])
    count = np.diff(t.ptr)
    if len(t.parent):
        terms = t.weight.reshape((-1,) + (1,) * (coarse.ndim - 1)) * coarse[t.parent]
        # left to right within each row, as the serial transfer's matrix-vector product adds them
        acc = terms[t.ptr[:-1][count > 0]].copy()
        width = int(count.max())
        for k in range(1, width):
            more = count > k
            acc[more[count > 0]] += terms[t.ptr[:-1][more] + k]
        out[t.rows[count > 0]] = acc
    fine.halo.update(out)
    return out
