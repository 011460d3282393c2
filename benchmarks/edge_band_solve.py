"""A nonlinear block solve of the contact edge band (normals and tangentials together) as an extra
fine-level smoothing step between Algorithm 2's cycles (issue 11, eighth part; docs/history/adaptive.md).
A Python prototype: nothing of it is in the core.

    python benchmarks/edge_band_solve.py cycles [--levels 7 9 11] [--frictions 0.4 2 5 8 40]
        [--modes off on] [--chunk 1] [--json PATH]
    python benchmarks/edge_band_solve.py limit [--level 11] [--friction 40] [--cycles 60] [--json PATH]
    python benchmarks/edge_band_solve.py smoother [--level 11] [--friction 40] [--cycles 60]
        [--blocks 300] [--block-sweeps 10] [--json PATH]

Measured 2026-12-03 (branch smooth7; docs/history/adaptive.md, "Issue 11, eighth part"): no cycle
count better by more than one anywhere (L11 F = 0.4 / 2 / 5 17 / 26 / 44 with and without it), L11
F = 8 / 40 unconverged either way; at F = 40 the band problem at the orbit iterate is solvable by
continuation in F only, and its solutions are unstable fixed points of point Gauss-Seidel.

The problem in the Hertz plane obstacle's contact frames (coulomb_newton_diagnosis.hertz_system:
x = D u, K = D A D, normal dof 2c+1, tangential 2c; r = b - K x, r_n >= 0 compressive, x_n <= g).

The band (rule `band_nodes`): the contact nodes whose core state (free / stick / slip) changed in
the last two cycles, plus those whose Alart-Curnier normal argument lam = r_n + c_n (x_n - g)
(c_n the node's diagonal entry) is small, |lam| <= ETA max lam (ETA = 0.02: at the contact edge both
the pressure and the gap tend to zero, so lam does; at a sticking node in the zone's interior it is
the pressure, away from the zone the scaled gap), plus one ring of contact neighbours (K_pq != 0);
nodes with a Dirichlet component are left out.

The band solve: every other dof frozen, the band's 2 dofs per node solved together
(dense; the local system K_bb x_b = b_b - K_b,rest x_rest with the Coulomb conditions of each band
node) by a semismooth Newton method on the Alart-Curnier function (the sliding rows
r_T - sign F r_n = 0, as coulomb_newton_diagnosis.newton_target, dense), Armijo backtracking on
|phi|^2; if it does not reach |phi| <= BAND_TOL (relative to the largest |lam| of the contact zone),
the band is instead swept by the core's own nodal Coulomb rule (_core.solve_node_coulomb_2D, the
point smoother's local solve) up to SWEEPS times, forward then backward, until the largest change is
below 1e-14 of max |x|; the result of either is feasible (x_n <= g at every node: Newton's only when
phi = 0, so a Newton result that is not converged is never taken).

`cycles`: Algorithm 2 one call of `--chunk` cycles at a time (p.solve(max_cycles=chunk, u0=u): the
Anderson history and the fallback state are lost between calls, so "off" is the same harness
without the band step, not the default solve), the band step after every call (mode on), until a
call converges (tol 1e-11, the core's test: the last cycle's correction); the result through
contactmg.checks.contact_conditions.
`limit`: the F = 40 question. Algorithm 2 (default solve, --cycles cycles) into its limit cycle;
then the band problem with every other dof frozen at that iterate, solved by the block Newton
from the iterate, from the sweeps' result, by continuation in F and by the band's own Algorithm 1,
and (for the point rule's answer) by band-only nodal sweeps; the linearized point Gauss-Seidel radius
at the solution found.
`smoother`: from the same iterate, core sweeps (ContactSolver2D.smooth) in blocks, with or without
the band step (with continuation) after each block; no coarse correction.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from contactmg import _core  # noqa: E402
from coulomb_newton_diagnosis import energy_norm, hertz_system  # noqa: E402

ETA = 0.02
BAND_TOL = 1e-10
SWEEPS = 2000
NEWTON_STEPS = 40
CONTINUATION = False  # --continuation: a Newton that fails is retried by continuation in F from the iterate


def band_nodes(S, x, changed, ring=True):
    """Contact indices of the band (see the module docstring)."""
    K, b, n, t, g = S["K"], S["b"], S["n"], S["t"], S["g"]
    r = b - K @ x
    diag = K.diagonal()
    lam = r[n] + diag[n] * (x[n] - g)
    lmax = max(float(lam.max()), 1e-300)
    sel = np.zeros(len(g), bool)
    sel[changed] = True
    sel |= np.abs(lam) <= ETA * lmax
    fixed = S["fixed"]
    sel &= ~(fixed[n] | fixed[t])
    if ring and sel.any():
        # contact neighbours: K couples contact node c to node j's dofs; map dof -> contact index
        pos = -np.ones(K.shape[0], int)
        pos[n] = np.arange(len(g))
        pos[t] = np.arange(len(g))
        rows = np.concatenate([n[sel], t[sel]])
        sub = K[rows]
        cols = pos[sub.indices]
        nb = np.zeros(len(g), bool)
        nb[cols[cols >= 0]] = True
        sel |= nb & ~(fixed[n] | fixed[t])
    return np.nonzero(sel)[0], lmax


def band_system(S, x, band):
    """Dense local system of the band: dofs (t, n) per node -> local t = 2k, n = 2k + 1."""
    dofs = np.ravel(np.column_stack([S["t"][band], S["n"][band]]))
    Kr = S["K"][dofs]
    rb = S["b"][dofs] - Kr @ x
    Kb = Kr[:, dofs].toarray()
    bb = rb + Kb @ x[dofs]  # b_b - K_b,rest x_rest
    return dofs, Kb, bb, S["g"][band]


def ac_phi(Kb, bb, g, F, xb):
    k = len(g)
    n, t = 2 * np.arange(k) + 1, 2 * np.arange(k)
    r = bb - Kb @ xb
    d = np.diag(Kb)
    lam = r[n] + d[n] * (xb[n] - g)
    lp = np.maximum(0.0, lam)
    z = r[t] + d[t] * xb[t]
    phi = np.empty_like(xb)
    phi[n] = r[n] - lp
    phi[t] = r[t] - np.clip(z, -F * lp, F * lp)
    return phi, lam, z


def band_state(Kb, bb, g, F, xb):
    """The band's normal / tangential dof indices and its Alart-Curnier state at xb."""
    k = len(g)
    n, t = 2 * np.arange(k) + 1, 2 * np.arange(k)
    _, lam, z = ac_phi(Kb, bb, g, F, xb)
    act = lam > 0
    stick = act & (np.abs(z) <= F * lam)
    return n, t, z, act, stick, act & ~stick


