"""The nested start: the problem solved on its coarse levels first, each solution interpolated to
the next level as its start (nested iteration, the first half of full multigrid).

Why: a body held only by its contacts, or one that must travel far before it touches, starts from
u = 0 far from its answer, and the monotone coarse corrections move it only as far as the smallest
gap under each coarse function allows (a plate on a cylinder crept by 1e-3 a cycle for 1000
cycles). On a coarse level the same travel is cheap, and from the interpolated coarse answer the
finest level has only its own details left (0034-nested-start).

The coarse problems are algebraic, so every hierarchy whose coarse nodes are fine nodes has them
(refined meshes, adaptive ones, coarse levels made from a fine mesh): A_k = P^T A_{k+1} P,
f_k = P^T f_{k+1}, and the Dirichlet data, contact nodes, normals, gaps and friction coefficients of
the fine nodes that are coarse nodes (rediscretization by injection). One body only.
"""
from __future__ import annotations

import time
from typing import List, Optional, Tuple

import numpy as np

from .. import _core
from ..model.problem import _block_matrix, _bsr


def injection(P) -> Optional[np.ndarray]:
    """For a prolongation P (fine x coarse, scipy): the fine node of each coarse node (the row of P
    that is the coarse node's unit vector), or None where a coarse node has none (aggregation)."""
    P = P.tocsr()
    counts = np.diff(P.indptr)
    single = np.nonzero(counts == 1)[0]
    cols, vals = P.indices[P.indptr[single]], P.data[P.indptr[single]]
    unit = vals == 1.0
    out = np.full(P.shape[1], -1, np.int64)
    out[cols[unit]] = single[unit]
    return None if np.any(out < 0) else out


def _galerkin(A, P, d: int):
    """P^T A P of a (n d x n d) scipy matrix and a scalar nodal prolongation P, block by block."""
    import scipy.sparse as sp

    Pd = sp.kron(P, sp.identity(d), format="csr")
    return (Pd.T @ A @ Pd).tocsr()


def _clip(u: np.ndarray, nodes: np.ndarray, normals: np.ndarray, gaps: np.ndarray) -> np.ndarray:
    """u with every contact node's normal displacement brought back onto its gap (an interpolated
    start may cut into the obstacle where the finer level's nodes are new)."""
    if len(nodes):
        over = np.maximum(np.einsum("ci,ci->c", u[nodes], normals) - gaps, 0.0)
        u[nodes] -= over[:, None] * normals
    return u


def _below_lowest(problem, nodes: np.ndarray) -> list:
    """Coarse levels for the lowest stage (the fine nodes `nodes`), made by geometric coarsening as a
    lone mesh gets them: alone it would only be smoothed (200 cycles of its sweeps were the largest
    part of the nested work on a thin plate's gmsh mesh). From the hierarchy's coarse mesh where
    that is the lowest level; else (coarse levels made from a mesh) from the Delaunay simplices of
    its nodes, which serve the coarsening's node graph and interpolation only (the coarse problems
    are algebraic)."""
    from ..mesh.coarsening import coarsening_prolongations
    from ..mesh.hierarchy import Transfer
    from ..mesh.mesh import Mesh, boundary_facets

    h = problem.hierarchy
    if not (h.from_fine_mesh or problem.coarse_levels_from_mesh()):
        mesh = h.meshes[0]
    else:
        from scipy.spatial import Delaunay, QhullError

        points = problem.mesh.points[nodes]
        d = points.shape[1]
        try:
            cells = Delaunay(points).simplices.astype(np.int64)
        except QhullError:  # fewer nodes than a simplex, or all in a plane
            return []
        cell_type = "triangle" if d == 2 else "tetra"
        facets = boundary_facets(cells, cell_type)
        mesh = Mesh._trusted(points, cells, cell_type, facets, np.zeros(len(facets), np.int64))
    return [Transfer.from_matrix(P).as_tuple() for P in coarsening_prolongations(mesh)]


