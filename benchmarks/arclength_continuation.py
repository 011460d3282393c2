"""Arc-length continuation in (x, F) of the discrete Coulomb problem on the adaptive Hertz hierarchy
(issue 11, ninth part; docs/history/adaptive.md): does the solution branch through the F = 20
Newton solution on level 11 turn back (a limit point in F) or reach F = 40?

    python benchmarks/arclength_continuation.py [--level 11] [--start out/cache/nw_F20.npy]
        [--from-F 20] [--to-F 40] [--min-F 0.5] [--max-pieces 400] [--deadline-seconds 3000]
        [--save-end PATH.npy] [--json PATH]
    python benchmarks/arclength_continuation.py --level 9 --from-F 20      # start: Algorithm 2 at F

The runs of the ninth part (one thread):
    python benchmarks/arclength_continuation.py --level 9 --verify-end --json benchmarks/results/arclength_continuation_L9_F20_up_cont1.json
    python benchmarks/arclength_continuation.py --level 10 --verify-end --json benchmarks/results/arclength_continuation_L10_F20_up_cont1.json
    python benchmarks/arclength_continuation.py --level 11 --max-pieces 20000 --deadline-seconds 2400 --verify-end \
        --save-end out/cache/ac_L11_F40.npy --json benchmarks/results/arclength_continuation_L11_F20_up_cont1.json
    python benchmarks/arclength_continuation.py --level 11 --min-F 0.4 --down --max-pieces 20000 --check-every 50 \
        --compare-alg2 --json benchmarks/results/arclength_continuation_L11_F20_down_cont1.json
    python benchmarks/arclength_continuation.py --level 11 --start "" --from-F 0.4 --max-pieces 20000 --check-every 50 \
        --compare out/cache/ac_L11_F40.npy out/cache/nw_F20.npy --json benchmarks/results/arclength_continuation_L11_F04_up_cont1.json
    python benchmarks/coulomb_newton_diagnosis.py rate --level 11 --friction 40 --start out/cache/ac_L11_F40.npy --steps 30 \
        --json benchmarks/results/arclength_continuation_L11_F40_rate_cont1.json

The problem in the Hertz plane obstacle's contact frames (coulomb_newton_diagnosis.hertz_system:
x = D u, r = b - K x, normal dof 2c+1, tangential 2c) and its Alart-Curnier residual phi(x, F)
(coulomb_newton_diagnosis.ac_residual). phi is piecewise smooth: on a fixed state of the contact
nodes (free / stick / slip with the sign s of r_T + c_T x_T) phi = 0 is the linear system
M_S(F) x = rhs_S(F) of coulomb_newton_diagnosis.newton_target (rows x_n = g for active nodes,
x_T = 0 for sticking ones, r_T - s F r_n = 0 for sliding ones, K rows elsewhere). M_S and rhs_S are
affine in F (only the sliding rows depend on it), so on one state the solution set in (x, F) is the
graph x_S(F) = M_S(F)^-1 rhs_S(F) over the F where M_S is regular: F is a monotone parameter of the
curve there, and the tangent of the bordered system [[G_x, G_F], [t^T]] is (x_S'(F), 1) up to its
orientation, with M_S x_S' = (-s r_n at the sliding rows).  A smooth limit point (dF/ds = 0 at a
regular G_x) cannot occur inside a piece; dF/ds can change sign only where the state changes (a
kink of the curve), and it does so where sign det M_S changes across the kink (the bordered
determinant keeps its sign along an oriented path).  So the pseudo-arclength continuation is done
exactly, piece by piece, with no predictor-corrector:

- one sparse LU (scipy.sparse.linalg.splu) of a base matrix A (the starting state's M_S(0)) and, for
  every row index whose row differs from A's in the current state (changed nodes and the sliding
  rows), the column A^-1 e_i (cached over the whole run); M_S(F) = A + U W(F)^T with W affine in F,
  and x_S(F) on the contact dofs and their stiffness neighbours J by the Sherman-Morrison-Woodbury
  formula (a capacitance matrix of the size m of the row changes, m x m dense);  refactored at the
  current state when the rows of changed nodes exceed --max-rank;
- on a piece, the state's inequalities as functions of F (in force units, >= 0 on the piece):
  free: c_n (g - x_n); stick: r_n and F r_n - |r_T|; slip s: r_n and c_T s x_T; marched in F with a
  step limited by their linear extrapolation, the first crossing bisected to 1e-13 F;
- at a crossing, every other state of the crossing node is tried on both sides of the breakpoint
  (F_b +- 1e-6 F_b): the continuation is the one (state, direction) whose inequalities all hold;
  if its direction is opposite to the incoming one the branch turns back there (a fold at a kink);
  none or several valid: the path ends (reported);
- sign det M_S = sign det A (from the LU's diagonal and permutations) times sign det of the
  capacitance matrix, recorded on both sides of every breakpoint; the full x_S(F) (one solve with A)
  and |phi(x, F)| checked at the start, every --check-every pieces, at folds and at the end.

Measured 2026-12-03 (branch cont1; docs/history/adaptive.md, "Issue 11, ninth part"): on L11 the branch
through the F = 20 Newton solution turns back first at F = 20.6397 (a kink: node 394 free -> slip,
sign det M_S + -> -), zig-zags through 84 turns (all kinks) in F = 17.02-21.14 and then rises to
F = 40 (151 pieces, 89 s): a solution at F = 40 (489 / 481 / 8 active / stick / slip, |phi| 5.9e-10,
contact_conditions 6.1e-9) from which Algorithm 2 departs (3.2 % away after 200 cycles). The branch
from Algorithm 2's F = 0.4 solution is the same one (506 pieces, the same F = 40 solution to 1.3e-10).
L9 / L10: from F = 20 to 40 with no turn, at Algorithm 2's own F = 40 solution.

    --compare-alg2   at the end point: Algorithm 2 from u = 0 at the end F and its distance
"""
import argparse
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

