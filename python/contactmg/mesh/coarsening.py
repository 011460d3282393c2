"""Coarse spaces from one fine mesh by geometric coarsening: coarse node sets and the nonnegative
interpolation between non-nested levels.

Each coarse level is a subset of the level above's nodes, a maximal independent set of its node
graph (no two chosen nodes neighbours, every other node next to a chosen one: about a quarter of the
nodes in 2D, an eighth in 3D, the ratio of uniform refinement). Boundary nodes are chosen first,
and among them the nodes on edges and corners of the boundary (where its normal turns), so the
coarse levels keep the body's outline. The coarse level's simplices are the Delaunay
triangulation of its nodes; a fine node is interpolated from the corners of the coarse simplex
that contains it by its barycentric coordinates, and a node outside every coarse simplex (on a
convex curved boundary between coarse boundary nodes) from the coarse simplex nearest to it, its
coordinates clipped to that simplex. Barycentric coordinates are nonnegative and sum to one, so
the prolongation keeps the two properties the monotone multigrid needs (truncation and the
monotone restriction of the obstacle keep their meaning, 0025-aggregation-coarse-spaces), and it
has at most d + 1 weights a row, as nodal interpolation between nested meshes has: the Galerkin
matrices of the coarse levels stay as sparse as a mesh's, which smoothed aggregation's are not.

The coarse simplices serve the interpolation only: the coarse matrices are the Galerkin products
of the fine matrix, so a poorly shaped Delaunay simplex costs accuracy of the coarse space, not
correctness.
"""
from __future__ import annotations

from typing import List

import numpy as np

from .aggregation import coarsest_nodes, node_graph
from .mesh import Mesh, boundary_facets, facet_area_vectors


# A boundary node whose facets' normals turn by more than about this angle lies on an edge or a corner.
FEATURE_ANGLE_DEG = 30.0


def node_classes(mesh: Mesh) -> np.ndarray:
    """Per node 0 (interior), 1 (boundary), and in 3D 2 (on an edge of the boundary) and 3 (at a
    corner), in 2D 2 (at a corner): the number of directions its boundary facets' unit normals
    span, each turning by more than about FEATURE_ANGLE_DEG (the eigenvalues of the mean of n n^T)."""
    n, d = mesh.num_points, mesh.dim
    facets = boundary_facets(mesh.cells, mesh.cell_type)
    cls = np.zeros(n, np.int64)
    if len(facets) == 0:
        return cls
    nf = facet_area_vectors(mesh.points, facets)
    nf = nf / np.maximum(np.linalg.norm(nf, axis=1, keepdims=True), 1e-300)
    k = facets.shape[1]
    node = facets.ravel()
    normal = np.repeat(nf, k, axis=0)
    M = np.zeros((n, d, d))
    np.add.at(M, node, np.einsum("ki,kj->kij", normal, normal))
    count = np.bincount(node, minlength=n)
    on = count > 0
    lam = np.linalg.eigvalsh(M[on] / count[on, None, None])
    # two directions at angle a give a second eigenvalue of about sin^2(a) / 4 for an even mix
    spans = (lam > np.sin(np.deg2rad(FEATURE_ANGLE_DEG)) ** 2 / 4).sum(axis=1)
    cls[on] = np.maximum(spans, 1)
    return cls


def independent_set(G, priority: np.ndarray) -> np.ndarray:
    """A maximal independent set of the graph G (CSR, no diagonal) as a boolean mask: every node
    whose priority is the largest among its undecided neighbours joins, its neighbours leave; in
    rounds until every node is decided (Luby's rounds with fixed priorities: the set is the one the
    greedy pass in decreasing priority would choose). Priorities must be distinct."""
    n = G.shape[0]
    ptr, idx = G.indptr, G.indices
    state = np.zeros(n, np.int8)  # 0 undecided, 1 chosen, -1 left out
    row = np.repeat(np.arange(n), np.diff(ptr))
    while True:
        open_ = state == 0
        if not open_.any():
            return state == 1
        p = np.where(open_, priority, -1.0)
        best = np.full(n, -1.0)
        np.maximum.at(best, row, p[idx])
        chosen = open_ & (priority > best)
        state[chosen] = 1
        hit = np.zeros(n, bool)
        hit[row[chosen[idx]]] = True  # a neighbour of a chosen node
        state[open_ & hit & ~chosen] = -1


