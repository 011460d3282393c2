"""Issue 11, fifth part: why nodal block Gauss-Seidel smooths P1 (triangle) elasticity slowly, and
whether a cheap extra subspace correction fixes it. numpy / scipy reference (no core solver): unit
square, 2 x 2 coarse squares with alternating diagonals (contactmg.generators.rectangle), all sides
clamped, Galerkin coarse matrices, E = 2000, Poisson's ratio 0.28.

    python benchmarks/p1_smoother_modes.py [--parts modes rates] [--mode-level 4] [--levels 4 6]

modes:  the two-grid error operator of nodal block SSOR(3,3) (omega 1 and 1.3; pre forward, post
        backward, as the core's cycle) with an exact coarse solve, built densely on a small level;
        its slowest eigenmodes: energy split by cell, share of the energy in the divergence term,
        and the A-orthogonal projection of the mode onto small local spaces (per-cell rigid
        rotations, per-node-patch rotations, per-edge normal/tangential pairs, per-cell 6-dof blocks).
rates:  V(nu, nu) rate (random start, zero load, geometric mean of the last 5 of 16 ratios) of the
        nodal sweep and of the nodal sweep followed by a successive subspace correction over local
        directions (each an exact 1-D energy minimization, Gauss-Seidel on V^T A V), with a work count
        per sweep in units of one nodal sweep (flops of the row products; see work()).
"""
import argparse
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from contactmg import _core
from contactmg.generators import rectangle
from contactmg.hierarchy import MeshHierarchy

E_MOD, POISSON = 2000.0, 0.28


def to_scipy(A):
    d = A.block_size
    indptr, indices = A.indptr, A.indices
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    r = (rows[:, None, None] * d + np.arange(d)[None, :, None]).repeat(d, 2)
    c = (indices[:, None, None] * d + np.arange(d)[None, None, :]).repeat(d, 1)
    return sp.csr_matrix((A.data.ravel(), (r.ravel(), c.ravel())), shape=A.shape)


def boundary_nodes(mesh):
    b = np.zeros(mesh.num_points, bool)
    b[np.unique(mesh.facets)] = True
    return b


def element_matrices(points, cells, E=E_MOD, nu=POISSON):
    """P1 plane-strain element stiffness, dofs (node, component) node-major; also the lambda part."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    x = points[cells]  # (nc, 3, 2)
    J = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=2)  # columns
    area = 0.5 * np.abs(np.linalg.det(J))
    G = np.linalg.inv(J)  # (nc, 2, 2): rows d(xi)/dx
    dref = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    grad = np.einsum("kr,crs->cks", dref, G)  # (nc, 3, 2) gradient of each hat
    B = np.zeros((len(cells), 3, 6))  # strain (xx, yy, 2xy) from dofs
    B[:, 0, 0::2] = grad[:, :, 0]
    B[:, 1, 1::2] = grad[:, :, 1]
    B[:, 2, 0::2] = grad[:, :, 1]
    B[:, 2, 1::2] = grad[:, :, 0]
    C = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
    Cl = np.array([[lam, lam, 0], [lam, lam, 0], [0, 0, 0]])
    K = np.einsum("c,cia,ij,cjb->cab", area, B, C, B)
    Kl = np.einsum("c,cia,ij,cjb->cab", area, B, Cl, B)
    return K, Kl


class Level:
    def __init__(self, A, free_nodes, points):
        self.A = A.tocsr()
        self.free = free_nodes  # indices of the level's nodes that are free
        self.points = points[free_nodes]
        n = A.shape[0] // 2
        blocks = np.stack([A[0::2, 0::2].diagonal(), A[0::2, 1::2].diagonal(), A[1::2, 0::2].diagonal(),
                           A[1::2, 1::2].diagonal()], 1).reshape(n, 2, 2)
        self.Dblocks = blocks
        self.D = sp.block_diag(list(blocks), format="csr")
        self.Dinv = sp.block_diag(list(np.linalg.inv(blocks)), format="csr")
        bl = sp.tril(self.A, -1).tocsr()
        # strictly block-lower: drop the (1, 0) entry inside each diagonal block
        Lb = (bl - sp.tril(self.D, -1)).tocsr()
        Lb.eliminate_zeros()
        self.L = Lb
        self.U = Lb.T.tocsr()
        self.cache = {}

    def sor(self, x, b, omega, forward):
        """One block SOR sweep: x += (D/omega + L)^{-1} (b - A x) (U when backward)."""
        key = (omega, forward)
        if key not in self.cache:
            T = (sp.eye(self.A.shape[0]) + omega * ((self.L if forward else self.U) @ self.Dinv)).tocsr()
            self.cache[key] = T
        r = b - self.A @ x
        w = spla.spsolve_triangular(self.cache[key], r, lower=forward, unit_diagonal=True)
        return x + omega * (self.Dinv @ w)


def hierarchy(levels, cell="triangle"):
    h = MeshHierarchy.build(rectangle(2, 2, cell=cell), levels)
    return h


def levels_of(h, E=E_MOD, nu=POISSON):
    """Galerkin hierarchy on the free nodes (all sides clamped). Returns levels (coarse first) and P's."""
    m = h.finest
    Af = to_scipy(_core.assemble_elasticity(m.points, m.cells, m.cell_type, E, nu))
    frees = [np.flatnonzero(~boundary_nodes(mm)) for mm in h.meshes]
    dof = lambda f: np.c_[2 * f, 2 * f + 1].ravel()  # noqa: E731
    A = Af[dof(frees[-1])][:, dof(frees[-1])]
    Ps, As = [], [A]
    for l in range(len(h.meshes) - 1, 0, -1):
        T = h.transfers[l - 1].matrix()[frees[l]][:, frees[l - 1]]
        P = sp.kron(T, sp.eye(2)).tocsr()
        Ps.insert(0, P)
        A = (P.T @ A @ P).tocsr()
        As.insert(0, A)
    lv = [Level(A, f, mm.points) for A, f, mm in zip(As, frees, h.meshes)]
    return lv, Ps, Af, frees