sys.path.insert(0, os.path.dirname(__file__))

from bench_json import write_json  # noqa: E402
from coulomb_newton_diagnosis import ac_residual, coulomb_state, hertz_system, hierarchy  # noqa: E402

FREE, STICK, SLIP_P, SLIP_M = 0, 1, 2, 3
NAMES = {FREE: "free", STICK: "stick", SLIP_P: "slip+", SLIP_M: "slip-"}


def state_of(S, F, x):
    """The state codes of the contact nodes at x (Alart-Curnier arguments, as newton_target)."""
    lam, z, active, stick, slip = coulomb_state(S, F, x)
    st = np.full(len(S["g"]), FREE)
    st[stick] = STICK
    st[slip & (z > 0)] = SLIP_P
    st[slip & (z <= 0)] = SLIP_M
    return st


def counts(st):
    return int((st != FREE).sum()), int((st == STICK).sum()), int(((st == SLIP_P) | (st == SLIP_M)).sum())


def _perm_sign(p):
    p = np.asarray(p).copy()
    seen = np.zeros(len(p), bool)
    parity = 0
    for i in range(len(p)):
        if not seen[i]:
            j, L = i, 0
            while not seen[j]:
                seen[j] = True
                j = p[j]
                L += 1
            parity += L - 1
    return -1 if parity % 2 else 1


