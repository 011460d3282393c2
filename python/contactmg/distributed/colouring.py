"""A colouring of a level's nodes (no two nodes of one cell share a colour) that does not depend on
the partition: the same colours on one rank and on any number of ranks, so that a coloured
Gauss-Seidel sweep visits the nodes in the same order however the mesh is distributed.

The rule is the greedy colouring in order of a priority: each node, taken from the highest priority
down, gets the smallest colour that none of its already coloured neighbours has. The priority is a
hash of the node's global id (ties, which a 64-bit hash makes rare, by the id): a fixed order
spread evenly over the mesh, so that the longest chain of decreasing priorities, which bounds the
rounds below, stays short (about log n / log log n). Computed distributedly by Jones-Plassmann:
a node whose neighbours of higher priority are all coloured takes its colour now, which is the
colour the greedy order gives it; ghost colours come from their owners between rounds."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .comm import get_comm, op

_MASK = np.uint64(0xFFFFFFFFFFFFFFFF)


def priority(gid: np.ndarray) -> np.ndarray:
    """splitmix64 of the global ids: a well-mixed 64-bit priority per node, the same on every rank."""
    with np.errstate(over="ignore"):
        z = np.asarray(gid, np.int64).astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def _neighbours(cells: np.ndarray, n: int):
    """Directed pairs (i, j), i != j, of nodes sharing a cell, without repeats, sorted by i, then j
    (scipy's CSR assembly merges the repeats: a fifth of the time np.unique took on them)."""
    k = cells.shape[1]
    a, b = np.nonzero(~np.eye(k, dtype=bool))
    i, j = cells[:, a].ravel(), cells[:, b].ravel()
    G = sp.csr_matrix((np.ones(len(i), np.int8), (i, j)), shape=(n, n))
    G.sum_duplicates()  # sorted, unique columns per row
    return np.repeat(np.arange(n, dtype=np.int64), np.diff(G.indptr)), G.indices.astype(np.int64)


class _Graph:
    """The local node graph (nodes sharing a cell, CSR by node) and its edges towards higher priority."""

    def __init__(self, cells: np.ndarray, gid: np.ndarray):
        self.n = len(gid)
        i, self.j = _neighbours(cells, self.n)  # sorted by i
        self.ptr = np.zeros(self.n + 1, np.int64)
        np.cumsum(np.bincount(i, minlength=self.n), out=self.ptr[1:])
        p = priority(gid)
        higher = (p[self.j] > p[i]) | ((p[self.j] == p[i]) & (gid[self.j] > gid[i]))
        self.hi_i, self.hi_j = i[higher], self.j[higher]


def greedy_colours(graph: _Graph, active: np.ndarray, colour: np.ndarray) -> int:
    """Jones-Plassmann steps over the local nodes, in place: every uncoloured node of `active` whose
    higher-priority neighbours are all coloured takes the smallest colour they do not have, repeated
    until no active node can take one. Returns how many nodes it coloured."""
    n = graph.n
    # the edges that can still hold a node back: from an uncoloured active node
    keep = active[graph.hi_i] & (colour[graph.hi_i] < 0)
    hi_i, hi_j = graph.hi_i[keep], graph.hi_j[keep]
    done = 0
    while True:
        blocked = colour[hi_j] < 0
        hi_i, hi_j = hi_i[blocked], hi_j[blocked]  # a coloured neighbour never blocks again
        waiting = np.zeros(n, bool)
        waiting[hi_i] = True
        ready = np.flatnonzero(active & (colour < 0) & ~waiting)
        if not len(ready):
            return done
        # the colours of the neighbours of each ready node (-1: not coloured yet)
        count = graph.ptr[ready + 1] - graph.ptr[ready]
        row = np.repeat(np.arange(len(ready)), count)
        at = np.repeat(graph.ptr[ready], count) + np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count,
                                                                                           count)
        c = colour[graph.j[at]]
        width = int(colour.max(initial=-1)) + 2
        used = np.zeros((len(ready), width), bool)
        used[row[c >= 0], c[c >= 0]] = True
        colour[ready] = np.argmin(used, axis=1)  # the first colour not used
        done += len(ready)


def colour_level(level, comm=None) -> np.ndarray:
    """Colours (0, 1, ...) of a LocalLevel's local nodes by the rule of the module's doc: owned nodes
    coloured here, ghost nodes given their owners' colours. Collective; the same colours for the
    same global ids on every number of ranks."""
    comm = get_comm(comm)
    n = len(level.gid)
    colour = np.full(n, -1, np.int64)
    owned = level.owner == comm.rank
    values = np.zeros(n)
    graph = _Graph(level.cells, level.gid)
    while True:
        greedy_colours(graph, owned, colour)
        left = comm.allreduce(int(np.count_nonzero(colour[owned] < 0)), op=op(comm, "SUM"))
        if level.halo is not None and comm.size > 1:
            values[:] = colour
            level.halo.update(values)
            colour[~owned] = values[~owned].astype(np.int64)
        if left == 0:
            return colour
