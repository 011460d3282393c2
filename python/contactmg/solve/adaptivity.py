"""A posteriori error estimation for contact problems and bulk marking.

The hierarchical estimator for variational inequalities (Kornhuber 1996; Kornhuber & Krause 2001):
for the discrete solution u on the finest mesh, take the next uniform refinement's new hat
functions (one per edge, at its midpoint) and solve, for each of them alone, the local defect
problem

    minimize 1/2 e^T A_EE e - r_E^T e + s_E |e_T|   subject to (u + e)_n <= g   at a contact node,

in the d x d block of the refined stiffness matrix A_EE, with the residual r_E = f - A u of the
interpolated solution, the contact constraint of the refined problem at the midpoint and the
friction bound frozen at the current one (Coulomb: F times the interpolated normal stress of u;
Tresca: the refined problem's bound). The indicator of the edge is the energy of its correction,
eta_E^2 = e_E^T A_EE e_E, and the estimate is sqrt(sum eta_E^2). Why this one and not a residual
estimator: it sees the contact constraint (where u already touches, the defect cannot push through
the obstacle, so a correctly resolved contact zone contributes nothing), it needs no constants, it
is exactly zero for a solution that is exact in the refined space, and it reuses the uniform
refinement, assembly and exact nodal solver of the core.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from .. import _core
from ..model.friction import Coulomb, Frictionless, Tresca
from ..mesh.hierarchy import (_BASE_BYTES, MeshHierarchy, Projector, _refined, available_memory_bytes,
                              bytes_per_node, longest_edge_first)
from ..mesh.mesh import Mesh
from .options import SolverOptions


@dataclass
class Estimate:
    """Edge indicators of the hierarchical estimator on `mesh` (the finest level)."""

    mesh: Mesh
    edges: np.ndarray          # (ne, 2) node pairs; edge k is the refined mesh's node n + k
    edge_eta2: np.ndarray      # (ne,) eta_E^2
    cell_eta2: np.ndarray      # (m,) eta_T^2: each edge's share split evenly among its cells

    @property
    def total(self) -> float:
        """The estimated total error (root of the sum of squared indicators)."""
        return float(np.sqrt(self.edge_eta2.sum()))


def _block_diagonal(A) -> np.ndarray:
    """The (n, d, d) diagonal blocks of a core BlockMatrix."""
    indptr, indices, data = A.indptr, A.indices, A.data
    n = len(indptr) - 1
    rows = np.repeat(np.arange(n), np.diff(indptr))
    pos = np.flatnonzero(indices == rows)
    if len(pos) != n:
        raise ValueError("the stiffness matrix lacks a diagonal block")
    return data[pos[np.argsort(rows[pos])]]


def hierarchical_estimate(refined_problem, u_fine: np.ndarray, n_coarse: int, coarse_mesh: Mesh,
                          coarse_normal_stress: Optional[np.ndarray] = None,
                          coarse_contact_nodes: Optional[np.ndarray] = None,
                          edges: Optional[np.ndarray] = None) -> Estimate:
    """The estimator from the problem on the uniformly refined mesh (`refined_problem`, whose first
    `n_coarse` nodes are the current mesh's and node n_coarse + k the midpoint of edges[k]) and the
    current solution interpolated onto it (`u_fine`). For Coulomb friction the frozen bound needs
    the current normal stress at the current contact nodes."""
    P = refined_problem
    mesh_f = P.mesh
    d, nf = mesh_f.dim, mesh_f.num_points
    if u_fine.shape != (nf, d):
        raise ValueError(f"u_fine must have shape {(nf, d)}, got {u_fine.shape}")
    new = np.arange(n_coarse, nf)
    r = (P.load - P.A.matvec(u_fine))[new]
    B = _block_diagonal(P.A)[new].copy()
    fixed = P.fixed[new].astype(bool)
    # fixed components carry no correction: identity rows and columns, zero residual
    r[fixed] = 0.0
    for a in range(d):
        sel = fixed[:, a]
        B[sel, a, :] = 0.0
        B[sel, :, a] = 0.0
        B[sel, a, a] = 1.0
    e = np.linalg.solve(B, r[..., None])[..., 0]

    c = P.contact
    local = c.nodes - n_coarse
    on_new = local >= 0
    if np.any(on_new):
        ids = np.flatnonzero(on_new)
        Q = c.frames[ids]
        bounds = _frozen_bounds(P, ids, n_coarse, coarse_normal_stress, coarse_contact_nodes)
        solve_node = getattr(_core, f"solve_node_tresca_{d}D")
        for j, k in enumerate(ids):
            i = local[k]
            Bl = Q[j].T @ B[i] @ Q[j]
            bl = Q[j].T @ r[i]
            gl = c.gaps[k] - Q[j][:, 0] @ u_fine[c.nodes[k]]
            e[i] = Q[j] @ np.asarray(solve_node(Bl, bl, gl, bounds[j]))
    eta2 = np.einsum("ni,nij,nj->n", e, B, e)
    eta2 = np.maximum(eta2, 0.0)
    if edges is None:
        edges = _edges(coarse_mesh)
    local = _local_edges(coarse_mesh.cell_type)
    ce = coarse_mesh.cells[:, local].reshape(-1, 2)
    eid = _edge_ids(edges, ce, coarse_mesh.num_points).reshape(-1, len(local))
    count = np.bincount(eid.ravel(), minlength=len(edges))
    cell_eta2 = (eta2[eid] / count[eid]).sum(axis=1)
    return Estimate(coarse_mesh, edges, eta2, cell_eta2)


def _frozen_bounds(P, ids, n_coarse, s_n, coarse_nodes) -> np.ndarray:
    """Friction bound of the new contact nodes ids (indices into P.contact) at the current state."""
    c = P.contact
    law = P.friction
    if isinstance(law, Frictionless):
        return np.zeros(len(ids))
    if isinstance(law, Tresca):
        return P.coefficients[ids]
    if not isinstance(law, Coulomb):
        raise TypeError(f"no frozen friction bound for {type(law).__name__}")
    if s_n is None or coarse_nodes is None:
        raise ValueError("Coulomb friction needs the current normal stress and contact nodes")
    stress = np.zeros(n_coarse)
    stress[coarse_nodes] = np.abs(np.minimum(s_n, 0.0))
    T = P.hierarchy.transfers[-1]
    rows = c.nodes[ids]
    p = np.array([T.weight[T.ptr[i]:T.ptr[i + 1]] @ stress[T.parent[T.ptr[i]:T.ptr[i + 1]]] for i in rows])
    return P.coefficients[ids] * p * c.measure[ids]


# the edges of a cell as pairs of its local vertices
_LOCAL_EDGES = {"triangle": [(0, 1), (1, 2), (2, 0)], "quad": [(0, 1), (1, 2), (2, 3), (3, 0)],
                "tetra": [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]}


def _local_edges(cell_type: str) -> np.ndarray:
    if cell_type not in _LOCAL_EDGES:
        raise ValueError(f"the hierarchical estimator has no edge list for {cell_type} cells")
    return np.array(_LOCAL_EDGES[cell_type])


def _edges(mesh: Mesh) -> np.ndarray:
    # 64-bit: refined meshes hold 32-bit ids, and the keys below are i * n + j
    e = np.sort(np.asarray(mesh.cells, dtype=np.int64)[:, _local_edges(mesh.cell_type)].reshape(-1, 2), axis=1)
    return np.unique(e, axis=0)


def _edge_ids(edges: np.ndarray, pairs: np.ndarray, n: int) -> np.ndarray:
    # i * n + j overflows 32 bits from n = 46,341 nodes on: the keys are built in 64 bits
    edges = np.asarray(edges, dtype=np.int64)
    n = int(n)
    keys = edges[:, 0] * n + edges[:, 1]
    p = np.sort(np.asarray(pairs, dtype=np.int64), axis=1)
    q = p[:, 0] * n + p[:, 1]
    idx = np.searchsorted(keys, q)
    if np.any(idx >= len(keys)) or np.any(keys[np.minimum(idx, len(keys) - 1)] != q):
        raise ValueError("an edge of a cell is missing from the edge list")
    return idx


def doerfler_mark(indicators: np.ndarray, theta: float) -> np.ndarray:
    """Bulk criterion: the fewest cells (largest indicators first) whose squared indicators sum to
    at least theta times the total. Ties at the threshold are all marked (a symmetric mesh stays
    symmetric)."""
    if not (isinstance(theta, (int, float)) and 0 < theta <= 1):
        raise ValueError(f"theta must lie in (0, 1], got {theta!r}")
    eta2 = np.asarray(indicators, dtype=float)
    if eta2.ndim != 1 or not np.all(np.isfinite(eta2)) or np.any(eta2 < 0):
        raise ValueError("indicators must be a 1D array of finite numbers >= 0")
    total = eta2.sum()
    if total <= 0:
        return np.zeros(0, dtype=np.int64)
    order = np.argsort(-eta2, kind="stable")
    csum = np.cumsum(eta2[order])
    k = int(np.searchsorted(csum, theta * total * (1 - 1e-12)))
    threshold = eta2[order[min(k, len(order) - 1)]]
    return np.flatnonzero(eta2 >= threshold * (1 - 1e-9)).astype(np.int64)


def estimate(hierarchy, problem_factory: Callable, result, projector=None) -> Estimate:
    """The hierarchical estimate of `result` (a solve on hierarchy's finest level): refines the
    finest mesh uniformly once (new boundary nodes through `projector`), builds the same problem
    there with `problem_factory` and solves the local defect problems of the new nodes."""

    mesh = hierarchy.finest
    if mesh.cell_type not in ("triangle", "tetra"):
        raise ValueError(f"the hierarchical estimator is implemented for triangles and tetrahedra, got {mesh.cell_type}")
    u = np.asarray(result.displacement)
    if u.shape != (mesh.num_points, mesh.dim):
        raise ValueError(f"the result does not belong to the finest level: displacement shape {u.shape}, "
                         f"expected {(mesh.num_points, mesh.dim)}")
    r = _core.refine(mesh.points, mesh.cells, mesh.cell_type, mesh.facets, mesh.facet_tags)
    fine, t = _refined(mesh, r, projector)
    refined = MeshHierarchy(list(hierarchy.meshes) + [fine], list(hierarchy.transfers) + [t], kind=hierarchy.kind)
    problem = problem_factory(refined)
    u_fine = t.matrix() @ u
    # node n + k of the uniform refinement is the midpoint of edge k: its two parents
    edges = np.sort(t.parent[mesh.num_points:].reshape(-1, 2), axis=1)
    return hierarchical_estimate(problem, u_fine, mesh.num_points, mesh, result.normal_stress,
                                 result.contact_nodes, edges)


def adaptive_hierarchy(mesh: Mesh, levels: int, problem_factory: Callable[[MeshHierarchy], object],
             projector: Optional[Projector] = None, theta: float = 0.5, solve_options: Optional[dict] = None,
             estimate_finest: bool = True, memory_fraction: float = 0.8,
             progress: Optional[Callable[[int, MeshHierarchy, object], None]] = None) -> MeshHierarchy:
    """Adaptive refinement of a simplicial mesh to `levels` levels in all (level 1 is `mesh`): on
    each level build the problem with `problem_factory(hierarchy)` (the hierarchy so far; the
    same description on every level), solve it (`problem.solve(**solve_options)`, or with
    `solve_options` a SolverOptions: `problem.solve(options=solve_options)`), estimate
    the error with the hierarchical estimator (contactmg.solve.adaptivity), mark the cells of the
    bulk criterion with parameter `theta` and refine them by newest-vertex bisection with
    conforming closure; new boundary nodes go through `projector`. Triangles: the refinement
    edge of a coarse cell is its longest edge (the coarse cells are rotated to put it first),
    every edge of a marked cell is bisected. Tetrahedra: the marked bisection of Arnold,
    Mukherjee and Pouly from the longest-edge marking of the coarse mesh, every marked cell
    bisected 3 times (the mesh size halved there); the bisection state of the finest cells is
    kept in `bisection_marks`.
    `estimated_error` holds the estimate of every level (the finest too, unless
    not estimate_finest). The result is nested like a uniform hierarchy: the same solvers run
    on it. Adaptivity is for simplices: quadrilateral and hexahedral meshes raise ValueError."""
    if mesh.cell_type not in ("triangle", "tetra"):
        raise ValueError(f"adaptive refinement is for triangle meshes and tetrahedral meshes (simplices: "
                         f"newest-vertex bisection); got {mesh.cell_type} cells: use MeshHierarchy.build for "
                         f"uniform refinement")
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)):
        raise TypeError(f"levels must be an integer, got {type(levels).__name__}")
    if levels < 1:
        raise ValueError(f"levels must be at least 1, got {levels}")
    if isinstance(theta, bool) or not isinstance(theta, (int, float)) or not 0 < theta <= 1:
        raise ValueError(f"theta must be a number in (0, 1], got {theta!r}")
    if not callable(problem_factory):
        raise TypeError("problem_factory must be a callable hierarchy -> Problem")
    if len(np.unique(mesh.cell_tags)) > 1:
        raise ValueError("adaptive refinement keeps no regions (cell tags): a mesh of several regions needs "
                         "MeshHierarchy.build (uniform refinement)")
    t0 = time.perf_counter()
    _core.check_cells(mesh.points, mesh.cells, mesh.cell_type)
    if mesh.cell_type == "triangle":
        coarse = Mesh._trusted(mesh.points, longest_edge_first(mesh.points, mesh.cells), mesh.cell_type,
                               mesh.facets, mesh.facet_tags, mesh.cell_tags)
    else:  # the core marks the coarse tetrahedra itself (bisection_marks None)
        coarse = mesh
    h = MeshHierarchy([coarse], [], kind="adaptive")
    # a SolverOptions, or a dict of its fields
    opts = dict(options=solve_options) if isinstance(solve_options, SolverOptions) else dict(solve_options or {})
    for level in range(1, levels + 1):
        if level == levels and not estimate_finest:
            break
        m = h.finest
        need = _BASE_BYTES + (4 if m.dim == 2 else 8) * m.num_points * bytes_per_node(m)
        have = available_memory_bytes()
        if need > memory_fraction * have:
            raise MemoryError(f"estimating level {level} needs about {need / 2**30:.1f} GiB, more than "
                              f"{memory_fraction:.0%} of the {have / 2**30:.1f} GiB available")
        problem = problem_factory(h)
        result = problem.solve(**opts)
        if not result.converged:
            raise RuntimeError(f"adaptive refinement: the solve on level {level} ({m.num_points} nodes) did "
                               f"not converge ({result.status}); the estimate would be meaningless")
        est = estimate(h, problem_factory, result, projector)
        h.estimated_error.append(est.total)
        if progress is not None:
            progress(level, h, result)
        if level == levels:
            break
        marked = doerfler_mark(est.cell_eta2, theta)
        if m.cell_type == "triangle":
            r = _core.bisect(m.points, m.cells, m.facets, m.facet_tags, marked)
        else:
            r = _core.bisect(m.points, m.cells, m.facets, m.facet_tags, marked, marks=h.bisection_marks)
            h.bisection_marks = r["marks"]
        fine, t = _refined(m, r, projector)
        h.meshes.append(fine)
        h.transfers.append(t)
    h.build_seconds = time.perf_counter() - t0
    return h