class PiecewisePath:
    def __init__(self, S, base_state, max_rank=200, verbose=True):
        self.S, self.verbose, self.max_rank = S, verbose, max_rank
        K = S["K"]
        self.N = K.shape[0]
        self.K = K
        self.c = K.diagonal()
        n, t = S["n"], S["t"]
        fixed = S["fixed"]
        # contact nodes with a Dirichlet component are not tracked (left in their base rows)
        self.tracked = ~(fixed[n] | fixed[t])
        cdofs = np.unique(np.concatenate([n, t]))
        Kc = K[cdofs]
        self.J = np.unique(np.concatenate([cdofs, Kc.indices]))
        self.loc = -np.ones(self.N, int)
        self.loc[self.J] = np.arange(len(self.J))
        self.KnJ = K[n][:, self.J].tocsr()
        self.KtJ = K[t][:, self.J].tocsr()
        self.lu_seconds, self.solves, self.factorizations = 0.0, 0, 0
        self.solve_seconds = 0.0
        self.factor(base_state)

    # --- base factorization -------------------------------------------------------------------
    def factor(self, base_state):
        S, K, n, t = self.S, self.K, self.S["n"], self.S["t"]
        self.base = base_state.copy()
        ident = self.S["fixed"].copy()
        ident[n[base_state != FREE]] = True
        ident[t[base_state == STICK]] = True
        self.ident = ident
        A = (sp.diags((~ident).astype(float)) @ K + sp.diags(ident.astype(float))).tocsc()
        rhs = S["b"].copy()
        rhs[S["fixed"]] = S["fixed_values"][S["fixed"]]
        act = base_state != FREE
        rhs[n[act]] = S["g"][act]
        rhs[t[base_state == STICK]] = 0
        self.rhs_base = rhs
        t0 = time.perf_counter()
        self.lu = spla.splu(A)
        self.lu_seconds += time.perf_counter() - t0
        self.factorizations += 1
        d = self.lu.U.diagonal()
        self.det_sign_A = int(np.prod(np.sign(d))) * _perm_sign(self.lu.perm_r) * _perm_sign(self.lu.perm_c)
        self.y = self._solve(rhs)
        self.yJ = self.y[self.J]
        self.cols = {}
        self.state = None
        if self.verbose:
            print(f"  factorization {self.factorizations}: {time.perf_counter() - t0:.1f} s, sign det A {self.det_sign_A}",
                  flush=True)

    def _solve(self, rhs):
        t0 = time.perf_counter()
        x = self.lu.solve(rhs)
        self.solve_seconds += time.perf_counter() - t0
        self.solves += 1 if rhs.ndim == 1 else rhs.shape[1]
        return x

    def _columns(self, rows):
        new = [i for i in rows if i not in self.cols]
        for k in range(0, len(new), 32):
            chunk = new[k:k + 32]
            E = np.zeros((self.N, len(chunk)))
            E[chunk, np.arange(len(chunk))] = 1.0
            Z = self._solve(E)
            for j, i in enumerate(chunk):
                self.cols[i] = Z[self.J, j].copy()
        return np.column_stack([self.cols[i] for i in rows]) if rows else np.zeros((len(self.J), 0))

    # --- a state's low-rank representation ----------------------------------------------------
    def set_state(self, st):
        """Rows of M_S(F) that differ from A: W0 + F W1 (restricted to J), rhs d0 + F d1."""
        if self.state is not None and np.array_equal(st, self.state):
            return
        S, n, t, b, g = self.S, self.S["n"], self.S["t"], self.S["b"], self.S["g"]
        rows, W0, W1, d0, d1 = [], [], [], [], []
        nJ = len(self.J)

        def unit(i):
            return sp.csr_matrix(([1.0], ([0], [self.loc[i]])), shape=(1, nJ))

        zero = sp.csr_matrix((1, nJ))
        for k in np.nonzero(self.tracked & ((st != self.base) | (st >= SLIP_P)))[0]:
            ba, ca = self.base[k] != FREE, st[k] != FREE
            if ba != ca:  # normal row
                i = n[k]
                base_row, base_rhs = (unit(i), g[k]) if ba else (self.KnJ[k], b[i])
                cur_row, cur_rhs = (unit(i), g[k]) if ca else (self.KnJ[k], b[i])
                rows.append(i), W0.append(cur_row - base_row), W1.append(zero), d0.append(cur_rhs - base_rhs), d1.append(0.0)
            bs, cs, sl = self.base[k] == STICK, st[k] == STICK, st[k] >= SLIP_P
            if bs != cs or sl:  # tangential row
                j = t[k]
                base_row, base_rhs = (unit(j), 0.0) if bs else (self.KtJ[k], b[j])
                cur_row, cur_rhs = (unit(j), 0.0) if cs else (self.KtJ[k], b[j])
                s = 1.0 if st[k] == SLIP_P else -1.0
                rows.append(j), W0.append(cur_row - base_row), d0.append(cur_rhs - base_rhs)
                W1.append(-s * self.KnJ[k] if sl else zero), d1.append(-s * b[n[k]] if sl else 0.0)
        n_slip = int((self.tracked & (st >= SLIP_P)).sum())
        if len(rows) - n_slip > self.max_rank:  # rows of changed nodes (a refactorization leaves the sliding rows)
            self.factor(st)
            return self.set_state(st)
        self.state = st.copy()
        self.rows = rows
        m = len(rows)
        self.Z = self._columns(rows)
        self.W0 = sp.vstack(W0).tocsr() if m else sp.csr_matrix((0, nJ))
        self.W1 = sp.vstack(W1).tocsr() if m else sp.csr_matrix((0, nJ))
        self.d0, self.d1 = np.array(d0), np.array(d1)
        self.P0, self.P1 = self.W0 @ self.Z, self.W1 @ self.Z
        self.v0, self.v1 = self.yJ + self.Z @ self.d0, self.Z @ self.d1
        self.Wv00, self.Wv01 = self.W0 @ self.v0, self.W0 @ self.v1
        self.Wv10, self.Wv11 = self.W1 @ self.v0, self.W1 @ self.v1
        self.sl = np.nonzero(self.tracked & (st >= SLIP_P))[0]
        self.slip_pos = np.array([rows.index(t[k]) for k in self.sl], int)

    def m(self):
        return len(self.rows)

    def capacitance(self, F):
        return np.eye(self.m()) + self.P0 + F * self.P1

    def xJ(self, F):
        v = self.v0 + F * self.v1
        if not self.m():
            return v
        Wv = self.Wv00 + F * (self.Wv01 + self.Wv10) + F * F * self.Wv11
        return v - self.Z @ np.linalg.solve(self.capacitance(F), Wv)

    def det_sign(self, F):
        return self.det_sign_A * int(np.linalg.slogdet(self.capacitance(F))[0]) if self.m() else self.det_sign_A

    def contact_values(self, F, xJ=None):
        """x_n, x_T, r_n, r_T at the contact nodes on the current piece."""
        S = self.S
        xJ = self.xJ(F) if xJ is None else xJ
        xn, xt = xJ[self.loc[S["n"]]], xJ[self.loc[S["t"]]]
        rn = S["b"][S["n"]] - self.KnJ @ xJ
        rt = S["b"][S["t"]] - self.KtJ @ xJ
        return xn, xt, rn, rt

    def indicators(self, F, st=None):
        """(nodes x 2) the state's inequalities in force units (>= 0 on the piece); untracked: +inf."""
        st = self.state if st is None else st
        S = self.S
        xn, xt, rn, rt = self.contact_values(F)
        cn, ct = self.c[S["n"]], self.c[S["t"]]
        ind = np.full((len(st), 2), np.inf)
        fr = st == FREE
        ind[fr, 0] = cn[fr] * (S["g"][fr] - xn[fr])
        ac = ~fr
        ind[ac, 0] = rn[ac]
        stk = st == STICK
        ind[stk, 1] = F * rn[stk] - np.abs(rt[stk])
        sp_ = st == SLIP_P
        ind[sp_, 1] = ct[sp_] * xt[sp_]
        sm = st == SLIP_M
        ind[sm, 1] = -ct[sm] * xt[sm]
        ind[~self.tracked] = np.inf
        return ind

    def tangent_J(self, F):
        """dx_S/dF on J: M_S x' = -s r_n at the sliding rows."""
        xn, xt, rn, rt = self.contact_values(F)
        c = np.zeros(self.m())
        s = np.where(self.state[self.sl] == SLIP_P, 1.0, -1.0)
        c[self.slip_pos] = -s * rn[self.sl]
        v = self.Z @ c
        if not self.m():
            return v
        W = self.W0 + F * self.W1
        return v - self.Z @ np.linalg.solve(self.capacitance(F), W @ v)

    def full_x(self, F):
        """x_S(F) on every dof: x = A^-1 (rhs_base + U (delta - W x_J)), one solve."""
        xJ = self.xJ(F)
        rhs = self.rhs_base.copy()
        if self.m():
            delta = self.d0 + F * self.d1
            rhs[self.rows] += delta - (self.W0 + F * self.W1) @ xJ
        return self._solve(rhs)