def newton_target(Kb, bb, g, F, xb):
    k = len(g)
    n, t, z, act, stick, slip = band_state(Kb, bb, g, F, xb)
    M = Kb.copy()
    rhs = bb.copy()
    M[n[act]] = 0
    M[n[act], n[act]] = 1
    rhs[n[act]] = g[act]
    M[t[stick]] = 0
    M[t[stick], t[stick]] = 1
    rhs[t[stick]] = 0
    s = np.sign(z[slip])
    M[t[slip]] = Kb[t[slip]] - (s * F)[:, None] * Kb[n[slip]]
    rhs[t[slip]] = bb[t[slip]] - s * F * bb[n[slip]]
    return np.linalg.solve(M, rhs), (int(act.sum()), int(stick.sum()), int(slip.sum()))


def band_newton(Kb, bb, g, F, xb, tol):
    phi, _, _ = ac_phi(Kb, bb, g, F, xb)
    th = 0.5 * phi @ phi
    hist = [float(np.sqrt(2 * th))]
    for _ in range(NEWTON_STEPS):
        if hist[-1] <= tol:
            break
        try:
            y, _ = newton_target(Kb, bb, g, F, xb)
        except np.linalg.LinAlgError:
            break
        st = 1.0
        while True:
            xt = xb + st * (y - xb)
            ph, _, _ = ac_phi(Kb, bb, g, F, xt)
            tn = 0.5 * ph @ ph
            if tn <= (1 - 1e-4 * st) * th or st < 2.0 ** -30:
                break
            st *= 0.5
        if st < 2.0 ** -30:
            break
        xb, th = xt, tn
        hist.append(float(np.sqrt(2 * th)))
    return xb, hist