def barycentric_prolongation(fine: np.ndarray, coarse: np.ndarray):
    """(P, simplices): the interpolation (scipy CSR, fine x coarse) of the points `fine` from the
    Delaunay simplices of the points `coarse`, nonnegative with rows summing to one (module
    docstring), and those simplices."""
    import scipy.sparse as sp
    from scipy.spatial import Delaunay

    d = coarse.shape[1]
    tri = Delaunay(coarse)
    simplex = tri.find_simplex(fine)
    bary = np.zeros((len(fine), d + 1))
    inside = simplex >= 0
    bary[inside] = _barycentric(tri, simplex[inside], fine[inside])
    # a flat simplex (coarse boundary nodes in a line) has no coordinates: take the nearest proper one
    outside = np.flatnonzero(~inside | ~np.isfinite(bary).all(axis=1))
    if len(outside):
        simplex[outside], bary[outside] = _nearest_simplex(tri, fine[outside])
    bary = np.clip(bary, 0.0, None)
    bary[bary < 1e-12] = 0.0
    bary /= bary.sum(axis=1, keepdims=True)
    cols = tri.simplices[simplex]
    rows = np.repeat(np.arange(len(fine)), d + 1)
    P = sp.csr_matrix((bary.ravel(), (rows, cols.ravel())), shape=(len(fine), len(coarse)))
    P.eliminate_zeros()
    P.sort_indices()
    return P, tri.simplices


def _barycentric(tri, simplex: np.ndarray, x: np.ndarray) -> np.ndarray:
    d = x.shape[1]
    T = tri.transform[simplex]
    b = np.einsum("kij,kj->ki", T[:, :d, :], x - T[:, d, :])
    return np.hstack([b, 1.0 - b.sum(axis=1, keepdims=True)])


def _nearest_simplex(tri, x: np.ndarray):
    """For points outside the triangulation: among the simplices at the nearest coarse node, the one
    whose clipped barycentric coordinates put the point nearest to where it is."""
    from scipy.spatial import cKDTree

    d = x.shape[1]
    near = cKDTree(tri.points).query(x)[1]
    # the simplices at each coarse node
    s = tri.simplices
    order = np.argsort(s.ravel(), kind="stable")
    node_of = s.ravel()[order]
    ptr = np.searchsorted(node_of, np.arange(len(tri.points) + 1))
    owners = order // (d + 1)
    out_s = np.empty(len(x), np.int64)
    out_b = np.empty((len(x), d + 1))
    for i, (p, c) in enumerate(zip(x, near)):
        cand = owners[ptr[c]:ptr[c + 1]]
        b = _barycentric(tri, cand, np.repeat(p[None], len(cand), axis=0))
        b = np.clip(b, 0.0, None)
        b /= np.maximum(b.sum(axis=1, keepdims=True), 1e-300)
        y = np.einsum("kj,kjd->kd", b, tri.points[s[cand]])
        dist = np.linalg.norm(y - p, axis=1)
        dist[~np.isfinite(dist)] = np.inf
        k = int(np.argmin(dist))
        if not np.isfinite(dist[k]):  # only flat simplices here: the nearest coarse node alone
            k, b[k] = 0, (s[cand[0]] == c).astype(float)
        out_s[i], out_b[i] = cand[k], b[k]
    return out_s, out_b


def coarsening_prolongations(mesh: Mesh, coarsest=None) -> List:
    """The prolongations (scipy CSR, fine x coarse) from the coarsest level to `mesh`, coarsest
    first, of geometric coarsening (module docstring), down to at most `coarsest` nodes (None:
    coarsest_nodes)."""
    import scipy.sparse as sp

    coarsest = coarsest_nodes(mesh.num_points, mesh.dim, coarsest)
    if not (isinstance(coarsest, (int, np.integer)) and coarsest >= mesh.dim + 2):
        raise ValueError(f"coarsest must be a number of nodes of at least {mesh.dim + 2}, got {coarsest!r}")
    x = mesh.points
    G = node_graph(mesh.cells, mesh.num_points)
    cls = node_classes(mesh)
    out = []
    while len(x) > coarsest:
        n = len(x)
        # distinct priorities: class first, then a fixed scramble of the index (no dependence on the
        # numbering's geometry, which would make the set line up)
        scramble = (np.arange(n, dtype=np.uint64) * np.uint64(2654435761)) % np.uint64(2**32)
        priority = cls * 2.0**33 + scramble.astype(float)
        keep = independent_set(G, priority)
        if keep.sum() < mesh.dim + 2 or keep.sum() >= n:  # too few for a simplex, or nothing joined
            break
        P, simplices = barycentric_prolongation(x, x[keep])
        out.append(P)
        x, cls = x[keep], cls[keep]
        k = simplices.shape[1]
        rows = np.repeat(simplices, k, axis=1).ravel()
        cols = np.tile(simplices, (1, k)).ravel()
        sel = rows != cols
        G = sp.csr_matrix((np.ones(int(sel.sum())), (rows[sel], cols[sel])), shape=(len(x), len(x)))
        G.data[:] = 1.0
    return out[::-1]