def march(P, F, direction, F_lo, F_hi, scale, tol, h0, hscale=1.0):
    """From F along the current piece in `direction`: the first F where an inequality fails
    (bisected), or the end of [F_lo, F_hi]. Returns (F_end, crossing nodes or None, evaluations)."""
    ind0 = P.indicators(F).min(axis=1)
    Fc, h, evals = F, h0 * F, 1
    hmax = 0.02 * F
    while True:
        Fn = Fc + direction * h
        end = None
        if Fn >= F_hi or Fn <= F_lo:
            Fn = F_hi if direction > 0 else F_lo
            end = Fn
        ind = P.indicators(Fn).min(axis=1)
        evals += 1
        if ind.min() < -tol:
            a, b = Fc, Fn
            for _ in range(200):
                if abs(b - a) <= 1e-13 * abs(b):
                    break
                mid = 0.5 * (a + b)
                im = P.indicators(mid).min(axis=1)
                evals += 1
                if im.min() < -tol:
                    b, ind = mid, im
                else:
                    a = mid
            bad = np.nonzero(ind < -tol)[0]
            return a, b, bad, evals
        if end is not None:
            return end, None, None, evals
        # step control: at most 1.25 times the first crossing predicted by linear extrapolation
        # of the inequalities (so a crossing is overshot and bisected, not approached forever)
        fin = np.isfinite(ind) & np.isfinite(ind0)
        slope = (ind[fin] - ind0[fin]) / h
        falling = slope < 0
        lim = np.inf
        if falling.any():
            lim = 1.25 * np.min(np.maximum(ind[fin][falling], 0) / -slope[falling])
        Fc, ind0 = Fn, ind
        h = max(min(2 * h, hmax * hscale, lim), 1e-9 * F)