def band_sweeps(Kb, bb, g, F, xb, sweeps=SWEEPS):
    """Forward / backward point sweeps of the band with the core's nodal Coulomb rule (frame (n, t))."""
    xb = xb.copy()
    k = len(g)
    # local (t, n) = (2j, 2j+1) -> the node frame (n, t) of the nodal rule: indices [2j+1, 2j]
    scale = max(float(np.abs(xb).max()), 1e-300)
    for s in range(sweeps):
        big = 0.0
        order = range(k) if s % 2 == 0 else range(k - 1, -1, -1)
        for j in order:
            ij = np.array([2 * j + 1, 2 * j])
            B = Kb[np.ix_(ij, ij)]
            rloc = bb[ij] - Kb[ij] @ xb + B @ xb[ij]
            old = xb[ij]
            new = _core.solve_node_coulomb_2D(np.ascontiguousarray(B), rloc, float(g[j]), float(F), old.copy(), 1)
            big = max(big, float(np.abs(new - old).max()))
            xb[ij] = new
        if big <= 1e-14 * scale:
            return xb, s + 1
    return xb, sweeps


def band_fixed_point(Kb, bb, g, F, xb, outer=60, inner=4000):
    """Algorithm 1 on the band alone: Tresca problems (convex; solved by point sweeps with the core's
    nodal Tresca rule) with the bound F r_n of the previous outer iterate, until the bound settles."""
    k = len(g)
    n = 2 * np.arange(k) + 1
    xb = xb.copy()
    hist = []
    for it in range(outer):
        r = bb - Kb @ xb
        bound = F * np.maximum(r[n], 0.0)
        scale = max(float(np.abs(xb).max()), 1e-300)
        for sw in range(inner):
            big = 0.0
            for j in (range(k) if sw % 2 == 0 else range(k - 1, -1, -1)):
                ij = np.array([2 * j + 1, 2 * j])
                B = Kb[np.ix_(ij, ij)]
                rloc = bb[ij] - Kb[ij] @ xb + B @ xb[ij]
                new = _core.solve_node_tresca_2D(np.ascontiguousarray(B), rloc, float(g[j]), float(bound[j]), 1)
                big = max(big, float(np.abs(new - xb[ij]).max()))
                xb[ij] = new
            if big <= 1e-15 * scale:
                break
        r = bb - Kb @ xb
        change = float(np.abs(F * np.maximum(r[n], 0.0) - bound).max())
        hist.append(change)
        if change <= 1e-13 * max(float(bound.max()), 1e-300):
            break
    return xb, hist


def point_gs_radius(Kb, bb, g, F, xb):
    """Spectral radius of the band's point Gauss-Seidel map (one forward + one backward sweep, as
    band_sweeps) linearized at xb for xb's state: active normals and sticking tangentials held,
    a sliding tangential solving its own row r_T - sign F r_n = 0, free nodes both rows of K."""
    k = len(g)
    n, t, z, act, stick, slip = band_state(Kb, bb, g, F, xb)
    J = Kb.copy()
    s = np.sign(z[slip])
    J[t[slip]] = Kb[t[slip]] - (s * F)[:, None] * Kb[n[slip]]
    keep = np.ones(2 * k, bool)
    keep[n[act]] = False
    keep[t[stick]] = False
    idx = np.nonzero(keep)[0]
    if len(idx) == 0:
        return 0.0
    Jf = J[np.ix_(idx, idx)]
    blk = idx // 2
    lower = blk[:, None] >= blk[None, :]
    upper = blk[:, None] <= blk[None, :]
    Lo, Up = np.where(lower, Jf, 0.0), np.where(upper, Jf, 0.0)
    Gf = -np.linalg.solve(Lo, Jf - Lo)
    Gb = -np.linalg.solve(Up, Jf - Up)
    return {"forward": float(np.abs(np.linalg.eigvals(Gf)).max()),
            "forward_backward": float(np.abs(np.linalg.eigvals(Gb @ Gf)).max()), "unknowns": int(len(idx))}