def _energy(A, f: np.ndarray, u: np.ndarray) -> float:
    x = u.ravel()
    return float(0.5 * x @ (A @ x) - f.ravel() @ x)


def nested_start(problem, core_options: dict, build: dict, load: np.ndarray, fixed_values: np.ndarray
                 ) -> Tuple[Optional[np.ndarray], dict]:
    """The start of a solve of `problem` (one body) on its finest level: its coarse levels solved
    from the coarsest up (the coarsest on coarse levels made from it: _below_lowest) with the core's
    options `core_options` (a dict, as to_core gives), each from the previous one's interpolated
    solution. Returns (start or None, record): None where the hierarchy has no injection or one
    level, or where the start's energy is not below that of u = 0 (the start only has to help; a
    monotone solve never loses what it gains)."""
    t0 = time.perf_counter()
    record = {"levels": [], "cycles": [], "converged": [], "work": 0.0, "seconds": 0.0}
    p = problem
    Ps = [t.matrix() for t in p.transfers]
    if p.multibody or not Ps:
        return None, record
    inj = [injection(P) for P in Ps]
    if any(i is None for i in inj):
        return None, record
    d, n = p.mesh.dim, p.mesh.num_points
    L = len(Ps) + 1
    # the finest node of every node of each level
    fine_of: List[np.ndarray] = [None] * L
    fine_of[L - 1] = np.arange(n)
    for k in range(L - 2, -1, -1):
        fine_of[k] = fine_of[k + 1][inj[k]]
    c = p.contact
    where = np.full(n, -1, np.int64)
    where[c.nodes] = np.arange(len(c.nodes))
    # assembled anew (the solver took the problem's matrix) and not kept by the problem: it goes with the start
    A = _bsr(p.take_matrix()[0], n, d).tocsr()
    mats, loads = [None] * L, [None] * L
    mats[L - 1], loads[L - 1] = A, np.asarray(load, dtype=float)
    for k in range(L - 2, -1, -1):
        mats[k] = _galerkin(mats[k + 1], Ps[k], d)
        loads[k] = Ps[k].T @ loads[k + 1]

    def level_data(k):
        nodes = fine_of[k]
        pos = where[nodes]
        on = np.nonzero(pos >= 0)[0]
        cc = pos[on]
        return (p.fixed[nodes], fixed_values[nodes], on.astype(np.int64), c.normals[cc], c.gaps[cc],
                p.coefficients[cc])

    transfers = [t.as_tuple() for t in p.transfers]
    cls = _core.ContactSolver2D if d == 2 else _core.ContactSolver3D
    u = None
    for k in range(L - 1):
        fixed, values, nodes, normals, gaps, coefs = level_data(k)
        if u is not None:
            u = _clip(Ps[k - 1] @ u, nodes, normals, gaps)
        core = cls(_block_matrix(mats[k], d), loads[k], fixed, values, nodes, normals, gaps, coefs, p.law,
                   transfers[:k] if k else _below_lowest(p, fine_of[0]), build)
        raw = core.solve(u, core_options)
        u = np.asarray(raw["u"])
        record["levels"].append(k)
        record["cycles"].append(int(raw["cycles"]))
        record["converged"].append(bool(raw["converged"]))
        record["work"] += int(raw["cycles"]) * len(fine_of[k]) / n
        del core
    fixed, values, nodes, normals, gaps, _ = level_data(L - 1)
    start = _clip(Ps[L - 2] @ u, nodes, normals, gaps)
    start[fixed.astype(bool)] = values[fixed.astype(bool)]
    zero = np.where(fixed.astype(bool), values, 0.0)
    record["seconds"] = time.perf_counter() - t0
    if not (_energy(A, loads[L - 1], start) < _energy(A, loads[L - 1], zero)):
        record["kept"] = False
        return None, record
    record["kept"] = True
    return start, record