def switch(P, st, F_a, F_b, nodes, direction, tol):
    """The continuation at a crossing of `nodes` between F_a (valid) and F_b (violated): every
    combination of other states of the nodes, both directions, from the breakpoint F_a, tested at
    F_a +- eps for eps = 1e-6 F_a (then 1e-7, 1e-8, 1e-5, 1e-4 F_a while the answer is not unique;
    then with the nodes that cross within 1e-6 F_a taken together). Returns the valid
    (state, direction, min inequality of the crossing nodes at eps), eps and the nodes switched."""
    import itertools

    def try_nodes(nodes, eps):
        cands = []
        options = [[c for c in (FREE, STICK, SLIP_P, SLIP_M)] for _ in nodes]
        for combo in itertools.product(*options):
            s2 = st.copy()
            s2[nodes] = combo
            for d in (1, -1):
                if np.array_equal(s2, st) and d == -direction:
                    continue  # the piece we came from
                P.set_state(s2)
                ind = P.indicators(F_a + d * eps)
                if ind.min() >= -tol:
                    cands.append((s2, d, float(ind[nodes].min())))
        return cands

    for rel in (1e-6, 1e-7, 1e-8, 1e-5, 1e-4):
        eps = rel * F_a
        cands = try_nodes(nodes, eps)
        if len(cands) == 1:
            return cands, eps, nodes
    eps = 1e-6 * F_a
    P.set_state(st)
    near = np.nonzero(P.indicators(F_a + direction * eps).min(axis=1) < -tol)[0]
    more = np.union1d(nodes, near)
    if len(more) > len(nodes) and len(more) <= 3:
        cands = try_nodes(more, eps)
        return cands, eps, more
    return cands, eps, nodes


