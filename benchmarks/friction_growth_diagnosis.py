"""Where Algorithm 2's cycle growth on adaptive Hertz level 11 at F >= 0.7 comes from, and whether a
Petrov-Galerkin coarse problem (the coarse correction seeing the sliding rows' F r_n coupling)
would remove it (issue 11, sixth part; docs/history/adaptive.md).

    python benchmarks/friction_growth_diagnosis.py histories [--levels 7 9 11] [--frictions ...]
    python benchmarks/friction_growth_diagnosis.py corerate  [--levels 7 9 11] [--frictions ...]
    python benchmarks/friction_growth_diagnosis.py twogrid   [--levels 7 9 11] [--frictions ...]

histories  Algorithm 2 (F(3,3), tol 1e-11, from u = 0, 1 thread) on the adaptive levels: the cycle
           of the last rebuild of the coarse problem (the contact state -- truncation -- changed for
           the last time; result.history["rebuilt"]) splits the count into settling and settled
           cycles; the settled phase's per-cycle contraction is the geometric mean of its
           correction ratios. Saves the converged solutions to out/fg/ for the other two modes.
           With CMG_EXPERIMENT_NO_ANDERSON=1 on a build with
           benchmarks/results/no_anderson_experiment_smooth5.patch applied: the plain cycle.
corerate   the core's fixed-state cycle map near the solution (from (1 - 1e-6) u*, tol 1e-30, 16
           cycles): ratios of successive corrections (power iteration on the cycle map with the
           state fixed). Meaningful with the mixing off (the patch above).
twogrid    a scipy model of the settled cycle as a linear map on the error (contact frames, the
           coulomb_newton_diagnosis.py assembly): fine = 3 forward / 3 backward sweeps of the
           linearized nodal block Gauss-Seidel on the Coulomb Jacobian J of the settled state
           (active normals and sticking tangentials fixed, sliding tangentials solve their row
           (K_T - sign F K_n) e = ..., non-symmetric; omega = 1.3 on nodes without contact, 1 at
           contact nodes; natural node order), coarse = exact solve on level L-1 with the truncated
           prolongation P~ and (a) the symmetric Galerkin matrix P~^T K P~ (the frozen bound F |s_n|:
           today's), (b) the Petrov-Galerkin P~^T J P~ = P~^T K P~ + P~^T N K P~ (N = -sign F e_T e_n^T
           of the k sliding nodes: a rank-k term). Both restrict the J-residual (the frozen bound's
           coarse right-hand side r - sign F r_n(u) e_T is J e). Spectral radii by ARPACK (eigs,
           largest magnitude) on the error map; also the smoother alone (L <= 7) and the two-grid
           map without friction coupling (J replaced by K: the sliding rows as K rows, "Tresca-like").
modes      where the slowest mode of the frozen, the PG and the smoother-alone maps lives, and
           Gauss-Seidel on the sliding chain alone (the J block of the sliding tangentials).
chain      the two-grid maps with an exact solve of that J block after every sweep.
threegrid  level L-1 smoothed instead of solved (L-2 exact): the PG term on L-1 only against
           everywhere and against today's symmetric levels.

Measured 2026-12-03 on branch smooth5 (1 thread): benchmarks/results/friction_growth_diagnosis_smooth6.txt,
docs/history/adaptive.md "Issue 11, sixth part".
"""
import argparse
import json
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

sys.path.insert(0, os.path.dirname(__file__))

from cycle_growth import adaptive_hierarchy  # noqa: E402
from contactmg.hertz import hertz_problem_on  # noqa: E402

OUT = os.path.join("out", "fg")


def sol_path(L, F):
    return os.path.join(OUT, f"sol_L{L}_F{F:g}.npy")


def split_history(h):
    c = np.asarray(h["correction_norm"], float)
    reb = np.asarray(h["rebuilt"], bool)
    n = len(c)
    last = int(np.nonzero(reb)[0][-1]) + 1 if reb.any() else 0  # 1-based cycle of the last rebuild
    settled = n - last
    # contraction in the settled phase: correction ratios of the cycles after the last rebuild
    # (the first settled cycle's ratio is taken against the last settling cycle's correction)
    if settled >= 2:
        seg = c[last - 1:] if last >= 1 else c
        rate = float((seg[-1] / seg[0]) ** (1.0 / (len(seg) - 1)))
        ratios = [float(x) for x in seg[1:] / seg[:-1]]
    else:
        rate, ratios = float("nan"), []
    return n, last, settled, rate, ratios