# ---------------------------------------------------------------- subspace directions
def cell_rotations(mesh, free):
    """Per cell: the infinitesimal rotation about its centroid on its (free) nodes."""
    pos = -np.ones(mesh.num_points, int)
    pos[free] = np.arange(len(free))
    rows, cols, vals = [], [], []
    for k, c in enumerate(mesh.cells):
        cen = mesh.points[c].mean(0)
        for v in c:
            if pos[v] < 0:
                continue
            dx = mesh.points[v] - cen
            rows += [2 * pos[v], 2 * pos[v] + 1]
            cols += [k, k]
            vals += [-dx[1], dx[0]]
    V = sp.csc_matrix((vals, (rows, cols)), shape=(2 * len(free), len(mesh.cells)))
    return drop_empty(V)


def patch_rotations(mesh, free):
    """Per free node i: rotation about x_i on the nodes of its patch (zero at i itself)."""
    pos = -np.ones(mesh.num_points, int)
    pos[free] = np.arange(len(free))
    nb = [set() for _ in range(mesh.num_points)]
    for c in mesh.cells:
        for a in c:
            nb[a].update(c)
    rows, cols, vals = [], [], []
    for k, i in enumerate(free):
        for v in nb[i]:
            if v == i or pos[v] < 0:
                continue
            dx = mesh.points[v] - mesh.points[i]
            rows += [2 * pos[v], 2 * pos[v] + 1]
            cols += [k, k]
            vals += [-dx[1], dx[0]]
    return drop_empty(sp.csc_matrix((vals, (rows, cols)), shape=(2 * len(free), len(free))))


def edges_of(mesh):
    e = np.sort(np.r_[mesh.cells[:, [0, 1]], mesh.cells[:, [1, 2]], mesh.cells[:, [0, 2]]], 1)
    return np.unique(e, axis=0)


def edge_modes(mesh, free, kinds=("normal", "tangent")):
    """Per edge (a, b) with both ends free: opposite displacements of its two nodes, normal to the
    edge (a local rotation of the edge) and / or along it (a local stretch)."""
    pos = -np.ones(mesh.num_points, int)
    pos[free] = np.arange(len(free))
    rows, cols, vals = [], [], []
    k = 0
    for a, b in edges_of(mesh):
        if pos[a] < 0 or pos[b] < 0:
            continue
        t = mesh.points[b] - mesh.points[a]
        t = t / np.linalg.norm(t)
        for kind in kinds:
            v = np.array([-t[1], t[0]]) if kind == "normal" else t
            rows += [2 * pos[a], 2 * pos[a] + 1, 2 * pos[b], 2 * pos[b] + 1]
            cols += [k] * 4
            vals += [-v[0], -v[1], v[0], v[1]]
            k += 1
    return drop_empty(sp.csc_matrix((vals, (rows, cols)), shape=(2 * len(free), k)))