def run(S, x0, F0, F_hi, F_lo, max_pieces, deadline, check_every=25, max_rank=200, verbose=True, direction=1):
    t0 = time.perf_counter()
    scale = float(np.abs(ac_residual(S, F0, S["fixed_values"].copy())).max())
    tol = 1e-11 * scale
    st = state_of(S, F0, x0)
    P = PiecewisePath(S, st, max_rank=max_rank, verbose=verbose)
    P.set_state(st)
    out = {"F0": F0, "scale": scale, "tol_inequality": tol, "start_counts": counts(st), "pieces": [], "checks": [],
           "folds": []}
    xf = P.full_x(F0)
    out["start_check"] = {"phi_newton_start": float(np.linalg.norm(ac_residual(S, F0, x0))),
                          "phi_piece": float(np.linalg.norm(ac_residual(S, F0, xf))),
                          "dx_rel": float(np.abs(xf - x0).max() / np.abs(x0).max()),
                          "min_indicator": float(P.indicators(F0).min())}
    if verbose:
        print(f"start F = {F0:g}: {counts(st)}; piece vs start {out['start_check']}", flush=True)
    F, k = F0, 0
    ind_start = P.indicators(F0).min()
    if ind_start < -tol:
        out["end"] = f"start state violates its inequalities ({ind_start:.1e})"
        return out, P, F, xf
    while k < max_pieces and time.perf_counter() - t0 < deadline:
        ts = time.perf_counter()
        P.set_state(st)
        for hscale in (1.0, 0.1, 0.01):
            F_a, F_b, nodes, evals = march(P, F, direction, F_lo, F_hi, scale, tol, 1e-4, hscale)
            # no crossing missed inside the piece (an inequality going below and back above zero
            # within one step): 32 interior points
            inner = [P.indicators(F + (F_a - F) * q).min() for q in np.linspace(0, 1, 34)[1:-1]]
            if min(inner) >= -tol:
                break
            print(f"  a crossing was missed on ({F:g}, {F_a:g}): steps 10 times shorter", flush=True)
        xt = P.tangent_J(0.5 * (F + F_a))
        rec = {"piece": k, "F_from": F, "F_to": F_a, "direction": direction, "counts": counts(st), "rank": P.m(),
               "det_sign": P.det_sign(0.5 * (F + F_a)), "max_dxdF_contact": float(np.abs(xt).max()),
               "evaluations": evals}
        if nodes is None:
            rec["end"] = "interval end"
            out["pieces"].append(rec)
            F = F_a
            if verbose:
                print(f"piece {k}: F {rec['F_from']:.6f} -> {F_a:.6f} {counts(st)}: reached the interval's end", flush=True)
            break
        x_old = P.xJ(F_a)
        cands, eps, nodes = switch(P, st, F_a, F_b, nodes, direction, tol)
        rec["nodes"] = [int(q) for q in nodes]
        rec["node_x"] = [float(S["xcoord"][q]) for q in nodes] if "xcoord" in S else None
        rec["from_states"] = [NAMES[int(st[q])] for q in nodes]
        rec["candidates"] = [([NAMES[int(c[0][q])] for q in nodes], c[1], c[2]) for c in cands]
        rec["eps"] = eps
        P.set_state(st)
        sign_before = P.det_sign(F_a)
        if len(cands) != 1:
            out["pieces"].append(rec)
            rec["end"] = f"{len(cands)} continuations"
            if verbose:
                print(f"piece {k}: F {rec['F_from']:.6f} -> {F_a:.6f}: nodes {rec['nodes']} {rec['from_states']}: "
                      f"{len(cands)} continuations {rec['candidates']}; path ends", flush=True)
            F = F_a
            break
        s2, d2, _ = cands[0]
        P.set_state(s2)
        sign_after = P.det_sign(F_a)
        # the new piece starts where the old one ends (both states' equations hold at the kink),
        # and its inequalities hold on (F_a, F_a + eps) too
        rec["jump"] = float(np.abs(P.xJ(F_a) - x_old).max() / np.abs(x_old).max())
        rec["min_ind_first_eps"] = float(min(P.indicators(F_a + d2 * eps * q).min() for q in np.linspace(0.1, 1, 10)))
        if rec["jump"] > (1e-8 if len(nodes) == 1 else 1e-6) or rec["min_ind_first_eps"] < -10 * tol:  # round-off at ~0.1 eps
            rec["end"] = "the continuation does not join the piece"
            out["pieces"].append(rec)
            print(f"piece {k}: the continuation does not join: jump {rec['jump']:.1e}, "
                  f"min inequality {rec['min_ind_first_eps']:.1e}; path ends", flush=True)
            break
        rec.update(to_states=[NAMES[int(s2[q])] for q in nodes], new_direction=d2, det_sign_before=sign_before,
                   det_sign_after=sign_after, seconds=time.perf_counter() - ts)
        out["pieces"].append(rec)
        fold = d2 != direction
        if verbose:
            print(f"piece {k}: F {rec['F_from']:.6f} -> {F_a:.9f} {counts(st)} rank {rec['rank']}: nodes {rec['nodes']} "
                  f"{rec['from_states']} -> {rec['to_states']}, det sign {sign_before:+d} -> {sign_after:+d}, "
                  f"direction {direction:+d} -> {d2:+d}{'  FOLD' if fold else ''} ({rec['seconds']:.1f} s)", flush=True)
        if fold or (k + 1) % check_every == 0:
            P.set_state(st)
            xf = P.full_x(F_a)
            chk = {"piece": k, "F": F_a, "phi": float(np.linalg.norm(ac_residual(S, F_a, xf))), "counts": counts(st),
                   "fold": fold}
            out["checks"].append(chk)
            if fold:
                out["folds"].append({"F": F_a, "piece": k, "phi": chk["phi"], "counts": counts(st),
                                     "nodes": rec["nodes"], "from": rec["from_states"], "to": rec["to_states"],
                                     "det_sign_before": sign_before, "det_sign_after": sign_after,
                                     "direction_before": direction, "direction_after": d2})
            if verbose:
                print(f"  check: |phi(x, {F_a:.6f})| = {chk['phi']:.2e}", flush=True)
        st, direction, F = s2, d2, F_a
        k += 1
    P.set_state(st)
    xf = P.full_x(F)
    out["end_F"] = F
    Fs = [q["F_to"] for q in out["pieces"]] + [F0]
    out["F_max"], out["F_min"] = max(Fs), min(Fs)
    out["n_folds"] = len(out["folds"])
    out["end_direction"] = direction
    out["end_counts"] = counts(st)
    out["end_phi"] = float(np.linalg.norm(ac_residual(S, F, xf)))
    out["seconds"] = time.perf_counter() - t0
    out.update(factorizations=P.factorizations, lu_seconds=P.lu_seconds, solves=P.solves, solve_seconds=P.solve_seconds)
    if verbose:
        print(f"end: F = {F:.6f}, direction {direction:+d}, {counts(st)}, |phi| {out['end_phi']:.2e}, "
              f"{len(out['pieces'])} pieces, {out['seconds']:.0f} s ({P.factorizations} LU {P.lu_seconds:.0f} s, "
              f"{P.solves} solves {P.solve_seconds:.0f} s)", flush=True)
    return out, P, F, xf