def histories(a):
    from contactmg.checks import contact_conditions
    os.makedirs(OUT, exist_ok=True)
    H = adaptive_hierarchy(11)
    rows = []
    tag = "no Anderson" if os.environ.get("CMG_EXPERIMENT_NO_ANDERSON") else "default (Anderson)"
    print(f"Algorithm 2 histories, {tag}: settling = cycles up to the last rebuild (contact state's last change)")
    print("| L | F | cycles | settling | settled | settled rate | state (active/stick/slip) | settled ratios |")
    print("|---|---|---|---|---|---|---|---|")
    for L in a.levels:
        for F in a.frictions:
            if L != 9 and F > 8:
                continue
            p = hertz_problem_on(H.truncated(L), F)
            t0 = time.perf_counter()
            r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1)
            sec = time.perf_counter() - t0
            v = float(contact_conditions(p, r)["max"])
            n, last, settled, rate, ratios = split_history(r.history)
            st = (int(r.history["active"][-1]), int(r.history["stick"][-1]), int(r.history["slip"][-1]))
            ok = bool(r.converged) and v <= 1e-8
            if ok and not os.environ.get("CMG_EXPERIMENT_NO_ANDERSON"):
                np.save(sol_path(L, F), np.asarray(r.displacement))
            rows.append({"level": L, "F": F, "cycles": n, "converged": ok, "violation": v, "settling": last,
                         "settled": settled, "settled_rate": rate, "state": st, "seconds": sec,
                         "history": {k: [float(x) for x in r.history[k]] for k in
                                     ("correction_norm", "active", "stick", "slip", "rebuilt")}})
            print(f"| {L} | {F:g} | {n}{'' if ok else '!'} | {last} | {settled} | {rate:.3f} | {st[0]}/{st[1]}/{st[2]} | "
                  + " ".join(f"{x:.2f}" for x in ratios) + " |", flush=True)
    return {"mode": "histories", "anderson": tag, "runs": rows}


def corerate(a):
    H = adaptive_hierarchy(11)
    rows = []
    print(f"fixed-state cycle map near u* (from (1 - 1e-6) u*, {a.steps} cycles, tol 1e-30): correction ratios, "
          f"{'no Anderson' if os.environ.get('CMG_EXPERIMENT_NO_ANDERSON') else 'default (Anderson)'}; "
          "rate = geometric mean from cycle 4 to the last above 30 x the round-off floor")
    for L in a.levels:
        for F in a.frictions:
            if not os.path.exists(sol_path(L, F)):
                continue
            p = hertz_problem_on(H.truncated(L), F)
            u = np.load(sol_path(L, F))
            recs = []
            p.solve("nmg", tol=1e-30, max_cycles=a.steps, threads=1, u0=u * (1 - 1e-6),
                    progress=lambda rec: recs.append(rec))
            c = np.array([float(x["correction_norm"]) for x in recs])
            states = sorted({(int(x["active"]), int(x["stick"]), int(x["slip"])) for x in recs})
            good = np.nonzero(c > 30 * c.min())[0]  # above the round-off floor (|u|_A = 0.16)
            k1 = int(good[-1]) if len(good) else 0
            k0 = min(3, k1)
            rate = float((c[k1] / c[k0]) ** (1 / (k1 - k0))) if k1 > k0 else float("nan")
            rows.append({"level": L, "F": F, "corrections": c.tolist(), "states": states, "rate": rate,
                         "window": [k0 + 1, k1 + 1]})
            print(f"L{L} F={F:g}: rate {rate:.3f} over cycles {k0 + 1}-{k1 + 1}, states {states}; corrections "
                  + " ".join(f"{x:.1e}" for x in c), flush=True)
    return {"mode": "corerate", "anderson_off": bool(os.environ.get("CMG_EXPERIMENT_NO_ANDERSON")), "runs": rows}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["histories", "corerate", "twogrid", "modes", "chain", "threegrid"])
    ap.add_argument("--levels", type=int, nargs="+", default=[7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.4, 0.7, 2.0, 5.0, 8.0, 12.0, 20.0])
    ap.add_argument("--steps", type=int, default=16)
    ap.add_argument("--json")
    a = ap.parse_args()
    t0 = time.perf_counter()
    out = {"histories": histories, "corerate": corerate, "twogrid": twogrid, "modes": modes, "chain": chain, "threegrid": threegrid}[a.mode](a)
    print(f"({time.perf_counter() - t0:.0f} s)")
    if a.json:
        os.makedirs(os.path.dirname(a.json) or ".", exist_ok=True)
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


