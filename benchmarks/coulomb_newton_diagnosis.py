"""Semismooth Newton on the discrete Coulomb conditions (Alart-Curnier), as a diagnosis of
Algorithm 2's failures at large F on the adaptive Hertz hierarchy (issue 11), and as an independent
solver to check Algorithm 2's solutions against.

    python benchmarks/coulomb_newton_diagnosis.py line   [--level 11] [--friction 40] [--cycles 40]
    python benchmarks/coulomb_newton_diagnosis.py alternate [--level 11] [--friction 40] [--steps 25]
    python benchmarks/coulomb_newton_diagnosis.py newton [--level 11] [--friction 40] [--start PATH.npy]
    python benchmarks/coulomb_newton_diagnosis.py continuation [--level 11] [--frictions 8 12 16 ...]
        [--json PATH]

The Coulomb conditions of every contact node p (frame of the Hertz plane obstacle: x_n = -u_y,
x_T = u_x; r = f - A u, r_n >= 0 compressive), written as the Alart-Curnier NCP function with
c_p = the node's own diagonal entries (no parameter; any c > 0 gives the same solutions):
    phi_n = r_n - max(0, r_n + c_n (x_n - g)),   phi_T = r_T - proj_[-F l, F l](r_T + c_T x_T),
    l = max(0, r_n + c_n (x_n - g));  phi = r on the other free dofs.
One Newton step solves, for the state of the current iterate (free / stick / slip with the sign of
r_T + c_T x_T), the linear system whose contact rows are x_n = g (active), x_T = 0 (stick) and the
sliding row r_T - sign F r_n = 0 (the term Algorithm 2's coarse problem freezes: non-symmetric),
by a sparse direct solve (SuperLU), then backtracks on |phi|^2 (Armijo, t >= 2^-20).

Modes:
  line          Algorithm 2 for --cycles cycles, then the contact nodes alone (every other node
                frozen, the problem of contact_line_diagnosis.py) by this Newton.
  alternate     one Algorithm 2 cycle (a solve with max_cycles=1 from the last iterate: Anderson's
                history is lost between calls) and one line Newton solve, --steps times: the line
                solve as an extra smoother step of the fine level, prototyped from Python.
  newton        the whole problem by this Newton from --start (default: 40 cycles of Algorithm 2),
                then Algorithm 2 from Newton's result.
  continuation  Algorithm 2 at each F of --frictions from the previous F's solution.
  rate          Algorithm 2 (tol 1e-30, --steps cycles) from --start scaled by 1 - 1e-6 (a solution,
                e.g. Newton's saved by `newton --save`): the contraction of the cycle map near the
                solution, contact state fixed; and from --start unscaled (round-off only).
Measured 2026-12-03 (branch adapt4, idle machine except another engineer's benchmarks;
docs/history/adaptive.md, "Issue 11, fourth part"): see there for the numbers.
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

from contactmg import _core  # noqa: E402
from contactmg.hertz import hertz_problem_on  # noqa: E402


def _csr(A):
    return sp.bsr_matrix((np.asarray(A.data).reshape(-1, 2, 2), np.asarray(A.indices), np.asarray(A.indptr)),
                         shape=A.shape).tocsr()


def hertz_system(p):
    """The problem in the contact frames of the Hertz plane obstacle (2D): K = D A D, b = D f,
    x = D u with D = -1 at the y dofs of contact nodes; normal dof 2c+1, tangential 2c."""
    m = p.mesh
    if m.points.shape[1] != 2:
        raise ValueError("2D only (the Hertz plane obstacle's frames)")
    A = _csr(_core.assemble_elasticity(m.points, m.cells, m.cell_type, p.material.E, p.material.nu))
    C, g = np.asarray(p.contact.nodes), np.asarray(p.contact.gaps)
    D = np.ones(A.shape[0])
    D[2 * C + 1] = -1
    fixed = p.fixed.ravel().astype(bool)
    return {"K": (sp.diags(D) @ A @ sp.diags(D)).tocsr(), "b": D * np.asarray(p.load).ravel(), "D": D,
            "g": g, "n": 2 * C + 1, "t": 2 * C, "fixed": fixed, "fixed_values": D * p.fixed_values.ravel()}


def line_system(S, x):
    """The contact dofs alone, every other dof frozen at x."""
    dofs = np.ravel(np.column_stack([S["t"], S["n"]]))  # (T, n) per node -> local t = 2k, n = 2k+1
    rest = x.copy()
    rest[dofs] = 0
    k = len(S["g"])
    return {"K": S["K"][dofs][:, dofs].tocsr(), "b": S["b"][dofs] - S["K"][dofs] @ rest, "g": S["g"],
            "n": 2 * np.arange(k) + 1, "t": 2 * np.arange(k), "fixed": np.zeros(2 * k, bool),
            "fixed_values": np.zeros(2 * k), "dofs": dofs}


def ac_residual(S, F, x):
    K, n, t, g = S["K"], S["n"], S["t"], S["g"]
    r = S["b"] - K @ x
    diag = K.diagonal()
    phi = r.copy()
    phi[S["fixed"]] = x[S["fixed"]] - S["fixed_values"][S["fixed"]]
    lam = np.maximum(0.0, r[n] + diag[n] * (x[n] - g))
    phi[n] = r[n] - lam
    phi[t] = r[t] - np.clip(r[t] + diag[t] * x[t], -F * lam, F * lam)
    return phi


def coulomb_state(S, F, x):
    """The Alart-Curnier state of x (c_p the node's own diagonal entries): the normal and tangential
    arguments lam, z and the masks active, stick, slip over the contact nodes."""
    K, b, n, t, g = S["K"], S["b"], S["n"], S["t"], S["g"]
    r = b - K @ x
    diag = K.diagonal()
    lam = r[n] + diag[n] * (x[n] - g)
    z = r[t] + diag[t] * x[t]
    active = lam > 0
    stick = active & (np.abs(z) <= F * lam)
    return lam, z, active, stick, active & ~stick


def newton_target(S, F, x):
    """The full Newton step's target y (the linear problem of x's state) and the state counts."""
    K, b, n, t, g = S["K"], S["b"], S["n"], S["t"], S["g"]
    lam, z, active, stick, slip = coulomb_state(S, F, x)
    N = K.shape[0]
    ident = np.zeros(N, bool)
    ident[S["fixed"]] = True
    ident[n[active]] = True
    ident[t[stick]] = True
    rhs = b.copy()
    rhs[S["fixed"]] = S["fixed_values"][S["fixed"]]
    rhs[n[active]] = g[active]
    rhs[t[stick]] = 0
    sgn = np.sign(z[slip])
    # sliding rows: r_T - sign F r_n = 0, i.e. (K_T - sign F K_n) x = b_T - sign F b_n
    E = sp.csr_matrix((-sgn * F, (t[slip], n[slip])), shape=(N, N))
    M = sp.diags((~ident).astype(float)) @ (K + E @ K) + sp.diags(ident.astype(float))
    rhs[t[slip]] = b[t[slip]] - sgn * F * b[n[slip]]
    return spla.spsolve(M.tocsc(), rhs), int(active.sum()), int(stick.sum()), int(slip.sum())


def semismooth_newton(S, F, x, max_steps=30, tol=1e-10, verbose=False):
    """Returns (x, |phi| history, state counts of the last step)."""
    phi = ac_residual(S, F, x)
    theta = 0.5 * phi @ phi
    hist, counts, stuck = [float(np.sqrt(2 * theta))], None, 0
    for it in range(max_steps):
        if hist[-1] <= tol:
            break
        y, *counts = newton_target(S, F, x)
        step = 1.0
        while True:
            xt = x + step * (y - x)
            ph = ac_residual(S, F, xt)
            tn = 0.5 * ph @ ph
            if tn <= (1 - 1e-4 * step) * theta or step < 2.0 ** -20:
                break
            step *= 0.5
        x, theta = xt, tn
        hist.append(float(np.sqrt(2 * theta)))
        stuck = stuck + 1 if step < 2.0 ** -20 else 0
        if verbose:
            print(f"  newton {it}: step {step:g} |phi| {hist[-1]:.3e} active {counts[0]} stick {counts[1]} slip {counts[2]}",
                  flush=True)
        if stuck >= 3:
            break
    return x, hist, counts


def hierarchy(level):
    from cycle_growth import adaptive_hierarchy
    return adaptive_hierarchy(11).truncated(level)


def energy_norm(p, du):
    du = du.reshape(-1, 2)
    return float(np.sqrt(max(np.sum(du * p.A.matvec(du)), 0.0)))


def main():
    from contactmg.checks import contact_conditions

    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["line", "alternate", "newton", "continuation", "rate"])
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--friction", type=float, default=40.0)
    ap.add_argument("--frictions", type=float, nargs="+", default=[8, 12, 16, 20, 25, 32, 40])
    ap.add_argument("--cycles", type=int, default=40)
    ap.add_argument("--steps", type=int, default=25)
    ap.add_argument("--start")
    ap.add_argument("--save")
    ap.add_argument("--json")
    a = ap.parse_args()
    H = hierarchy(a.level)
    out = {"mode": a.mode, "level": a.level}
    if a.mode == "continuation":
        u, rows = None, []
        for F in a.frictions:
            p = hertz_problem_on(H, F)
            t0 = time.perf_counter()
            r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1, u0=u)
            v = float(contact_conditions(p, r)["max"])
            rows.append({"F": F, "cycles": int(r.cycles), "converged": bool(r.converged), "violation": v})
            print(f"F = {F:g}: {r.cycles} cycles, converged {r.converged}, violation {v:.1e} ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
            if r.converged:
                u = np.asarray(r.displacement).copy()
        out["runs"] = rows
    elif a.mode == "rate":
        F = a.friction
        p = hertz_problem_on(H, F)
        u0 = np.load(a.start).reshape(-1, 2)
        out["F"] = F
        for name, start in (("perturbed", u0 * (1 - 1e-6)), ("exact", u0)):
            recs = []
            p.solve("nmg", tol=1e-30, max_cycles=a.steps, threads=1, u0=start, progress=lambda rec: recs.append(rec))
            c = [float(x["correction_norm"]) for x in recs]
            states = sorted({(x["active"], x["stick"], x["slip"]) for x in recs})
            rate = (c[-1] / c[9]) ** (1 / (len(c) - 10)) if len(c) > 10 and c[9] > 0 else float("nan")
            print(f"{name}: corrections " + " ".join(f"{v:.1e}" for v in c) + f"\n  states {states}, "
                  f"rate per cycle over cycles 10-{len(c)}: {rate:.3f}", flush=True)
            out[name] = {"corrections": c, "states": states, "rate": rate}
    else:
        F = a.friction
        out["F"] = F
        p = hertz_problem_on(H, F)
        S = hertz_system(p)
        if a.start:
            u = np.load(a.start).ravel()
        else:
            r = p.solve("nmg", tol=1e-11, max_cycles=a.cycles, threads=1)
            print(f"Algorithm 2, {r.cycles} cycles, converged {r.converged}; last corrections "
                  + " ".join(f"{c:.3e}" for c in r.history["correction_norm"][-5:]))
            u = np.asarray(r.displacement).ravel().copy()
        if a.mode == "line":
            x = S["D"] * u
            Ls = line_system(S, x)
            xl, hist, counts = semismooth_newton(Ls, F, x[Ls["dofs"]].copy(), verbose=True)
            out.update(line_newton=hist, counts=counts)
        elif a.mode == "newton":
            x, hist, counts = semismooth_newton(S, F, S["D"] * u, verbose=True)
            u = S["D"] * x
            if a.save:
                np.save(a.save, u)
            r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1, u0=u.reshape(-1, 2))
            v = float(contact_conditions(p, r)["max"])
            print(f"Algorithm 2 from Newton's result: {r.cycles} cycles, converged {r.converged}, violation {v:.1e}")
            out.update(newton=hist, counts=counts, nmg_after={"cycles": int(r.cycles), "converged": bool(r.converged),
                                                              "violation": v})
        else:  # alternate
            rows = []
            for k in range(a.steps):
                r = p.solve("nmg", tol=1e-11, max_cycles=1, threads=1, u0=u.reshape(-1, 2))
                u = np.asarray(r.displacement).ravel().copy()
                x = S["D"] * u
                Ls = line_system(S, x)
                xl, hist, _ = semismooth_newton(Ls, F, x[Ls["dofs"]].copy())
                x2 = x.copy()
                x2[Ls["dofs"]] = xl
                du = S["D"] * x2 - u
                u = u + du
                rows.append({"cycle": float(r.history["correction_norm"][-1]), "line": energy_norm(p, du),
                             "line_residual": hist[-1]})
                print(f"{k}: cycle correction {rows[-1]['cycle']:.3e}, line correction {rows[-1]['line']:.3e}, "
                      f"line |phi| {hist[-1]:.1e}", flush=True)
            out["steps"] = rows
    if a.json:
        os.makedirs(os.path.dirname(a.json) or ".", exist_ok=True)
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