def band_step(S, F, x, changed):
    band, lmax = band_nodes(S, x, changed)
    info = {"band": int(len(band))}
    if len(band) == 0:
        return x, info
    dofs, Kb, bb, g = band_system(S, x, band)
    tol = BAND_TOL * lmax
    x0 = x[dofs]
    phi0 = float(np.linalg.norm(ac_phi(Kb, bb, g, F, x0)[0]))
    xb, hist = band_newton(Kb, bb, g, F, x0.copy(), tol)
    info.update(phi0=phi0, newton=len(hist) - 1, phi_newton=hist[-1], tol=tol)
    if hist[-1] > tol and CONTINUATION:
        xc = x0.copy()
        for Fk in np.geomspace(0.05, 1.0, 40) * F:
            xc, hk = band_newton(Kb, bb, g, Fk, xc, tol)
        if hk[-1] <= 1e3 * tol:  # the continuation's end stalls at |phi| ~ 1e-9 of max lam (near-singular)
            xb, hist = xc, hk
            info.update(phi_continuation=hk[-1], by="continuation")
    if info.get("by") == "continuation":
        pass
    elif hist[-1] > tol:
        xb, ns = band_sweeps(Kb, bb, g, F, x0)
        info.update(sweeps=ns, phi_sweeps=float(np.linalg.norm(ac_phi(Kb, bb, g, F, xb)[0])))
        info["by"] = "sweeps"
    else:
        info["by"] = "newton"
    assert np.all(xb[1::2] <= g + 1e-12 * max(1.0, float(np.abs(g).max()))), "band result penetrates"
    y = x.copy()
    y[dofs] = xb
    return y, info


def problem(H, L, F):
    from contactmg.hertz import hertz_problem
    return hertz_problem("triangle", L, F, coulomb_at_zero=True, hierarchy=H.truncated(L))


def run_cycles(H, L, F, mode, chunk=1, max_cycles=200):
    from contactmg.checks import contact_conditions
    p = problem(H, L, F)
    S = hertz_system(p)
    C = np.asarray(p.contact.nodes)
    u, cycles, hist, bands, changes = None, 0, [], [], []
    prev = [np.zeros(len(C), int)]
    t0 = time.perf_counter()
    r = None
    while cycles < max_cycles:
        r = p.solve("nmg", tol=1e-11, max_cycles=min(chunk, max_cycles - cycles), threads=1, u0=u)
        cycles += int(r.cycles)
        hist += [float(c) for c in r.history["correction_norm"]]
        u = np.asarray(r.displacement).copy()
        st = np.asarray(r.node_state)[C].astype(int)
        changes.append(int(np.count_nonzero(st != prev[-1])))
        if r.converged:
            break
        if mode == "on":
            changed = np.nonzero((st != prev[-1]) | (st != prev[-2] if len(prev) > 1 else False))[0]
            x = S["D"] * u.ravel()
            y, info = band_step(S, F, x, changed)
            info["cycle"] = cycles
            info["move"] = energy_norm(p, S["D"] * (y - x))
            bands.append(info)
            u = (S["D"] * y).reshape(-1, 2)
        prev.append(st)
    sec = time.perf_counter() - t0
    viol = float(contact_conditions(p, r)["max"]) if r.converged else float("nan")
    return {"level": L, "F": F, "mode": mode, "chunk": chunk, "cycles": cycles, "converged": bool(r.converged),
            "violation": viol, "ok": bool(r.converged) and viol <= 1e-8, "seconds": sec,
            "correction_norm": hist, "band_steps": bands, "state_changes": changes,
            "last_state_change": int(max([i + 1 for i, c in enumerate(changes) if c > 0], default=0)),
            "final": {"active": int(np.count_nonzero(st > 0)), "slip": int(np.count_nonzero(st == 2))}}, u