def _block_sor_factor(Kf, node_of, omega_of, lower):
    """splu of D / omega + L (lower) or D / omega + U: the block Gauss-Seidel sweep's matrix on the
    free dofs (node blocks of 1 or 2 dofs; a node's dofs are consecutive)."""
    C = Kf.tocoo()
    ni, nj = node_of[C.row], node_of[C.col]
    same = ni == nj
    keep = same | ((nj < ni) if lower else (nj > ni))
    w = np.where(same, 1.0 / omega_of[C.row], 1.0)
    M = sp.csc_matrix((C.data[keep] * w[keep], (C.row[keep], C.col[keep])), shape=Kf.shape)
    return spla.splu(M, permc_spec="NATURAL", diag_pivot_thresh=0.0)


class TwoGrid:
    """The settled cycle's error map on the free dofs of level L's state (see the module doc)."""

    def __init__(self, H, L, F, u, omega=1.3, nu=3):
        from coulomb_newton_diagnosis import coulomb_state, hertz_system
        Hl = H.truncated(L)
        p = hertz_problem_on(Hl, F)
        S = hertz_system(p)
        K, n, t = S["K"], S["n"], S["t"]
        x = S["D"] * np.asarray(u).ravel()
        lam, z, active, stick, slip = coulomb_state(S, F, x)
        self.counts = (int(active.sum()), int(stick.sum()), int(slip.sum()))
        N = K.shape[0]
        trunc = S["fixed"].copy()
        trunc[n[active]] = True
        trunc[t[stick]] = True
        E = sp.csr_matrix((-np.sign(z[slip]) * F, (t[slip], n[slip])), shape=(N, N))
        J = (K + E @ K).tocsr()
        fr = np.nonzero(~trunc)[0]
        self.nfree = len(fr)
        self.fr = fr
        Kf, Jf = K[fr][:, fr].tocsr(), J[fr][:, fr].tocsr()
        node_of = fr // 2
        contact = np.zeros(N // 2, bool)
        contact[np.asarray(p.contact.nodes)] = True
        omega_of = np.where(contact[node_of], 1.0, omega)
        Pn = Hl.transfers[-1].matrix().tocsr()
        P = sp.kron(Pn, sp.identity(2), format="csr")
        P = (sp.diags(S["D"]) @ P).tocsr()
        # coarse Dirichlet dofs: those whose injected fine dof (a row of P with one entry 1) is fixed
        Pc = P.tocoo()
        rowcount = np.bincount(Pc.row, minlength=N)
        inj = (rowcount[Pc.row] == 1) & np.isclose(np.abs(Pc.data), 1.0)
        cfixed = np.zeros(P.shape[1], bool)
        cfixed[Pc.col[inj]] = S["fixed"][Pc.row[inj]]
        ckeep = np.nonzero(~cfixed)[0]
        Pt = P[fr][:, ckeep].tocsc()
        nonempty = np.nonzero(np.diff(Pt.indptr) > 0)[0]
        Pt = Pt[:, nonempty].tocsr()
        self.ckeep = ckeep[nonempty]  # level L-1 dofs of the coarse space
        self.Hl, self.omega = Hl, omega
        self.ncoarse = Pt.shape[1]
        self.Kf, self.Jf, self.Pt, self.PtT = Kf, Jf, Pt, Pt.T.tocsr()
        self.nu = nu
        self.fwd = {m: _block_sor_factor(A, node_of, omega_of, True) for m, A in (("J", Jf), ("K", Kf))}
        self.bwd = {m: _block_sor_factor(A, node_of, omega_of, False) for m, A in (("J", Jf), ("K", Kf))}
        KP = (Kf @ Pt).tocsr()
        self.Ac = {"galerkin": spla.splu((self.PtT @ KP).tocsc()),
                   "petrov": spla.splu((self.PtT @ (Jf @ Pt)).tocsc())}
        self.rank = int(slip.sum())
        # the PG term P~^T N K P~: rows of the coarse dofs whose basis functions touch a sliding tangential
        D = (self.PtT @ (Jf - Kf) @ Pt).tocsr()
        D.eliminate_zeros()
        self.pg_rows, self.pg_nnz = int(np.count_nonzero(np.diff(D.indptr))), int(D.nnz)
        self.Ac_nnz = int((self.PtT @ KP).nnz)
        self.slip_x = p.mesh.points[np.asarray(p.contact.nodes)[slip], 0] if slip.any() else np.array([])

    def three_grid(self, top="galerkin", below="galerkin"):
        """Level L-1 as a smoothed level instead of an exact solve: its matrix is `top` (the
        symmetric Galerkin or the PG one), 3 forward / 3 backward block-SOR sweeps on it (omega
        on every node; the core keeps 1 on bounded rows) around an exact solve on level L-2 with
        P2^T A P2, A = the symmetric (`below` = "galerkin") or the PG (`below` = "petrov") level
        L-1 matrix: the restricted PG term (PG on L-1 only) is top = petrov, below = galerkin."""
        Pn2 = self.Hl.transfers[-2].matrix().tocsr()
        P2 = sp.kron(Pn2, sp.identity(2), format="csr")[self.ckeep]
        Pc = P2.tocoo()
        rowcount = np.bincount(Pc.row, minlength=P2.shape[0])
        inj = (rowcount[Pc.row] == 1) & np.isclose(np.abs(Pc.data), 1.0)
        has_injected_row = np.zeros(P2.shape[1], bool)
        has_injected_row[Pc.col[inj]] = True
        P2 = P2.tocsc()
        cols = np.nonzero((np.diff(P2.indptr) > 0) & has_injected_row)[0]  # L-2 dofs injected into a kept L-1 dof
        P2 = P2[:, cols].tocsr()
        A1 = {"galerkin": (self.PtT @ self.Kf @ self.Pt).tocsr(), "petrov": (self.PtT @ self.Jf @ self.Pt).tocsr()}
        At = A1[top]
        node_of = self.ckeep // 2
        om = np.full(len(node_of), self.omega)
        fw, bw = _block_sor_factor(At, node_of, om, True), _block_sor_factor(At, node_of, om, False)
        A2 = spla.splu((P2.T @ A1[below] @ P2).tocsc())
        P2T = P2.T.tocsr()

        def coarse_solve(rc):
            x = np.zeros_like(rc)
            for _ in range(self.nu):
                x += fw.solve(rc - At @ x)
            x += P2 @ A2.solve(P2T @ (rc - At @ x))
            for _ in range(self.nu):
                x += bw.solve(rc - At @ x)
            return x
        return coarse_solve

    def chain_solve(self, e):
        """An exact solve of the sliding tangentials' J rows, every other component kept (a block
        subspace correction of the whole sliding chain)."""
        if not hasattr(self, "_chain"):
            sl = np.nonzero(self.Jf.diagonal() != self.Kf.diagonal())[0]
            self._chain = (sl, spla.splu(self.Jf[sl][:, sl].tocsc()) if len(sl) else None)
        sl, lu = self._chain
        if lu is not None:
            e = e.copy()
            e[sl] -= lu.solve((self.Jf[sl] @ e))
        return e

    def apply(self, e, coarse="galerkin", op="J", smooth=True, chain=False):
        A = self.Jf if op == "J" else self.Kf
        if smooth:
            for _ in range(self.nu):
                e = e - self.fwd[op].solve(A @ e)
                if chain:
                    e = self.chain_solve(e)
        if callable(coarse):
            e = e - self.Pt @ coarse(self.PtT @ (A @ e))
        elif coarse:
            ac = self.Ac[coarse] if op == "J" else self.Ac["galerkin"]
            e = e - self.Pt @ ac.solve(self.PtT @ (A @ e))
        if smooth:
            for _ in range(self.nu):
                e = e - self.bwd[op].solve(A @ e)
                if chain:
                    e = self.chain_solve(e)
        return e

    def radius(self, k=4, **kw):
        n = self.nfree
        T = spla.LinearOperator((n, n), matvec=lambda v: self.apply(np.asarray(v).ravel(), **kw), dtype=float)
        rng = np.random.default_rng(1)
        ev = spla.eigs(T, k=k, which="LM", tol=1e-5, ncv=max(2 * k + 1, 20), v0=rng.standard_normal(n),
                       maxiter=2000, return_eigenvectors=False)
        ev = ev[np.argsort(-np.abs(ev))]
        return float(abs(ev[0])), [complex(v) for v in ev]


def settled_models(a, H):
    """(L, F, the two-grid model of the stored solution, the time before it was built) for every
    level and friction of the arguments whose solution has been stored (sol_path)."""
    for L in a.levels:
        for F in a.frictions:
            if os.path.exists(sol_path(L, F)):
                t0 = time.perf_counter()
                yield L, F, TwoGrid(H, L, F, np.load(sol_path(L, F))), t0


def modes(a):
    """Where the slowest mode of each two-grid map lives: |eigenvalue|, the energy share of its 20
    most energetic dofs and their nodes' coordinates (the sliding nodes' x for comparison)."""
    H = adaptive_hierarchy(11)
    rows = []
    for L, F, T, t0 in settled_models(a, H):
        pts = hertz_problem_on(H.truncated(L), F).mesh.points
        print(f"L{L} F={F:g}: {T.rank} sliding nodes at x = {np.round(np.sort(T.slip_x), 4).tolist()}", flush=True)
        # the sliding chain alone: forward Gauss-Seidel on the J rows of the sliding tangentials,
        # every other error component zero (dense, k x k), and the same with the K rows
        sl = np.nonzero(T.Jf.diagonal() != T.Kf.diagonal())[0]
        for name, A in (("J", T.Jf), ("K", T.Kf)):
            Ass = A[sl][:, sl].toarray()
            Mlow = np.tril(Ass)
            G = np.eye(len(sl)) - np.linalg.solve(Mlow, Ass)
            rho = float(max(abs(np.linalg.eigvals(G)))) if len(sl) else float("nan")
            lam = np.linalg.eigvals(Ass) if len(sl) else np.array([np.nan])
            print(f"  sliding chain alone ({len(sl)} tangentials), Gauss-Seidel on its {name} rows: radius {rho:.3f}, "
                  f"eigenvalues of the block: min Re {lam.real.min():.3g}, max |Im| {abs(lam.imag).max():.3g}", flush=True)
            rows.append({"level": L, "F": F, "map": f"chain GS {name}", "radius": rho})
        for c in ("galerkin", "petrov", None) if L <= 9 else ("galerkin", "petrov"):
            n = T.nfree
            op = spla.LinearOperator((n, n), matvec=lambda v: T.apply(np.asarray(v).ravel(), coarse=c), dtype=float)
            w, V = spla.eigs(op, k=2, which="LM", tol=1e-5, ncv=20, maxiter=3000)
            i = int(np.argmax(abs(w)))
            v = V[:, i]
            en = np.abs(np.conj(v) * (T.Kf @ v))
            en /= en.sum()
            top = np.argsort(-en)[:20]
            nodes = np.unique(T.fr[top] // 2)
            xs, ys = np.round(np.unique(pts[nodes, 0]), 4).tolist(), np.round(np.unique(pts[nodes, 1]), 4).tolist()
            name = {"galerkin": "frozen (a)", "petrov": "Petrov-Galerkin (b)", None: "smoother alone"}[c]
            print(f"  {name}: |eig| {abs(w[i]):.3f} ({w[i].real:.3f}{w[i].imag:+.3f}i), top-20 dofs hold {en[top].sum():.2f} "
                  f"of the energy, at x = {xs}, y = {ys} ({time.perf_counter() - t0:.0f} s)", flush=True)
            rows.append({"level": L, "F": F, "map": name, "eig": [float(w[i].real), float(w[i].imag)],
                         "top20_energy": float(en[top].sum()), "x": xs, "y": ys})
    return {"mode": "modes", "runs": rows}


def chain(a):
    """The two-grid maps with an exact solve of the sliding chain's J block after every sweep."""
    H = adaptive_hierarchy(11)
    rows = []
    print("two-grid model + an exact sliding-chain solve after every sweep: spectral radii")
    print("| L | F | sliding | frozen (a) | frozen + chain | PG (b) + chain |")
    print("|---|---|---|---|---|---|")
    for L, F, T, t0 in settled_models(a, H):
        r = {"level": L, "F": F, "sliding": T.rank}
        r["frozen"], _ = T.radius(coarse="galerkin")
        r["frozen_chain"], _ = T.radius(coarse="galerkin", chain=True)
        r["petrov_chain"], _ = T.radius(coarse="petrov", chain=True)
        rows.append(r)
        print(f"| {L} | {F:g} | {T.rank} | {r['frozen']:.3f} | {r['frozen_chain']:.3f} | {r['petrov_chain']:.3f} |", flush=True)
    return {"mode": "chain", "runs": rows}


def threegrid(a):
    """Three-grid model: L, L-1 smoothed (3 / 3 block SOR on its matrix), L-2 exact."""
    H = adaptive_hierarchy(11)
    rows = []
    print("three-grid model (L fine, L-1 smoothed, L-2 exact): spectral radii; level L-1 matrix / level L-2 from")
    print("| L | F | sliding | sym / sym (today's) | PG / sym (PG on L-1 only) | PG / PG |")
    print("|---|---|---|---|---|---|")
    for L, F, T, t0 in settled_models(a, H):
        r = {"level": L, "F": F, "sliding": T.rank}
        for key, (top, below) in (("sym_sym", ("galerkin", "galerkin")), ("pg_sym", ("petrov", "galerkin")),
                                  ("pg_pg", ("petrov", "petrov"))):
            r[key], _ = T.radius(coarse=T.three_grid(top, below))
        rows.append(r)
        print(f"| {L} | {F:g} | {T.rank} | {r['sym_sym']:.3f} | {r['pg_sym']:.3f} | {r['pg_pg']:.3f} |", flush=True)
    return {"mode": "threegrid", "runs": rows}


def twogrid(a):
    H = adaptive_hierarchy(11)
    rows = []
    print("two-grid model of the settled cycle (exact coarse solve on L-1), spectral radii of the error map")
    print("| L | F | state a/st/sl | free / coarse dofs | Tresca-like (no F r_n) | frozen (a) | Petrov-Galerkin (b) | "
          "smoother alone | top eigenvalues (a) | PG term: coarse rows / nnz (of A_c nnz) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for L, F, T, t0 in settled_models(a, H):
        res = {"level": L, "F": F, "state": T.counts, "free": T.nfree, "coarse": T.ncoarse}
        res["tresca"], _ = T.radius(op="K")
        res["frozen"], ev_a = T.radius(coarse="galerkin")
        res["petrov"], ev_b = T.radius(coarse="petrov")
        res["smoother"], _ = T.radius(coarse=None) if L <= 7 else (float("nan"), None)
        res.update(eig_frozen=[[v.real, v.imag] for v in ev_a], eig_petrov=[[v.real, v.imag] for v in ev_b],
                   pg_rows=T.pg_rows, pg_nnz=T.pg_nnz, Ac_nnz=T.Ac_nnz, rank=T.rank,
                   slip_x=[float(v) for v in T.slip_x], seconds=time.perf_counter() - t0)
        rows.append(res)
        print(f"| {L} | {F:g} | {T.counts[0]}/{T.counts[1]}/{T.counts[2]} | {T.nfree} / {T.ncoarse} | {res['tresca']:.3f} | "
              f"{res['frozen']:.3f} | {res['petrov']:.3f} | {res['smoother']:.3f} | "
              + ", ".join(f"{v.real:.3f}{v.imag:+.3f}i" for v in ev_a[:3])
              + f" | {T.pg_rows} / {T.pg_nnz} ({T.Ac_nnz}) |", flush=True)
    return {"mode": "twogrid", "runs": rows}


if __name__ == "__main__":
    main()
