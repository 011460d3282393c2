"""Issue 10, tetrahedra: is the V(3,3) rate of ~0.5 on Kuhn cubes a defect or a property of point-block
Gauss-Seidel with P1 interpolation? Independent computations in numpy/scipy (PyAMG's compiled block
Gauss-Seidel as the smoother), on the project's own matrices and transfers and on an independent
P1 assembly:

- A (project) against an independent numpy P1 assembly; Galerkin P^T A_f P against the
  rediscretized coarse matrix; P reproducing linear fields and rigid-body modes;
- exact two-grid and V-cycle rates (power iteration on the error propagation, energy norm) for the
  scalar Laplacian and for elasticity, forward-only / symmetric sweeps, mesh vs lexicographic order;
- vertex-star (overlapping patch) multiplicative Schwarz as the smoother, for comparison.

    python benchmarks/tet_twogrid.py [--levels 2 5] [--checks] [--patch]

Needs PyAMG (`pip install pyamg`), for this comparison only: it is not a dependency of the package.
"""
import argparse
import itertools

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from pyamg.relaxation.relaxation import gauss_seidel

from contactmg import _core
from contactmg.generators_3d import box
from contactmg.hierarchy import MeshHierarchy

E, NU = 2000.0, 0.28


def to_scipy(B):
    n = B.shape[0]
    return sp.bsr_matrix((np.asarray(B.data), np.asarray(B.indices), np.asarray(B.indptr)), shape=(n, n)).tocsr()


def p1_assembly(points, cells, d):
    """Independent P1 assembly: Laplacian (d = 1) or elasticity (d = 3), numpy only."""
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    X = points[cells]                                    # c x 4 x 3
    J = (X[:, 1:] - X[:, :1]).transpose(0, 2, 1)         # columns: edges from vertex 0
    vol = np.abs(np.linalg.det(J)) / 6
    Ginv = np.linalg.inv(J)                              # rows: gradients of barycentrics 1..3
    G = np.concatenate([-Ginv.sum(1, keepdims=True), Ginv], 1)  # c x 4 x 3
    rows, cols, vals = [], [], []
    for a, b in itertools.product(range(4), repeat=2):
        ga, gb = G[:, a], G[:, b]
        if d == 1:
            rows.append(cells[:, a]); cols.append(cells[:, b]); vals.append(vol * (ga * gb).sum(1))
            continue
        for i, j in itertools.product(range(3), repeat=2):
            v = lam * ga[:, i] * gb[:, j] + mu * ga[:, j] * gb[:, i] + (mu * (ga * gb).sum(1) if i == j else 0)
            rows.append(3 * cells[:, a] + i); cols.append(3 * cells[:, b] + j); vals.append(vol * v)
    n = d * len(points)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def rigid_modes(points):
    x, y, z = points.T
    o, z0 = np.ones_like(x), np.zeros_like(x)
    modes = [(o, z0, z0), (z0, o, z0), (z0, z0, o), (-y, x, z0), (z0, -z, y), (z, z0, -x)]
    return np.array([np.column_stack(m).ravel() for m in modes]).T


class Cycle:
    """V(nu1, nu2) over a list of (A, P) with block Gauss-Seidel (blocksize b) or a patch smoother."""

    def __init__(self, As, Ps, b, nu1, nu2, symmetric_pre=False, smoother="gs", patches=None, kind="V"):
        self.kind = kind
        self.As, self.Ps, self.b, self.nu1, self.nu2 = As, Ps, b, nu1, nu2
        self.sym = symmetric_pre
        self.Absr = [A.tobsr(blocksize=(b, b)) if b > 1 else A for A in As]
        self.coarse = spla.splu(As[0].tocsc())
        self.smoother, self.patches = smoother, patches
        if smoother == "patch":
            self.local = []
            for A, pl in zip(As, patches):
                loc = []
                for dofs in pl:
                    loc.append((dofs, np.linalg.inv(A[dofs][:, dofs].toarray())))
                self.local.append(loc)

    def smooth(self, l, x, rhs, forward):
        if self.smoother == "gs":
            gauss_seidel(self.Absr[l], x, rhs, iterations=1, sweep="forward" if forward else "backward")
            return
        A = self.As[l]
        loc = self.local[l] if forward else self.local[l][::-1]
        for dofs, inv in loc:
            r = rhs[dofs] - A[dofs] @ x
            x[dofs] += inv @ r

    def vcycle(self, l, x, rhs, two_grid=False, kind=None):
        kind = kind or self.kind
        if l == 0:
            x[:] = self.coarse.solve(rhs)
            return
        for _ in range(self.nu1):
            self.smooth(l, x, rhs, True)
            if self.sym:
                self.smooth(l, x, rhs, False)
        for v in range(1 if kind == "V" else 2):
            r = rhs - self.As[l] @ x
            rc = self.Ps[l - 1].T @ r
            xc = np.zeros_like(rc)
            if two_grid:
                xc[:] = spla.spsolve(self.As[l - 1].tocsc(), rc)
            else:
                self.vcycle(l - 1, xc, rc, kind="V" if (kind == "F" and v == 1) else kind)
            x += self.Ps[l - 1] @ xc
            if two_grid:
                break
        for _ in range(self.nu2):
            self.smooth(l, x, rhs, False)
            if self.sym:
                self.smooth(l, x, rhs, True)

    def rate(self, iters=25, seed=0, two_grid=False):
        A = self.As[-1]
        x = np.random.default_rng(seed).standard_normal(A.shape[0])
        zero = np.zeros_like(x)
        norms = []
        for _ in range(iters):
            x /= np.sqrt(x @ (A @ x))
            self.vcycle(len(self.As) - 1, x, zero, two_grid=two_grid)
            norms.append(np.sqrt(x @ (A @ x)))
        return float(np.exp(np.mean(np.log(norms[-5:]))))


