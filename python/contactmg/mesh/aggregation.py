"""Coarse spaces from one fine mesh: nonnegative aggregation.

The monotone multigrid needs coarse spaces whose prolongation weights are nonnegative: the
truncation of coarse basis functions at fine nodes on the obstacle, and the monotone restriction of
the obstacle (a coarse bound from the fine slack under each coarse function), keep their meaning only
then. Smoothed aggregation with the elasticity matrix gives negative weights; this module builds
the coarse spaces by

1. **pairwise aggregation**: `rounds` greedy matchings of the node graph (each node joined with one
   unmatched neighbour, the one with the fewest neighbours), so that an aggregate holds up to
   2^rounds nodes (rounds = the dimension: the coarsening of uniform refinement, 4 in 2D, 8 in 3D);
2. **smoothing by the graph**: P = (I - omega D^-1 L) P0 with L = D - W the graph Laplacian of the
   node graph (W its 0/1 adjacency, D the degrees). For omega <= 1 the operator is a weighted
   average, (1 - omega) I + omega D^-1 W, with nonnegative weights, so P stays nonnegative and its
   rows still sum to one: a partition of unity, like the hat functions of geometric coarsening,
   whose coarse functions are smoother than the plain aggregates' 0/1 (which took 166-180 F-cycles
   on the Hertz benchmark against 19 smoothed, 0025-aggregation-coarse-spaces).

Each coarse level is aggregated again from the coarse graph (P0^T W P0's pattern) until it has at
most `coarsest` nodes.
"""
from __future__ import annotations

from typing import List, Tuple

import numpy as np

from .mesh import Mesh


def node_graph(cells: np.ndarray, n: int):
    """The node adjacency (n x n, 0/1, no diagonal) of a mesh's cells: nodes that share a cell."""
    import scipy.sparse as sp

    k = cells.shape[1]
    rows = np.repeat(cells, k, axis=1).ravel()
    cols = np.tile(cells, (1, k)).ravel()
    keep = rows != cols
    G = sp.csr_matrix((np.ones(int(keep.sum())), (rows[keep], cols[keep])), shape=(n, n))
    G.data[:] = 1.0
    return G


def pairwise_matching(G) -> Tuple[np.ndarray, int]:
    """(aggregate of each node, count): a greedy matching of the graph G, nodes with fewer
    neighbours first (boundary nodes), each paired with its unmatched neighbour of fewest
    neighbours; a node left without one is an aggregate of its own."""
    n = G.shape[0]
    ptr, idx = G.indptr, G.indices
    deg = np.diff(ptr)
    agg = np.full(n, -1, np.int64)
    count = 0
    for i in np.argsort(deg, kind="stable"):
        if agg[i] >= 0:
            continue
        nb = idx[ptr[i]:ptr[i + 1]]
        free = nb[agg[nb] < 0]
        agg[i] = count
        if len(free):
            agg[free[np.argmin(deg[free])]] = count
        count += 1
    return agg, count


def _pattern(M):
    M = M.tocsr()
    M.data[:] = 1.0
    M.setdiag(0)
    M.eliminate_zeros()
    return M


# Coarse levels stop at this many nodes: a direct solve of them costs about a cycle of the finest level.
COARSEST_NODES = 200


def coarsest_nodes(num_nodes: int, dim: int, coarsest=None) -> int:
    """The size coarse levels made from a mesh of `num_nodes` nodes go down to: `coarsest` where
    given, else COARSEST_NODES, and an eighth of the mesh for a mesh of at most that many nodes (a
    small mesh still gets coarse levels: its sweeps alone took 55 cycles on 338 dofs)."""
    if coarsest is not None:
        return coarsest
    return COARSEST_NODES if num_nodes > COARSEST_NODES else max(dim + 2, num_nodes // 8)


def aggregation_prolongations(mesh: Mesh, coarsest=None, rounds: int = 0, omega: float = 1.0) -> List:
    """The prolongations (scipy CSR, fine x coarse) from the coarsest level to `mesh`, coarsest
    first, of nonnegative smoothed aggregation (module docstring), down to at most `coarsest` nodes
    (None: coarsest_nodes). `rounds`: matchings per level (0: the mesh's dimension);
    `omega` in [0, 1]: the smoothing (0: plain aggregation)."""
    import scipy.sparse as sp

    coarsest = coarsest_nodes(mesh.num_points, mesh.dim, coarsest)

    if not (isinstance(coarsest, (int, np.integer)) and coarsest >= 1):
        raise ValueError(f"coarsest must be a positive number of nodes, got {coarsest!r}")
    if not (0.0 <= omega <= 1.0):
        raise ValueError(f"omega must lie in [0, 1] (beyond 1 the weights turn negative), got {omega!r}")
    rounds = rounds or mesh.dim
    G = node_graph(mesh.cells, mesh.num_points)
    out = []
    while G.shape[0] > coarsest:
        n = G.shape[0]
        P = sp.identity(n, format="csr")
        coarse_graph = G
        for _ in range(rounds):
            agg, m = pairwise_matching(coarse_graph)
            Q = sp.csr_matrix((np.ones(coarse_graph.shape[0]), (np.arange(coarse_graph.shape[0]), agg)),
                              shape=(coarse_graph.shape[0], m))
            P = (P @ Q).tocsr()
            coarse_graph = _pattern(Q.T @ coarse_graph @ Q)
        if P.shape[1] >= n:  # nothing left to join (isolated nodes): stop coarsening
            break
        if omega > 0:
            degree = np.asarray(G.sum(axis=1)).ravel()
            S = (1.0 - omega) * sp.identity(n) + omega * (sp.diags(1.0 / np.maximum(degree, 1.0)) @ G)
            P = (S @ P).tocsr()
        P.eliminate_zeros()
        P.sort_indices()
        out.append(P)
        G = coarse_graph
    return out[::-1]