def cell_blocks(mesh, free):
    """All dofs of each cell (for the projection measure only)."""
    pos = -np.ones(mesh.num_points, int)
    pos[free] = np.arange(len(free))
    rows, cols = [], []
    k = 0
    for c in mesh.cells:
        for v in c:
            if pos[v] >= 0:
                for comp in range(2):
                    rows.append(2 * pos[v] + comp)
                    cols.append(k)
                    k += 1
    return sp.csc_matrix((np.ones(len(rows)), (rows, cols)), shape=(2 * len(free), k))


def drop_empty(V):
    V = V.tocsc()
    keep = np.flatnonzero(np.diff(V.indptr) > 0)
    return V[:, keep].tocsc()


def captured(A, V, e):
    """Share of e's energy in span(V) (A-orthogonal projection)."""
    g = V.T @ (A @ e)
    G = (V.T @ A @ V).toarray()
    c = np.linalg.solve(G, g)
    return float(g @ c / (e @ (A @ e)))


# ---------------------------------------------------------------- cycles
class SubspaceGS:
    """Successive exact 1-D minimizations over the columns of V (in order; reversed when backward):
    Gauss-Seidel on V^T A V with the restricted residual."""

    def __init__(self, A, V, omega=1.0):
        self.V = V.tocsr()
        G = (V.T @ A @ V).tocsr()
        d = G.diagonal()
        self.dinv = 1.0 / d
        self.omega = omega
        n = G.shape[0]
        Dm = sp.diags(d)
        self.Tl = (sp.eye(n) + omega * sp.tril(G, -1) @ sp.diags(self.dinv)).tocsr()
        self.Tu = (sp.eye(n) + omega * sp.triu(G, 1) @ sp.diags(self.dinv)).tocsr()
        self.nnzG, self.nnzV = G.nnz, V.nnz
        del Dm

    def apply(self, A, x, b, forward):
        r = self.V.T @ (b - A @ x)
        w = spla.spsolve_triangular(self.Tl if forward else self.Tu, r, lower=forward, unit_diagonal=True)
        return x + self.V @ (self.omega * self.dinv * w)


def vcycle(lv, Ps, l, x, b, nu1, nu2, omega, extra=None, cycle="V", coarse_exact=None):
    L = lv[l]
    if l == 0:
        return spla.spsolve(L.A.tocsc(), b)
    for _ in range(nu1):
        x = L.sor(x, b, omega, True)
        if extra is not None and l in extra:
            x = extra[l].apply(L.A, x, b, True)
    P = Ps[l - 1]
    r = P.T @ (b - L.A @ x)
    if coarse_exact is not None and l == coarse_exact:
        c = spla.spsolve(lv[l - 1].A.tocsc(), r)
    else:
        c = vcycle(lv, Ps, l - 1, np.zeros(len(r)), r, nu1, nu2, omega, extra, cycle)
    x = x + P @ c
    for _ in range(nu2):
        if extra is not None and l in extra:
            x = extra[l].apply(L.A, x, b, False)
        x = L.sor(x, b, omega, False)
    return x


def rate(lv, Ps, nu, omega, extra=None, cycles=16, seed=0, two_grid=False):
    l = len(lv) - 1
    A = lv[l].A
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(A.shape[0])
    b = np.zeros_like(x)
    en = [np.sqrt(x @ (A @ x))]
    for _ in range(cycles):
        x = vcycle(lv, Ps, l, x, b, nu, nu, omega, extra, coarse_exact=l if two_grid else None)
        en.append(np.sqrt(x @ (A @ x)))
        x /= en[-1]
        en[-1] = 1.0 if len(en) else en[-1]
    # ratios were normalized: en[k] before normalization / 1
    return float(np.exp(np.mean(np.log(np.asarray(en[-5:])))))


def rate_norms(lv, Ps, nu, omega, extra=None, cycles=16, seed=0, two_grid=False):
    l = len(lv) - 1
    A = lv[l].A
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(A.shape[0])
    x /= np.sqrt(x @ (A @ x))
    b = np.zeros_like(x)
    q = []
    for _ in range(cycles):
        x = vcycle(lv, Ps, l, x, b, nu, nu, omega, extra, coarse_exact=l if two_grid else None)
        n = np.sqrt(x @ (A @ x))
        q.append(n)
        x /= n
    return float(np.exp(np.mean(np.log(q[-5:]))))