def vertex_stars(A_scalar_pattern, b):
    """Overlapping patches: every node with its direct neighbours (all b components)."""
    S = A_scalar_pattern.tocsr()
    out = []
    for i in range(S.shape[0]):
        nodes = S.indices[S.indptr[i]:S.indptr[i + 1]]
        out.append((b * nodes[:, None] + np.arange(b)).ravel())
    return out


def build(cell, levels, lexicographic):
    h = MeshHierarchy.build(box(2, 2, 2, cell=cell), levels)
    out = []
    for lvl, m in enumerate(h.meshes):
        free = m.points[:, 2] > 1e-12
        if lexicographic:  # renumber nodes by (x, y, z)
            order = np.lexsort((m.points[:, 2], m.points[:, 1], m.points[:, 0]))
        else:
            order = np.arange(m.num_points)
        order = order[free[order]]
        out.append((m, order))
    return h, out


def checks(h):
    """Independent verification of the project's matrices and transfers on the Kuhn cube."""
    for l in range(1, h.levels):
        mf, mc = h.meshes[l], h.meshes[l - 1]
        Af = to_scipy(_core.assemble_elasticity(mf.points, mf.cells, mf.cell_type, E, NU))
        Ac = to_scipy(_core.assemble_elasticity(mc.points, mc.cells, mc.cell_type, E, NU))
        if mf.cell_type == "tetra":
            Aind = p1_assembly(mf.points, mf.cells, 3)
            err_assembly = abs(Af - Aind).max() / abs(Aind).max()
        else:
            err_assembly = float("nan")
        Ps = h.transfers[l - 1].matrix()
        P = sp.kron(Ps, sp.eye(3)).tocsr()
        err_galerkin = abs(P.T @ Af @ P - Ac).max() / abs(Ac).max()
        err_linear = abs(Ps @ mc.points - mf.points).max()
        err_rbm = abs(P @ rigid_modes(mc.points) - rigid_modes(mf.points)).max()
        kernel = abs(Af @ rigid_modes(mf.points)).max() / abs(Af).max()
        # diagonal block inverse as the smoother uses it: D_i^{-1} D_i = I
        D = [Af[3 * i:3 * i + 3, 3 * i:3 * i + 3].toarray() for i in range(0, mf.num_points, max(1, mf.num_points // 50))]
        print(f"  L{l + 1}: |A - A_numpy| {err_assembly:.1e}  |P^T A P - A_coarse| {err_galerkin:.1e}  "
              f"|P x_c - x_f| {err_linear:.1e}  |P rbm_c - rbm_f| {err_rbm:.1e}  |A rbm| {kernel:.1e}  "
              f"min eig of diag blocks {min(np.linalg.eigvalsh(d).min() for d in D):.3g}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 5])
    ap.add_argument("--cell", default="tetra")
    ap.add_argument("--patch", action="store_true", help="also the vertex-star smoother (slow, python)")
    ap.add_argument("--checks", action="store_true")
    a = ap.parse_args()
    L0, L1 = a.levels
    for lex in (False, True):
        h, lv = build(a.cell, L1, lex)
        if a.checks and not lex:
            checks(h)
        for problem in ("laplace", "elasticity"):
            b = 1 if problem == "laplace" else 3
            As, Ps = [], []
            for l, (m, order) in enumerate(lv):
                if problem == "laplace":
                    A = p1_assembly(m.points, m.cells, 1) if m.cell_type == "tetra" else None
                    if A is None:
                        continue
                else:
                    A = to_scipy(_core.assemble_elasticity(m.points, m.cells, m.cell_type, E, NU))
                dofs = (b * order[:, None] + np.arange(b)).ravel()
                As.append(A[dofs][:, dofs].tocsr())
                if l > 0:
                    _, oc = lv[l - 1]
                    Pfull = sp.kron(h.transfers[l - 1].matrix(), sp.eye(b)).tocsr()
                    dc = (b * oc[:, None] + np.arange(b)).ravel()
                    Ps.append(Pfull[dofs][:, dc].tocsr())
            if not As:
                continue
            for L in range(L0, L1 + 1):
                row = []
                for (n1, n2, sym) in ((1, 1, False), (3, 3, False), (3, 3, True)):
                    c = Cycle(As[:L], Ps[:L - 1], b, n1, n2, symmetric_pre=sym)
                    tg = c.rate(two_grid=True, iters=20) if L <= 5 else float("nan")
                    row.append(f"V({n1},{n2}){'sym' if sym else ''} {c.rate():.3f} TG {tg:.3f}")
                # F(3,3) with the fine level visiting its coarse level twice (the textbook F-cycle)
                row.append(f"F(3,3) {Cycle(As[:L], Ps[:L - 1], b, 3, 3, kind='F').rate():.3f}")
                if a.patch and L <= 4:
                    pats = [vertex_stars(abs(A[::b, ::b]) if b > 1 else A, b) for A in As[:L]]
                    c = Cycle(As[:L], Ps[:L - 1], b, 1, 1, smoother="patch", patches=pats)
                    row.append(f"star V(1,1) {c.rate(iters=15):.3f}")
                print(f"{'lex' if lex else 'mesh'} {problem:10} L{L} dofs {As[L - 1].shape[0]:7d}  " + "  ".join(row),
                      flush=True)


if __name__ == "__main__":
    main()
