"""Where Algorithm 2's smoother cycles at large F (issue 11, adaptive Hertz level 11, F = 40):
the contact line alone.

    python benchmarks/contact_line_diagnosis.py [--level 11] [--friction 40] [--cycles 40]
        [--sweeps 300] [--json out/contact_line_diagnosis.json]

Runs Algorithm 2 for --cycles cycles (into its limit cycle at L11, F = 40), then freezes every node
off the contact boundary and relaxes the contact nodes alone (the "line" problem: 2D, nodes in
the order of x, the frames of the Hertz plane obstacle, x_n = -u_y, x_T = u_x):
  point   the core's nodal Coulomb rule (cpp/laws/nodal_solve.hpp, 2D: the node's own Coulomb
          condition exactly where q = F |B_Tn| / B_TT < 1, the lagged bound elsewhere), node by node
  pair    overlapping pairs of neighbouring contact nodes solved jointly and exactly: all 4 x 4
          state combinations (free, stick, slide +/-) of the pair, the consistent one nearest the
          current iterate in the B-norm
Prints the max change per sweep of both, the nodes that keep changing under the point rule with
their states over the last 10 sweeps, q, and F B_{pn,qT} / B_{qT,qT} of their neighbours.
Measured 2026-12-02 (main at e563a79, 40 cycles into the limit cycle; results/contact_line_diagnosis_L11_F40.json):
the point rule cycles on the line alone (max change 4.4e-6 for 300 sweeps; 16 of the 1,653 contact
nodes keep moving, all at the left edge of the contact zone, x = -0.0335 .. -0.0320: the innermost
alternates slide / stick every sweep, the free nodes outside it (and one sliding node among them)
follow; q = 0.74-0.78, F B_{pn,qT} / B_{qT,qT} = 3.6-4.9 towards both neighbours). The pair sweep does not converge there either (a period of 20 sweeps between
1.3e-7 and 1.7e-5). On an iterate of an earlier build it converged (0.45 per sweep), which is why it
was tried inside the cycle as an extra smoother step (Coulomb, 2D, after every fine sweep): it made
no run of the ten coefficients on adaptive L3-L11 converge that did not, and F = 5 / 8 on L11 went
from 30 / 54 cycles to 37-200 / no convergence (the report of the `adapt2` branch).
"""
import argparse
import itertools
import json
import os
import sys

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(__file__))
from cycle_growth import adaptive_hierarchy  # noqa: E402

from contactmg import _core  # noqa: E402
from contactmg.hertz import hertz_problem_on  # noqa: E402


def line_problem(p, u):
    m = p.mesh
    A = _core.assemble_elasticity(m.points, m.cells, m.cell_type, p.material.E, p.material.nu)
    Asp = sp.bsr_matrix((np.asarray(A.data).reshape(-1, 2, 2), np.asarray(A.indices), np.asarray(A.indptr)),
                        shape=A.shape).tocsr()
    f = np.asarray(p.load).ravel()
    order = np.argsort(m.points[p.contact.nodes, 0])
    C, g = p.contact.nodes[order], p.contact.gaps[order]
    dofs = np.ravel(np.column_stack([2 * C + 1, 2 * C]))  # (n, T) per node
    sgn = np.tile([-1.0, 1.0], len(C))
    K = (sp.diags(sgn) @ Asp[dofs][:, dofs] @ sp.diags(sgn)).tocsr()
    v = u.copy()
    v[dofs] = 0
    b = sgn * (f[dofs] - Asp[dofs] @ v)
    return C, g, K, b, sgn * u[dofs], m.points[C, 0]


def node_solve(B, b, gap, F, old):
    """cpp/laws/nodal_solve.hpp's solve_node_coulomb in 2D."""
    def on_gap():
        BTn, BTT = B[1, 0], B[1, 1]
        c, p0 = b[1] - BTn * gap, b[0] - B[0, 0] * gap
        if F * abs(BTn) / BTT >= 1:
            s = F * max(0.0, p0 - BTn * old[1])
            xt = 0.0 if abs(c) <= s else np.sign(c) * (abs(c) - s) / BTT
        else:
            s = F * max(0.0, p0)
            if abs(c) <= s:
                xt = 0.0
            else:
                sg = np.sign(c)
                s = max(F * (p0 - BTn * c / BTT) / (1 - F * BTn * sg / BTT), 0.0)
                xt = sg * (abs(c) - s) / BTT if abs(c) > s else 0.0
        return np.array([gap, xt]), p0 - BTn * xt
    if old[0] >= gap:
        x, pr = on_gap()
        if pr >= 0:
            return x
    t = np.linalg.solve(B, b)
    return t if t[0] < gap else on_gap()[0]