def verify_end(H, S, u, F, cycles=200):
    """The end point at F: semismooth Newton polish, contactmg.checks.contact_conditions, and
    Algorithm 2 (default solve) started from it: does it stay?"""
    import types
    from contactmg.checks import contact_conditions
    from contactmg.hertz import hertz_problem_on
    from coulomb_newton_diagnosis import semismooth_newton, energy_norm
    p = hertz_problem_on(H, F)
    scale = float(np.abs(ac_residual(S, F, S["fixed_values"].copy())).max())
    x, hist, cnt = semismooth_newton(S, F, S["D"] * u, max_steps=5, tol=1e-11 * scale)
    u1 = S["D"] * x
    r1 = p.solve("nmg", tol=1e-11, max_cycles=1, threads=1, u0=u1.reshape(-1, 2))
    res = types.SimpleNamespace(displacement=u1.reshape(-1, 2), contact_frames=r1.contact_frames)
    chk = contact_conditions(p, res)
    out = {"F": F, "newton_polish": hist, "newton_counts": cnt, "polish_move": energy_norm(p, u1 - u) / energy_norm(p, u),
           "contact_conditions": {k: float(v) for k, v in chk.items()}}
    print(f"end point at F = {F:g}: Newton polish |phi| {hist[0]:.2e} -> {hist[-1]:.2e}, moved {out['polish_move']:.1e} "
          f"(energy, relative); contact_conditions max {chk['max']:.2e}", flush=True)
    recs = []
    t0 = time.perf_counter()
    r = p.solve("nmg", tol=1e-11, max_cycles=cycles, threads=1, u0=u1.reshape(-1, 2), progress=lambda rec: recs.append(rec))
    ua = np.asarray(r.displacement).ravel()
    cn = [float(q["correction_norm"]) for q in recs]
    out["alg2_from_end"] = {"cycles": int(r.cycles), "converged": bool(r.converged), "seconds": time.perf_counter() - t0,
                            "corrections": cn, "states": [(int(q["active"]), int(q["stick"]), int(q["slip"])) for q in recs],
                            "distance_from_start": energy_norm(p, ua - u1) / energy_norm(p, u1),
                            "phi_end": float(np.linalg.norm(ac_residual(S, F, S["D"] * ua)))}
    a = out["alg2_from_end"]
    print(f"Algorithm 2 from it: {r.cycles} cycles, converged {r.converged}, first corrections "
          + " ".join(f"{c:.1e}" for c in cn[:8]) + f", last " + " ".join(f"{c:.1e}" for c in cn[-5:])
          + f"; distance from the start {a['distance_from_start']:.2e} (energy, relative), |phi| {a['phi_end']:.2e} "
          f"({a['seconds']:.0f} s)", flush=True)
    # Algorithm 2 from u = 0 (the default solve): where it ends against the path's solution
    t0 = time.perf_counter()
    r0 = p.solve("nmg", tol=1e-11, max_cycles=cycles, threads=1)
    u0 = np.asarray(r0.displacement).ravel()
    x0 = S["D"] * u0
    st0, st1 = state_of(S, F, x0), state_of(S, F, x)
    out["alg2_from_zero"] = {"cycles": int(r0.cycles), "converged": bool(r0.converged), "seconds": time.perf_counter() - t0,
                             "last_corrections": [float(c) for c in r0.history["correction_norm"][-6:]],
                             "distance_to_path_solution": energy_norm(p, u0 - u1) / energy_norm(p, u1),
                             "phi": float(np.linalg.norm(ac_residual(S, F, x0))), "counts": counts(st0),
                             "nodes_in_other_state": int((st0 != st1).sum())}
    b = out["alg2_from_zero"]
    print(f"Algorithm 2 from 0: {r0.cycles} cycles, converged {r0.converged}, distance to the path's solution "
          f"{b['distance_to_path_solution']:.2e} (energy, relative), |phi| {b['phi']:.2e}, {b['counts']}, "
          f"{b['nodes_in_other_state']} nodes in another state ({b['seconds']:.0f} s)", flush=True)
    return out