def cmd_cycles(a, H):
    rows = []
    print("| L | F | mode | chunk | cycles | last state change | violation | band nodes (median / max) | by newton / sweeps | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for L in a.levels:
        for F in a.frictions:
            uoff = None
            for mode in a.modes:
                res, u = run_cycles(H, L, F, mode, a.chunk, a.max_cycles)
                if mode == "off":
                    uoff = u
                elif uoff is not None and res["converged"]:
                    res["relative_difference_to_off"] = float(np.abs(u - uoff).max() / np.abs(uoff).max())
                b = res["band_steps"]
                nb = [s["band"] for s in b]
                bys = [s.get("by") for s in b]
                res["continuation_steps"] = bys.count("continuation")
                print(f"| {L} | {F:g} | {mode} | {a.chunk} | {res['cycles']}{'' if res['ok'] else '!'} | {res['last_state_change']} | {res['violation']:.1e} | "
                      + (f"{int(np.median(nb))} / {max(nb)} | {bys.count('newton')} / {bys.count('sweeps')}"
                   + (f" (+{bys.count('continuation')} by continuation)" if CONTINUATION else "") if nb else "- | -")
                      + f" | {res['seconds']:.0f} |", flush=True)
                rows.append(res)
                if a.json:
                    with open(a.json, "w") as fh:
                        json.dump(rows, fh, indent=1)


def cmd_limit(a, H):
    L, F = a.level, a.friction
    p = problem(H, L, F)
    S = hertz_system(p)
    C = np.asarray(p.contact.nodes)
    r = p.solve("nmg", tol=1e-11, max_cycles=a.cycles, threads=1)
    c = r.history["correction_norm"]
    print(f"L{L} F = {F:g}: {r.cycles} cycles, converged {r.converged}, last corrections "
          + " ".join(f"{v:.3e}" for v in c[-6:]), flush=True)
    x = S["D"] * np.asarray(r.displacement).ravel()
    out = {"level": L, "F": F, "cycles": int(r.cycles), "corrections": [float(v) for v in c], "bands": []}
    xc_all = np.abs(p.mesh.points[C, 0])
    fixed = S["fixed"]
    free_c = ~(fixed[S["n"]] | fixed[S["t"]])
    for ring in ("lam+ring", "x 0.0312-0.0336", "x 0.030-0.0345"):
        band, lmax = band_nodes(S, x, np.zeros(0, int), ring=(ring == "lam+ring"))
        if ring.startswith("x "):
            lo, hi = (float(v) for v in ring[2:].split("-"))
            band = np.nonzero((xc_all >= lo) & (xc_all <= hi) & free_c)[0]
        # band = the small-lam nodes (+ ring); also the full edge: every contact node within the last 0.003 of the zone
        dofs, Kb, bb, g = band_system(S, x, band)
        tol = BAND_TOL * lmax
        x0 = x[dofs]
        phi0 = float(np.linalg.norm(ac_phi(Kb, bb, g, F, x0)[0]))
        t0 = time.perf_counter()
        xb, hist = band_newton(Kb, bb, g, F, x0.copy(), tol)
        xs, ns = band_sweeps(Kb, bb, g, F, x0, sweeps=20000)
        phis = float(np.linalg.norm(ac_phi(Kb, bb, g, F, xs)[0]))
        # other starts for Newton: the sweeps' result, and continuation in F from the iterate
        xn2, h2 = band_newton(Kb, bb, g, F, xs.copy(), tol)
        xc, cont = x0.copy(), []
        for Fk in np.geomspace(0.05, 1.0, 40) * F:
            xc, hk = band_newton(Kb, bb, g, Fk, xc, BAND_TOL * lmax)
            cont.append({"F": Fk, "steps": len(hk) - 1, "phi": hk[-1]})
        # the continuation's end, judged on its own: residual, fixed point of the point rule, state
        phic = float(np.linalg.norm(ac_phi(Kb, bb, g, F, xc)[0]))
        xcs, _ = band_sweeps(Kb, bb, g, F, xc, sweeps=1)
        xcs200, _ = band_sweeps(Kb, bb, g, F, xc, sweeps=200)
        _, lamc, zc = ac_phi(Kb, bb, g, F, xc)
        actc = lamc > 0
        stc = actc & (np.abs(zc) <= F * lamc)
        cont_rec = {"phi": phic, "phi_rel": phic / lmax, "one_sweep_move": float(np.abs(xcs - xc).max() / np.abs(xc).max()),
                    "sweeps200_move": float(np.abs(xcs200 - xc).max() / np.abs(xc).max()),
                    "state": {"active": int(actc.sum()), "stick": int(stc.sum()), "slip": int((actc & ~stc).sum())},
                    "distance_from_iterate": float(np.abs(xc - x0).max() / np.abs(x0).max())}
        cont_rec["point_gs_radius"] = point_gs_radius(Kb, bb, g, F, xc)
        # other solutions? Newton from random starts between the iterate and the continuation's end
        rng = np.random.default_rng(0)
        others = []
        for _ in range(10):
            w = rng.uniform(0, 1, size=len(g)).repeat(2)
            xs0 = x0 + w * (xc - x0)
            xo, ho = band_newton(Kb, bb, g, F, xs0, 1e-9 * lmax)
            others.append({"phi": ho[-1], "steps": len(ho) - 1,
                           "distance_to_continuation": float(np.abs(xo - xc).max() / np.abs(xc).max())})
        print(f"  continuation end: |phi| / max lam {phic / lmax:.1e}, one sweep moves it {cont_rec['one_sweep_move']:.1e}, "
              f"200 sweeps {cont_rec['sweeps200_move']:.1e}, linearized point GS radius {cont_rec['point_gs_radius']}, state {cont_rec['state']}, from the iterate {cont_rec['distance_from_iterate']:.1e}; "
              "newton from 10 mixed starts: " + ", ".join(f"{o['phi'] / lmax:.0e}@{o['distance_to_continuation']:.0e}" for o in others), flush=True)
        xq, fp = band_fixed_point(Kb, bb, g, F, x0, outer=20, inner=2000)
        phiq = float(np.linalg.norm(ac_phi(Kb, bb, g, F, xq)[0]))
        found = [v for v, h in ((xb, hist[-1]), (xn2, h2[-1]), (xc, cont[-1]["phi"]), (xq, phiq)) if h <= tol]
        spread = (max(float(np.abs(v - found[0]).max()) for v in found) / max(np.abs(found[0]).max(), 1e-300)
                  if found else None)
        # is Newton's solution a fixed point of the point rule?
        xf, nf = band_sweeps(Kb, bb, g, F, xb, sweeps=1)
        _, lam, z = ac_phi(Kb, bb, g, F, xb)
        act = lam > 0
        stick = act & (np.abs(z) <= F * lam)
        xpos = p.mesh.points[C[band], 0]
        rec = {"ring": ring, "band": int(len(band)), "x_range": [float(np.abs(xpos).min()), float(np.abs(xpos).max())],
               "phi0": phi0, "tol": tol, "newton_hist": hist, "newton_converged": hist[-1] <= tol,
               "sweeps": ns, "phi_sweeps": phis, "sweeps_vs_newton": float(np.abs(xs - xb).max() / max(np.abs(xb).max(), 1e-300)),
               "newton_fixed_point_move": float(np.abs(xf - xb).max() / max(np.abs(xb).max(), 1e-300)),
               "newton_state": {"active": int(act.sum()), "stick": int(stick.sum()), "slip": int((act & ~stick).sum())},
               "move_from_iterate": float(np.abs(xb - x0).max() / max(np.abs(x0).max(), 1e-300)),
               "continuation_end": cont_rec, "newton_mixed_starts": others,
               "fixed_point_bound_changes": fp, "phi_fixed_point": phiq,
               "newton_from_sweeps": h2, "continuation": cont, "solutions_found": len(found),
               "solutions_spread": spread,
               "seconds": time.perf_counter() - t0}
        print(f"band {ring}: {len(band)} nodes |x| {rec['x_range'][0]:.4f}-{rec['x_range'][1]:.4f}, |phi0| {phi0:.1e}; "
              f"newton from iterate {len(hist) - 1} steps |phi| {hist[-1]:.1e}, from sweeps {len(h2) - 1} steps {h2[-1]:.1e}, "
              f"continuation {cont[-1]['phi']:.1e}; band Algorithm 1 {len(fp)} outer, bound change {fp[-1]:.1e}, |phi| {phiq:.1e}; point sweeps {ns} -> |phi| {phis:.1e}; solutions found {len(found)}, "
              f"spread {spread if spread is None else f'{spread:.1e}'}; state {rec['newton_state']}, "
              f"newton's solution moved by one sweep {rec['newton_fixed_point_move']:.1e}", flush=True)
        out["bands"].append(rec)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


def cmd_smoother(a, H):
    """Sweeps alone against sweeps + the band step, from the default solve's --cycles-th iterate
    (no coarse correction): is the fine smoother with the band block stable at F = 40?"""
    global CONTINUATION
    CONTINUATION = True
    L, F = a.level, a.friction
    p = problem(H, L, F)
    S = hertz_system(p)
    C = np.asarray(p.contact.nodes)
    r = p.solve("nmg", tol=1e-11, max_cycles=a.cycles, threads=1)
    solver = p.core_solver()
    u_start = np.asarray(r.displacement).copy()
    out = {"level": L, "F": F, "cycles": int(r.cycles), "arms": []}
    for arm in ("sweeps", "sweeps+band"):
        u = u_start.copy()
        rows = []
        st_prev = None
        for blk in range(a.blocks):
            u = np.asarray(_core.testing.smooth(solver, u, a.block_sweeps, "lexicographic", 1))
            one = np.asarray(_core.testing.smooth(solver, u, 1, "lexicographic", 1))
            move = energy_norm(p, one - u)
            x = S["D"] * u.ravel()
            rn = (S["b"] - S["K"] @ x)[S["n"]]
            diag = S["K"].diagonal()
            lamv = rn + diag[S["n"]] * (x[S["n"]] - S["g"])
            zt = (S["b"] - S["K"] @ x)[S["t"]] + diag[S["t"]] * x[S["t"]]
            state = np.where(lamv <= 0, 0, np.where(np.abs(zt) <= F * lamv, 1, 2))
            changed = np.zeros(0, int) if st_prev is None else np.nonzero(state != st_prev)[0]
            cmove = float(np.abs((one - u)[C]).max())
            rec = {"block": blk + 1, "one_sweep_move": move, "contact_max_move": cmove, "changed": int(len(changed)),
                   "slip": int(np.count_nonzero(state == 2)), "active": int(np.count_nonzero(state > 0))}
            if arm == "sweeps+band":
                y, info = band_step(S, F, x, changed)
                rec["band"] = info["band"]
                rec["by"] = info.get("by")
                u = (S["D"] * y).reshape(-1, 2)
            st_prev = state
            rows.append(rec)
            if blk % 10 == 9 or blk == a.blocks - 1:
                print(f"{arm}: block {blk + 1} ({(blk + 1) * a.block_sweeps} sweeps): one-sweep move {move:.2e} (max on contact nodes {cmove:.1e}), "
                      f"changed {rec['changed']}, active {rec['active']}, slip {rec['slip']}"
                      + (f", band {rec['band']} by {rec['by']}" if 'band' in rec else ""), flush=True)
        out["arms"].append({"arm": arm, "rows": rows})
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["cycles", "limit", "smoother"])
    ap.add_argument("--blocks", type=int, default=100)
    ap.add_argument("--block-sweeps", type=int, default=10)
    ap.add_argument("--levels", type=int, nargs="+", default=[7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.4, 2.0, 5.0, 8.0, 40.0])
    ap.add_argument("--modes", nargs="+", choices=["off", "on"], default=["off", "on"])
    ap.add_argument("--chunk", type=int, default=1)
    ap.add_argument("--max-cycles", type=int, default=200)
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--friction", type=float, default=40.0)
    ap.add_argument("--cycles", type=int, default=60)
    ap.add_argument("--continuation", action="store_true")
    ap.add_argument("--json")
    a = ap.parse_args()
    global CONTINUATION
    CONTINUATION = a.continuation
    from cycle_growth import adaptive_hierarchy
    H = adaptive_hierarchy(11)
    {"cycles": cmd_cycles, "limit": cmd_limit, "smoother": cmd_smoother}[a.mode](a, H)


if __name__ == "__main__":
    main()