def pair_solve(B, b, gg, F, old):
    sols = []
    for states in itertools.product("FS+-", repeat=2):
        M, rhs = B.copy(), b.copy()
        for k, s in enumerate(states):
            n, t = 2 * k, 2 * k + 1
            if s == "F":
                continue
            M[n] = 0
            M[n, n] = 1
            rhs[n] = gg[k]
            if s == "S":
                M[t] = 0
                M[t, t] = 1
                rhs[t] = 0
            else:
                sg = 1.0 if s == "+" else -1.0
                M[t], rhs[t] = B[t] - sg * F * B[n], b[t] - sg * F * b[n]
        try:
            y = np.linalg.solve(M, rhs)
        except np.linalg.LinAlgError:
            continue
        r, ok = b - B @ y, True
        for k, s in enumerate(states):
            n, t = 2 * k, 2 * k + 1
            if s == "F":
                ok &= y[n] < gg[k]
            else:
                ok &= r[n] >= -1e-14 * abs(b[n])
                ok &= abs(r[t]) <= F * r[n] * (1 + 1e-12) if s == "S" else ((y[t] > 0) == (s == "+") and y[t] != 0)
        if ok:
            for k, s in enumerate(states):
                if s != "F":
                    y[2 * k] = gg[k]
                if s == "S":
                    y[2 * k + 1] = 0
            sols.append(y)
    if not sols:
        return None
    return sols[int(np.argmin([(y - old) @ B @ (y - old) for y in sols]))]


def blocks(K, i, w):
    sl = slice(2 * i, 2 * i + 2 * w)
    return K[2 * i:2 * i + 2 * w], sl


def point_sweep(K, b, g, F, x):
    for i in range(len(g)):
        row, sl = blocks(K, i, 1)
        B = row[:, sl].toarray()
        x[sl] = node_solve(B, b[sl] - row @ x + B @ x[sl], g[i], F, x[sl].copy())


def pair_sweep(K, b, g, F, x, forward):
    for i in (range(len(g) - 1) if forward else range(len(g) - 2, -1, -1)):
        row, sl = blocks(K, i, 2)
        B = row[:, sl].toarray()
        if B[0, 2] == 0 and B[0, 3] == 0:
            continue
        y = pair_solve(B, b[sl] - row @ x + B @ x[sl], g[i:i + 2], F, x[sl].copy())
        if y is not None:
            x[sl] = y


def state(x, g, i):
    return "F" if x[2 * i] < g[i] else ("S" if x[2 * i + 1] == 0 else ("+" if x[2 * i + 1] > 0 else "-"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--friction", type=float, default=40.0)
    ap.add_argument("--cycles", type=int, default=40)
    ap.add_argument("--sweeps", type=int, default=300)
    ap.add_argument("--json")
    a = ap.parse_args()
    F = a.friction
    p = hertz_problem_on(adaptive_hierarchy(11).truncated(a.level), F)
    r = p.solve("nmg", tol=1e-11, max_cycles=a.cycles)
    print(f"Algorithm 2, L{a.level} F={F}: {r.cycles} cycles, converged {r.converged}, last corrections "
          + " ".join(f"{c:.2e}" for c in r.history["correction_norm"][-5:]))
    C, g, K, b, x0, xs = line_problem(p, np.asarray(r.displacement).ravel().copy())
    out = {"level": a.level, "F": F, "cycles": a.cycles, "contact_nodes": len(C)}
    x, hist, point = x0.copy(), [], []
    for s in range(a.sweeps):
        xo = x.copy()
        point_sweep(K, b, g, F, x)
        point.append(float(np.abs(x - xo).max()))
        hist.append(x.copy())
    print("point rule, max change every 20 sweeps: " + " ".join(f"{c:.1e}" for c in point[::20]) + f" (last {point[-1]:.1e})")
    H = np.array(hist[-10:])
    var = np.abs(H - H[-1]).max(0)
    moving = np.where((var[0::2] > 1e-12) | (var[1::2] > 1e-12))[0]
    rows = []
    for i in moving:
        B = K[2 * i:2 * i + 2, 2 * i:2 * i + 2].toarray()
        nb = [j for j in (i - 1, i + 1) if 0 <= j < len(C) and K[2 * i, 2 * j + 1] != 0]
        cpl = [float(F * K[2 * i, 2 * j + 1] / K[2 * j + 1, 2 * j + 1]) for j in nb]
        rows.append({"x": float(xs[i]), "q": float(F * abs(B[1, 0]) / B[1, 1]),
                     "states": "".join(state(h, g, i) for h in H), "coupling": cpl})
        if len(rows) <= 12:
            print(f"  x={xs[i]:+.5f} q={rows[-1]['q']:.2f} states {rows[-1]['states']} F B_pn,qT/B_qT "
                  + " ".join(f"{c:+.2f}" for c in cpl))
    print(f"  {len(moving)} nodes keep changing")
    x, pair = x0.copy(), []
    for s in range(a.sweeps):
        xo = x.copy()
        pair_sweep(K, b, g, F, x, s % 2 == 0)
        pair.append(float(np.abs(x - xo).max()))
        if pair[-1] < 1e-15:
            break
    xo = x.copy()
    point_sweep(K, b, g, F, x)
    after = float(np.abs(x - xo).max())
    print(f"pair sweep: {len(pair)} sweeps, max change " + " ".join(f"{c:.1e}" for c in pair[::5])
          + f"; one point sweep on its result moves it by {after:.1e}")
    out.update(point_changes=point, moving_nodes=rows, pair_changes=pair, point_after_pair=after)
    if a.json:
        os.makedirs(os.path.dirname(a.json) or ".", exist_ok=True)
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