def main():
    from contactmg.hertz import hertz_problem_on
    ap = argparse.ArgumentParser()
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--start", default=None, help="a saved solution u (.npy); default: L11 out/cache/nw_F20.npy, "
                    "else Algorithm 2 at --from-F")
    ap.add_argument("--from-F", type=float, default=20.0)
    ap.add_argument("--to-F", type=float, default=40.0)
    ap.add_argument("--min-F", type=float, default=0.5)
    ap.add_argument("--down", action="store_true", help="start in the direction of decreasing F")
    ap.add_argument("--max-pieces", type=int, default=400)
    ap.add_argument("--max-rank", type=int, default=200)
    ap.add_argument("--check-every", type=int, default=25)
    ap.add_argument("--deadline-seconds", type=float, default=3000)
    ap.add_argument("--save-end")
    ap.add_argument("--verify-end", action="store_true", help="at the end point (if it is --to-F): Newton polish, "
                    "contact_conditions, Algorithm 2 started from it")
    ap.add_argument("--verify-cycles", type=int, default=200)
    ap.add_argument("--compare-alg2", action="store_true")
    ap.add_argument("--compare", nargs="*", default=[], help="saved solutions u (.npy): the end point's distance "
                    "to each (energy norm, relative) and the number of contact nodes in another state")
    ap.add_argument("--json")
    a = ap.parse_args()
    t0 = time.perf_counter()
    H = hierarchy(a.level)
    p = hertz_problem_on(H, a.from_F)
    S = hertz_system(p)
    S["xcoord"] = np.asarray(p.mesh.points)[np.asarray(p.contact.nodes), 0]
    start = a.start if a.start else (os.path.join("out", "cache", "nw_F20.npy") if a.level == 11 and a.from_F == 20 else None)
    out = {"level": a.level, "dofs": int(S["K"].shape[0]), "contact_nodes": int(len(S["g"])), "start": start}
    if start:
        u = np.load(start).ravel()
    else:
        r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1)
        out["start_alg2"] = {"cycles": int(r.cycles), "converged": bool(r.converged)}
        print(f"Algorithm 2 at F = {a.from_F:g}: {r.cycles} cycles, converged {r.converged}", flush=True)
        u = np.asarray(r.displacement).ravel().copy()
    res, P, F_end, x_end = run(S, S["D"] * u, a.from_F, a.to_F, a.min_F, a.max_pieces, a.deadline_seconds,
                               check_every=a.check_every, max_rank=a.max_rank, direction=-1 if a.down else 1)
    out.update(res)
    if a.save_end:
        np.save(a.save_end, S["D"] * x_end)
        out["saved"] = a.save_end
    if a.compare:
        from coulomb_newton_diagnosis import energy_norm
        st_end = state_of(S, F_end, x_end)
        out["compare"] = {}
        for path in a.compare:
            uc = np.load(path).ravel()
            xc = S["D"] * uc
            ue = S["D"] * x_end
            out["compare"][path] = {"distance": energy_norm(p, ue - uc) / energy_norm(p, uc),
                                    "nodes_in_other_state": int((state_of(S, F_end, xc) != st_end).sum()),
                                    "phi_of_saved_at_end_F": float(np.linalg.norm(ac_residual(S, F_end, xc)))}
            print(f"end point vs {path}: {out['compare'][path]}", flush=True)
    if a.compare_alg2:
        from coulomb_newton_diagnosis import energy_norm
        pe = hertz_problem_on(H, F_end)
        re_ = pe.solve("nmg", tol=1e-11, max_cycles=200, threads=1)
        ua, ue = np.asarray(re_.displacement).ravel(), S["D"] * x_end
        out["compare_alg2"] = {"F": F_end, "cycles": int(re_.cycles), "converged": bool(re_.converged),
                               "distance": energy_norm(pe, ue - ua) / energy_norm(pe, ua),
                               "nodes_in_other_state": int((state_of(S, F_end, S["D"] * ua) != state_of(S, F_end, x_end)).sum())}
        print(f"end point vs Algorithm 2 at F = {F_end:g}: {out['compare_alg2']}", flush=True)
    if a.verify_end and abs(F_end - a.to_F) < 1e-12 * a.to_F:
        out["verify_end"] = verify_end(H, S, S["D"] * x_end, a.to_F, a.verify_cycles)
    out["total_seconds"] = time.perf_counter() - t0
    write_json(a.json, out)


if __name__ == "__main__":
    main()
