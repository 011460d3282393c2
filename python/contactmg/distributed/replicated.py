"""Coarse levels held whole by every rank (agglomeration onto every rank): below a size a level
costs more in exchanges than in work. A rank's share of a small level is a few hundred rows, and each
colour of each sweep still waits for a halo exchange: on two ranks the Hertz half disk at level 7
made 850 exchanges a cycle, most of them on the coarse levels. A level of at most REPLICATE_NODES
global nodes, and every level below it, is therefore held by every rank in full and swept there
without an exchange; the level above it restricts onto its owned rows as before, and one allgather
gives every rank the whole vector (residual, bounds), the prolongation reads the whole correction.

Why the bits stay those of one rank: on one rank every level is whole already. A replicated level
is numbered as one rank numbers it (the coarsest in global id, the others in (colour, global id)),
its Galerkin rows at the boundary are the owners' rows (the same bits on any partition) gathered
into that numbering, and below the boundary every rank runs the one-rank code on the same data."""
from __future__ import annotations

from types import SimpleNamespace
from typing import Optional

import numpy as np

from .colouring import _neighbours
from .comm import SerialComm, op
from .hierarchy import LocalTransfer

# The default size below which a coarse level is held whole by every rank (with every level below
# it): at this size a sweep of the whole level takes about as long as a few halo exchanges.
REPLICATE_NODES = 8192


# ... and while the whole levels together hold at most this share of the matrix blocks a rank holds
# on the fine level (a level's blocks: its pairs of nodes sharing a cell, which is the pattern of its
# Galerkin rows on uniform hierarchies). Every rank holds those levels in full: on the 3D sphere, two
# ranks holding both coarse levels (6,365 nodes, with rows denser than the fine level's) held 1.27
# times the serial bytes per dof.
WHOLE_SHARE = 1 / 8


def _owned_blocks(level) -> int:
    """The matrix blocks of the level's owned rows: the pairs of nodes that share a cell (an owned
    node has all its cells locally), each node with itself."""
    i, _ = _neighbours(level.cells, len(level.gid))
    owned = level.owner == level.rank
    return int(np.count_nonzero(owned[i]) + np.count_nonzero(owned))


def replicated_count(comm, hierarchy, whole_below: Optional[int] = None) -> int:
    """How many of the coarse levels (levels 0, 1, ...; never the fine level) every rank holds whole:
    from the coarsest up, those of at most whole_below global nodes; by default (None) those of at
    most REPLICATE_NODES while all of them together hold at most WHOLE_SHARE of the fine matrix
    blocks of the rank that holds the fewest. None on one rank (every level is whole there).
    Collective."""
    if comm.size == 1:
        return 0
    levels = hierarchy.levels[:-1]
    budget = np.inf
    cost = [0] * len(levels)
    if whole_below is None:
        whole_below = REPLICATE_NODES
        budget = WHOLE_SHARE * comm.allreduce(_owned_blocks(hierarchy.levels[-1]), op=op(comm, "MIN"))
        for l, lev in enumerate(levels):
            if lev.num_global_nodes > whole_below:
                break
            cost[l] = comm.allreduce(_owned_blocks(lev), op=op(comm, "SUM"))
    k, total = 0, 0
    while k < len(levels) and levels[k].num_global_nodes <= whole_below and total + cost[k] <= budget:
        total += cost[k]
        k += 1
    return k


class Whole:
    """One level held whole: `level` (the fields the cycle reads from a LocalLevel: gid, owner, rank,
    halo, colour, transfer, num_global_nodes) in the one-rank numbering, and the maps between it and
    the distributed level's local nodes."""

    def __init__(self, comm, dist, below: Optional["Whole"], coarsest: bool):
        self.comm, self.dist = comm, dist
        n = dist.num_global_nodes
        own = dist.owner == dist.rank
        parts = comm.allgather((dist.gid[own], dist.colour[own] if dist.colour is not None else None))
        colour = np.zeros(n, np.int64)
        for g, c in parts:
            if c is not None:
                colour[g] = c
        # one rank's numbering (hierarchy._order_by_colour): the coarsest in global id, the others in
        # (colour, global id)
        gid = np.arange(n, dtype=np.int64) if coarsest else np.lexsort((np.arange(n), colour)).astype(np.int64)
        self.index_of_gid = np.empty(n, np.int64)
        self.index_of_gid[gid] = np.arange(n)
        self.local = self.index_of_gid[dist.gid]  # the whole level's index of each local node
        transfer = None
        if below is not None:  # every fine row, gathered from the owners
            t = dist.transfer
            rows = comm.allgather((dist.gid[t.rows], np.diff(t.ptr), t.parent_gid, t.weight))
            fine_gid = np.concatenate([r[0] for r in rows])
            counts = np.concatenate([r[1] for r in rows])
            parent_gid = np.concatenate([r[2] for r in rows])
            ptr = np.zeros(len(fine_gid) + 1, np.int64)
            np.cumsum(counts, out=ptr[1:])
            transfer = LocalTransfer(self.index_of_gid[fine_gid], ptr, below.index_of_gid[parent_gid], parent_gid,
                                     np.concatenate([r[3] for r in rows]))
        self.level = SimpleNamespace(gid=gid, owner=np.zeros(n, np.int64), rank=0, halo=None,
                                     colour=None if coarsest else colour[gid], transfer=transfer,
                                     num_global_nodes=n)
        self.serial = SerialComm()

    def gather(self, owned_values: np.ndarray) -> np.ndarray:
        """The whole level's rows (one-rank numbering) from every rank's owned rows of the
        distributed level (rows = its local nodes). Collective."""
        dist = self.dist
        own = np.flatnonzero(dist.owner == dist.rank)
        parts = self.comm.allgather((self.local[own], owned_values[own]))
        out = np.empty((dist.num_global_nodes,) + owned_values.shape[1:])
        for i, v in parts:
            out[i] = v
        return out

    def gather_rows(self, rows, d: int):
        """(indptr, indices, blocks) of the whole level's matrix in its numbering, from every rank's
        owned rows of the distributed level (a CoarseRows in the distributed numbering). Collective."""
        indptr, indices, blocks = rows.blocks()
        dist = self.dist
        counts = np.diff(indptr)
        own = np.flatnonzero((dist.owner == dist.rank) & (counts > 0))
        row = np.repeat(np.arange(len(counts)), counts)
        keep = np.isin(row, own)
        parts = self.comm.allgather((self.local[row[keep]], self.local[indices[keep]], blocks[keep]))
        r = np.concatenate([p[0] for p in parts])
        c = np.concatenate([p[1] for p in parts])
        b = np.concatenate([p[2] for p in parts])
        order = np.lexsort((c, r))
        n = dist.num_global_nodes
        ptr = np.zeros(n + 1, np.int64)
        np.cumsum(np.bincount(r, minlength=n), out=ptr[1:])
        return ptr, c[order].astype(np.int64), np.ascontiguousarray(b[order])