# ---------------------------------------------------------------- work
def work_nodal(A):
    """Flops of one nodal sweep: the row products (2 flops per matrix entry) plus the 2x2 solve."""
    return 2 * A.nnz + 8 * (A.shape[0] // 2)


def work_subspace(A, S):
    """One subspace sweep done globally, as Gauss-Seidel on the stored G = V^T A V: a residual
    (2 nnz(A)), V^T r and V w (2 nnz(V) each) and the triangular sweep over G (nnz(G) + n_V)."""
    return 2 * A.nnz + 4 * S.nnzV + S.nnzG + S.V.shape[1]


def work_subspace_local(A, V):
    """The same correction done locally, direction by direction (as a core routine would): for each
    direction, the rows of A at its support (2 flops per entry) and the update."""
    Vr = V.tocsc()
    rowlen = np.diff(A.tocsr().indptr)
    f = 0
    for k in range(V.shape[1]):
        rows = Vr.indices[Vr.indptr[k]:Vr.indptr[k + 1]]
        f += 2 * rowlen[rows].sum() + 4 * len(rows)
    return f


def two_grid_operator(lv, Ps, nu, omega, extra=None):
    """Dense E = S_post (I - P Ac^-1 P^T A) S_pre of the finest pair, pre forward, post backward."""
    l = len(lv) - 1
    L, P = lv[l], Ps[l - 1]
    A = L.A
    n = A.shape[0]
    X = np.eye(n)
    Z = np.zeros((n, n))
    for _ in range(nu):
        X = L.sor(X, Z, omega, True)
        if extra is not None:
            X = extra.apply(A, X, Z, True)
    Ac = lv[l - 1].A.toarray()
    X = X - P @ np.linalg.solve(Ac, P.T @ (A @ X))
    for _ in range(nu):
        if extra is not None:
            X = extra.apply(A, X, Z, False)
        X = L.sor(X, Z, omega, False)
    return X


def slow_modes(lv, Ps, nu, omega, k=4, extra=None):
    """The k largest |eigenvalues| of E and their eigenvectors (E is A-self-adjoint: real spectrum)."""
    E = two_grid_operator(lv, Ps, nu, omega, extra)
    A = lv[-1].A.toarray()
    Lc = np.linalg.cholesky(A)
    S = Lc.T @ E @ np.linalg.inv(Lc.T)  # symmetric similar matrix
    S = 0.5 * (S + S.T)
    w, Q = np.linalg.eigh(S)
    idx = np.argsort(-np.abs(w))[:k]
    vecs = np.linalg.solve(Lc.T, Q[:, idx])
    return w[idx], vecs


# ---------------------------------------------------------------- non-overlapping aggregates
def aggregates(mesh, free, kind="cells", seed=None):
    """A partition of the free nodes into non-overlapping groups: whole cells taken greedily (each
    node in at most one), then leftover nodes paired along an edge with another leftover node, the
    rest single. kind="pairs": pairs only (a greedy edge matching). Returns a list of arrays of
    positions into `free`, in the order of their smallest node."""
    pos = -np.ones(mesh.num_points, int)
    pos[free] = np.arange(len(free))
    taken = np.zeros(len(free), bool)
    groups = []
    cells = mesh.cells if seed is None else mesh.cells[np.random.default_rng(seed).permutation(len(mesh.cells))]
    if kind == "cells":
        for c in cells:
            p = pos[c]
            if (p >= 0).all() and not taken[p].any():
                taken[p] = True
                groups.append(np.sort(p))
    ed = edges_of(mesh)
    if seed is not None:
        ed = ed[np.random.default_rng(seed + 1).permutation(len(ed))]
    for a, b in ed:
        pa, pb = pos[a], pos[b]
        if pa >= 0 and pb >= 0 and not taken[pa] and not taken[pb]:
            taken[pa] = taken[pb] = True
            groups.append(np.sort([pa, pb]))
    for p in np.flatnonzero(~taken):
        groups.append(np.array([p]))
    groups.sort(key=lambda g: g[0])
    return groups


class AggregateSOR:
    """Block SOR over non-overlapping node groups: each group's dofs solved exactly together
    (relaxed by omega), groups in order (reversed when backward)."""

    def __init__(self, A, groups, omega):
        perm = np.concatenate([np.c_[2 * g, 2 * g + 1].ravel() for g in groups])
        self.perm = perm
        Ap = A[perm][:, perm].tocsr()
        sizes = np.array([2 * len(g) for g in groups])
        starts = np.r_[0, np.cumsum(sizes)]
        blocks = [Ap[s:e, s:e].toarray() for s, e in zip(starts[:-1], starts[1:])]
        D = sp.block_diag(blocks, format="csr")
        self.Dinv = sp.block_diag([np.linalg.inv(b) for b in blocks], format="csr")
        Lb = (sp.tril(Ap, -1) - sp.tril(D, -1)).tocsr()
        Lb.eliminate_zeros()
        n = A.shape[0]
        self.Tl = (sp.eye(n) + omega * Lb @ self.Dinv).tocsr()
        self.Tu = (sp.eye(n) + omega * Lb.T.tocsr() @ self.Dinv).tocsr()
        self.Ap, self.omega = Ap, omega
        self.block_entries = int(sum(s * s for s in sizes))

    def sweep(self, A, x, b, forward):
        p = self.perm
        r = (b - A @ x)[p]
        w = spla.spsolve_triangular(self.Tl if forward else self.Tu, r, lower=forward, unit_diagonal=True)
        dx = np.empty_like(x)
        dx[p] = self.omega * (self.Dinv @ w)
        return x + dx


def vcycle_agg(lv, Ps, smoothers, l, x, b, nu1, nu2, omega):
    """V-cycle whose smoother on level l is smoothers[l] (an AggregateSOR) or the nodal SOR."""
    L = lv[l]
    if l == 0:
        return spla.spsolve(L.A.tocsc(), b)
    sm = smoothers.get(l)
    for _ in range(nu1):
        x = sm.sweep(L.A, x, b, True) if sm is not None else L.sor(x, b, omega, True)
    P = Ps[l - 1]
    c = vcycle_agg(lv, Ps, smoothers, l - 1, np.zeros(P.shape[1]), P.T @ (b - L.A @ x), nu1, nu2, omega)
    x = x + P @ c
    for _ in range(nu2):
        x = sm.sweep(L.A, x, b, False) if sm is not None else L.sor(x, b, omega, False)
    return x


def rate_agg(lv, Ps, smoothers, nu, omega, cycles=16, seed=0):
    l = len(lv) - 1
    A = lv[l].A
    x = np.random.default_rng(seed).standard_normal(A.shape[0])
    x /= np.sqrt(x @ (A @ x))
    q = []
    for _ in range(cycles):
        x = vcycle_agg(lv, Ps, smoothers, l, x, np.zeros_like(x), nu, nu, omega)
        n = np.sqrt(x @ (A @ x))
        q.append(n)
        x /= n
    return float(np.exp(np.mean(np.log(q[-5:]))))


# ---------------------------------------------------------------- other cheap alternatives
def lambda_max(A, Dinv, iters=60, seed=0):
    x = np.random.default_rng(seed).standard_normal(A.shape[0])
    for _ in range(iters):
        y = Dinv @ (A @ x)
        lam = np.sqrt(y @ y / (x @ x))
        x = y / np.linalg.norm(y)
    return lam * 1.05


def chebyshev(A, Dinv, x, b, k, lmax, ratio):
    """k steps of Chebyshev iteration for D^-1 A on [lmax / ratio, lmax] (one matrix product each)."""
    lmin = lmax / ratio
    theta, delta = 0.5 * (lmax + lmin), 0.5 * (lmax - lmin)
    sigma = theta / delta
    rho = 1.0 / sigma
    r = Dinv @ (b - A @ x)
    d = r / theta
    for _ in range(k):
        x = x + d
        r = r - Dinv @ (A @ d)
        rho_new = 1.0 / (2 * sigma - rho)
        d = rho_new * rho * d + 2 * rho_new / delta * r
        rho = rho_new
    return x


def vcycle_gen(lv, Ps, l, x, b, pre, post):
    """V-cycle with smoothers pre(l, x, b) and post(l, x, b)."""
    L = lv[l]
    if l == 0:
        return spla.spsolve(L.A.tocsc(), b)
    x = pre(l, x, b)
    P = Ps[l - 1]
    c = vcycle_gen(lv, Ps, l - 1, np.zeros(P.shape[1]), P.T @ (b - L.A @ x), pre, post)
    x = post(l, x + P @ c, b)
    return x


def rate_gen(lv, Ps, pre, post, cycles=16, seed=0):
    A = lv[-1].A
    x = np.random.default_rng(seed).standard_normal(A.shape[0])
    x /= np.sqrt(x @ (A @ x))
    q = []
    for _ in range(cycles):
        x = vcycle_gen(lv, Ps, len(lv) - 1, x, np.zeros_like(x), pre, post)
        n = np.sqrt(x @ (A @ x))
        q.append(n)
        x /= n
    return float(np.exp(np.mean(np.log(q[-5:]))))


# ---------------------------------------------------------------- driver
def seen(A, V, e):
    """sum_k (v_k^T A e)^2 / (v_k^T A v_k) / e^T A e: the energy the 1-D minimizations over the
    columns of V would remove from e if applied additively (how well the family 'sees' the mode)."""
    g = V.T @ (A @ e)
    dv = np.asarray(V.multiply(A @ V).sum(0)).ravel()
    return float((g ** 2 / dv).sum() / (e @ (A @ e)))


def seen_blocks(A, groups, e):
    """The same for exact solves on blocks of nodes (groups: arrays of node positions)."""
    r = A @ e
    s = 0.0
    for g in groups:
        dd = np.c_[2 * g, 2 * g + 1].ravel()
        s += r[dd] @ np.linalg.solve(A[dd][:, dd].toarray(), r[dd])
    return s / (e @ (A @ e))


def part_modes(level):
    h = hierarchy(level)
    lv, Ps, _, frees = levels_of(h)
    m, free, A = h.finest, frees[-1], lv[-1].A
    K, Kl = element_matrices(m.points, m.cells)
    pos = -np.ones(m.num_points, int)
    pos[free] = np.arange(len(free))
    nodes = [np.array([i]) for i in range(len(free))]
    cells = [pos[c][pos[c] >= 0] for c in m.cells]
    fams = {"cell rotation": cell_rotations(m, free), "patch rotation": patch_rotations(m, free),
            "edge normal": edge_modes(m, free, ("normal",)), "edge tangent": edge_modes(m, free, ("tangent",))}
    print(f"modes: unit square level {level}, {A.shape[0]} dofs, two-grid nodal SSOR(3,3) with an exact coarse solve")
    x = m.points[m.cells]
    J = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=2)
    grad = np.einsum("kr,crs->cks", np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]), np.linalg.inv(J))
    area = 0.5 * np.abs(np.linalg.det(J))
    print("  omega  eig   lambda-share  10%-cells  rot^2/|grad|^2  div^2/|grad|^2  coarse-share | seen by: node  cell(6x6)"
          "  " + "  ".join(fams))
    for om in (1.0, 1.3):
        w, vecs = slow_modes(lv, Ps, 3, om, k=3)
        for j in range(3):
            e = vecs[:, j]
            ue = np.zeros((m.num_points, 2))
            ue[free] = e.reshape(-1, 2)
            loc = ue[m.cells].reshape(len(m.cells), 6)
            ek = np.einsum("ca,cab,cb->c", loc, K, loc)
            el = np.einsum("ca,cab,cb->c", loc, Kl, loc)
            gu = np.einsum("cks,ckt->cts", grad, ue[m.cells])
            g2 = np.sum(area * (gu ** 2).sum((1, 2)))
            rot = 0.5 * (gu[:, 1, 0] - gu[:, 0, 1])
            div = gu[:, 0, 0] + gu[:, 1, 1]
            top = np.sort(ek)[::-1][: len(ek) // 10].sum() / ek.sum()
            print(f"  {om:4.1f} {w[j]:6.3f}   {el.sum() / ek.sum():6.3f}     {top:6.3f}      {np.sum(area * rot ** 2) / g2:6.3f}"
                  f"          {np.sum(area * div ** 2) / g2:6.3f}        {captured(A, Ps[-1], e):6.3f}   |        "
                  f"{seen_blocks(A, nodes, e):5.3f}  {seen_blocks(A, cells, e):5.3f}  "
                  + "  ".join(f"{seen(A, V, e):{len(k)}.3f}" for k, V in fams.items()), flush=True)


def part_rates(level):
    h = hierarchy(level)
    lv, Ps, _, frees = levels_of(h)
    A = lv[-1].A
    wn = work_nodal(A)
    top = len(lv) - 1
    print(f"rates: unit square level {level}, {A.shape[0]} dofs; V-cycle rate, work per cycle in nodal fine sweeps"
          " (the smoother's fine-level work only; the grid transfers and coarse levels come on top of every variant alike)")
    print(f"  {'variant':58} {'rate':>6} {'work':>6} {'rate^(1/work)':>13}")

    def row(name, r, work):
        print(f"  {name:58} {r:6.3f} {work:6.1f} {r ** (1.0 / work):13.3f}", flush=True)

    def sorn(l, x, b, om, fw, n):
        for _ in range(n):
            x = lv[l].sor(x, b, om, fw)
        return x

    for om in (1.0, 1.3):
        for nu in (3, 4, 6):
            row(f"nodal SSOR omega {om} V({nu},{nu})", rate_norms(lv, Ps, nu, om), 2 * nu)
    fams = {"cell rotation": cell_rotations, "patch rotation": patch_rotations,
            "edge normal": lambda m, f: edge_modes(m, f, ("normal",)), "edge normal+tangent": edge_modes}
    for name, f in fams.items():
        ex = {l: SubspaceGS(lv[l].A, f(h.meshes[l], frees[l])) for l in range(1, len(lv))}
        wl = work_subspace_local(A, ex[top].V) / wn
        wg = work_subspace(A, ex[top]) / wn
        for nu in (2, 3):
            row(f"nodal 1.3 + {name} after every sweep V({nu},{nu}) [local]", rate_norms(lv, Ps, nu, 1.3, ex), 2 * nu * (1 + wl))
        row(f"  the same V(3,3), done on the stored G = V^T A V", rate_norms(lv, Ps, 3, 1.3, ex), 6 * (1 + wg))
    ex = {l: SubspaceGS(lv[l].A, patch_rotations(h.meshes[l], frees[l])) for l in range(1, len(lv))}
    wg = work_subspace(A, ex[top]) / wn
    pre = lambda l, x, b: ex[l].apply(lv[l].A, sorn(l, x, b, 1.3, True, 3), b, True)  # noqa: E731
    post = lambda l, x, b: sorn(l, ex[l].apply(lv[l].A, x, b, False), b, 1.3, False, 3)  # noqa: E731
    row("nodal 1.3 V(3,3) + one patch-rotation pass pre and post [G]", rate_gen(lv, Ps, pre, post), 6 + 2 * wg)
    for om in (1.0, 1.3):
        sm = {l: AggregateSOR(lv[l].A, aggregates(h.meshes[l], frees[l], "cells"), om) for l in range(1, len(lv))}
        extra = (sm[top].block_entries * 2 - 8 * (A.shape[0] // 2)) / wn  # block solves beyond the 2x2 ones
        for nu in (3, 4):
            row(f"non-overlapping cell aggregates (6x6 blocks) SOR {om} V({nu},{nu})", rate_agg(lv, Ps, sm, nu, om), 2 * nu * (1 + extra))
    lm = {l: lambda_max(lv[l].A, lv[l].Dinv) for l in range(1, len(lv))}
    for k in (3, 6):
        f = lambda l, x, b: chebyshev(lv[l].A, lv[l].Dinv, x, b, k, lm[l], 8.0)  # noqa: E731
        row(f"Chebyshev, block Jacobi, [lmax/8, lmax], degree {k} V", rate_gen(lv, Ps, f, f), 2 * k)
    for wpre, wpost in ((1.3, 1.3), (1.4, 1.4), (1.0, 1.4), (1.2, 1.5), (1.0, 1.6), (1.0, 1.7), (1.0, 1.8), (1.8, 1.0), (0.9, 1.7)):
        for nu in (3,) if (wpre, wpost) != (1.0, 1.7) else (2, 3, 4):
            r = rate_gen(lv, Ps, lambda l, x, b: sorn(l, x, b, wpre, True, nu),
                         lambda l, x, b: sorn(l, x, b, wpost, False, nu), cycles=30)
            row(f"nodal SOR, omega {wpre} pre / {wpost} post, V({nu},{nu})", r, 2 * nu)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", nargs="+", default=["modes", "rates"])
    ap.add_argument("--mode-level", type=int, default=5)
    ap.add_argument("--levels", type=int, nargs="+", default=[6])
    args = ap.parse_args()
    t0 = time.perf_counter()
    if "modes" in args.parts:
        part_modes(args.mode_level)
    if "rates" in args.parts:
        for L in args.levels:
            part_rates(L)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
