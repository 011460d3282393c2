"""Published verification problems of two and three bodies in contact, against their closed-form
solutions: a steel roller on an aluminium block (two-body Hertz, full and half model), two
concentric rings (Lame, and Michell for a cos 2 theta load), two concentric hollow spheres (Lame),
two equal hemispheres pressed together (symmetry; against one hemisphere on a rigid plane), three
blocks stacked on a floor without supports, and the roller and the rings on their coarse mesh alone.

The scenes are built in two_body_scenes.py (gmsh meshes, public contactmg API). Per scene a table of
the measured figures next to their targets; for every solve also the largest violation of the
discrete contact conditions of the contact nodes (contactmg.results.checks.contact_conditions:
relative to the force scale, penetration to the displacement scale), the nonmortar facet nodes that
carry no condition of their own (held along their normal by Dirichlet data, or facing the mortar
side over too little of their support: taken out by the boundary modification of the dual basis).

Run: python benchmarks/model/two_body_verification.py [--quick]"""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
from _common import parser, write_result  # noqa: E402

import two_body_scenes as sc  # noqa: E402
from contactmg.results.checks import contact_conditions  # noqa: E402


def pressure(res):
    """Contact pressure of the contact nodes (positive in compression)."""
    return -np.asarray(res.normal_stress)


def solve(make):
    """Builds and solves; the common facts of the solve."""
    t0 = time.perf_counter()
    p = make()
    t1 = time.perf_counter()
    r = p.solve()
    t2 = time.perf_counter()
    lo = sc.nonmortar_nodes_left_out(p)
    row = {"dofs": int(p.mesh.num_points * p.mesh.dim), "cycles": r.cycles, "converged": bool(r.converged),
           "conditions": contact_conditions(p, r)["max"],
           "left_out": "+".join(f"{d['left_out']}/{d['total']}" for d in lo),
           "held": sum(d["held"] or 0 for d in lo), "uncovered": sum(d["uncovered"] or 0 for d in lo),
           "setup_s": round(t1 - t0, 2), "solve_s": round(t2 - t1, 2)}
    return p, r, row


def fmt(v):
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.1e}"
    return "-" if v is None else str(v)


def table(title, rows, keys):
    print(f"\n== {title}")
    if not rows:
        return
    cells = [[fmt(r.get(k)) for k in keys] for r in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) for i, k in enumerate(keys)]
    print("  ".join(k.ljust(w) for k, w in zip(keys, widths)))
    for c in cells:
        print("  ".join(v.ljust(w) for v, w in zip(c, widths)))


COMMON = ["dofs", "cycles", "converged", "conditions", "left_out", "held", "uncovered",
          "setup_s", "solve_s"]


def roller(levels):
    """Peak pressure and half-width against p0 and b; the half model against the full one."""
    b, p0 = sc.roller_hertz()
    rows = []
    for friction in (0.0, 0.1):
        for half in (False, True):
            for lv in levels:
                p, r, row = solve(lambda: sc.roller_problem(half, lv, friction))
                pr = pressure(r)
                x = p.mesh.points[p.contact.nodes, 0]
                pressed = pr > 1e-9 * pr.max()
                row = {"model": "half" if half else "full", "friction": friction,
                       "h": sc.ROLLER_H0 / 2 ** (lv - 1), **row,
                       "peak": float(pr.max()), "peak/p0-1": float(pr.max() / p0 - 1),
                       "halfwidth": float(np.abs(x[pressed]).max()),
                       "halfwidth/b-1": float(np.abs(x[pressed]).max() / b - 1),
                       "x_of_peak": float(x[np.argmax(pr)])}
                rows.append(row)
    for row in rows:
        if row["model"] == "half":
            full = next(f for f in rows if f["model"] == "full" and f["h"] == row["h"] and f["friction"] == row["friction"])
            row["half/full-1"] = row["peak"] / full["peak"] - 1
    table(f"1. roller on block: p0 = {p0:.1f}, b = {b:.3f}  [peak within 1 % at h = 0.125, half = full to 0.5 %, "
          "cycles <= 20, spread <= 3]", rows,
          ["model", "friction", "h"] + COMMON[:4] + ["peak/p0-1", "half/full-1", "halfwidth/b-1", "x_of_peak"]
          + COMMON[4:])
    return {"p0": p0, "b": b, "rows": rows}


def fit_cos2(p, r):
    """Least-squares q0 + q2 cos 2 theta of the nodal pressure of the contact nodes in contact."""
    pr = pressure(r)
    x = p.mesh.points[p.contact.nodes]
    th = np.arctan2(x[:, 1], x[:, 0])
    on = pr > 1e-9 * pr.max()
    q, *_ = np.linalg.lstsq(np.c_[np.ones(on.sum()), np.cos(2 * th[on])], pr[on], rcond=None)
    return q, pr, on


def rings(levels, size=10.0):
    """Uniform pressure against Lame; the cos 2 theta load's fitted amplitude against Michell."""
    q_lame = sc.rings_lame()
    q2 = sc.rings_michell()
    rows = []
    for p2 in (0.0, sc.RING_P2):
        for lv in levels:
            p, r, row = solve(lambda: sc.rings_problem(lv, size, p2=p2))
            q, pr, on = fit_cos2(p, r)
            total = sum(d["total"] for d in sc.nonmortar_nodes_left_out(p))
            row = {"load": "p0" if p2 == 0 else "p0 + p2 cos2", "h_inner": size / 2 ** (lv - 1), **row,
                   "in_contact": f"{int(on.sum())}/{total}",
                   "pmin/q-1": float(pr[on].min() / q_lame - 1) if p2 == 0 else None,
                   "pmax/q-1": float(pr[on].max() / q_lame - 1) if p2 == 0 else None,
                   "q0/q-1": float(q[0] / q_lame - 1), "q2/q2_exact-1": float(q[1] / q2 - 1) if p2 else None}
            rows.append(row)
    table(f"2. concentric rings: Lame q = {q_lame:.3f}, Michell q2 = {q2:.3f}  [cos 2 amplitude within 10 % at the "
          "third size]", rows, ["load", "h_inner"] + COMMON[:4] + ["in_contact", "pmin/q-1", "pmax/q-1", "q0/q-1",
                                                                    "q2/q2_exact-1"] + COMMON[4:])
    return {"lame_q": q_lame, "michell_q2": q2, "p0": sc.RING_P0, "p2": sc.RING_P2, "rows": rows}


def shells(levels, size=0.25):
    q_lame = sc.shells_lame()
    rows = []
    for lv in levels:
        p, r, row = solve(lambda: sc.shells_problem(lv, size))
        pr = pressure(r)
        on = pr > 1e-9 * pr.max()
        total = sum(d["total"] for d in sc.nonmortar_nodes_left_out(p))
        rows.append({"refinements": lv - 1, **row, "in_contact": f"{int(on.sum())}/{total}",
                     "pmin/q-1": float(pr[on].min() / q_lame - 1), "pmax/q-1": float(pr[on].max() / q_lame - 1),
                     "pmean/q-1": float(pr[on].mean() / q_lame - 1)})
    table(f"3. concentric hollow spheres: Lame q = {q_lame:.1f}  [all in contact; within 2 % at the second "
          "refinement]", rows, ["refinements"] + COMMON[:4] + ["in_contact", "pmin/q-1", "pmax/q-1", "pmean/q-1"]
          + COMMON[4:])
    return {"lame_q": q_lame, "pressure": sc.SHELL_P, "rows": rows}


def hemispheres(levels, h0=0.04):
    a, p0 = sc.hemisphere_hertz()
    rows = []
    for lv in levels:
        q, r1, row1 = solve(lambda: sc.hemisphere_on_plane_problem(lv, h0))
        pr1 = pressure(r1)
        rows.append({"body": "one on plane", "h": h0 / 2 ** (lv - 1), **row1, "peak": float(pr1.max()),
                     "peak/p0-1": float(pr1.max() / p0 - 1)})
        # the quarter model, and the whole hemispheres (no symmetry planes) for comparison
        for quarter in (True, False):
            p, r, row = solve(lambda: sc.hemispheres_problem(lv, h0, quarter=quarter))
            pr = pressure(r)
            on = pr > 1e-9 * pr.max()
            # where the nonmortar nodes in contact are now: on the plane z = 0 by symmetry
            nodes = p.contact.nodes[on]
            shift = float((p.mesh.points[nodes, 2] + np.asarray(r.displacement)[nodes, 2]).mean())
            rows.append({"body": "two, quarter" if quarter else "two, whole", "h": h0 / 2 ** (lv - 1), **row,
                         "shift/approach": shift / sc.HEMI_APPROACH, "peak": float(pr.max()),
                         "peak/p0-1": float(pr.max() / p0 - 1), "peak two/one-1": float(pr.max() / pr1.max() - 1)})
    table(f"4. equal hemispheres: Hertz a = {a:.3f}, p0 = {p0:.1f}  [shift < 1 %, two = one to 1 %]", rows,
          ["body", "h"] + COMMON[:4] + ["shift/approach", "peak/p0-1", "peak two/one-1"] + COMMON[4:])
    return {"hertz_a": a, "hertz_p0": p0, "approach": sc.HEMI_APPROACH, "rows": rows}


def stack(size, levels_fallback=3, size_fallback=0.2):
    rows = []
    for name, make in (("coarsened", lambda: sc.stack_problem(size)),
                       (f"refined ({levels_fallback} levels)", lambda: sc.stack_problem(size_fallback, levels_fallback))):
        try:
            p, r, row = solve(make)
        except ValueError as e:
            rows.append({"hierarchies": name, "refused": str(e)})
            continue
        bal = sc.body_balance(r)
        rows.append({"hierarchies": name, **row, "levels": [b.hierarchy.levels for b in p.bodies],
                     "balance_max": max(bal), "balance": bal})
    table("5. three blocks stacked on a floor  [balance per body 1e-8, cycles <= 25]", rows,
          ["hierarchies", "refused", "levels"] + COMMON[:4] + ["balance_max"] + COMMON[4:])
    return {"rows": rows}


def coarse_alone():
    rows = []
    for name, make in (("roller (full)", lambda: sc.roller_problem(False, 1)),
                       ("rings (p0)", lambda: sc.rings_problem(1, p2=0.0)),
                       ("rings (p0 + p2 cos2)", lambda: sc.rings_problem(1))):
        p, r, row = solve(make)
        rows.append({"scene": name, **row, "notes": "; ".join(getattr(p, "notes", []) or [])})
    table("6. the coarse mesh as the only level  [cycles <= 30]", rows, ["scene"] + COMMON + ["notes"])
    return {"rows": rows}


def main():
    args = parser(__doc__).parse_args()
    q = args.quick
    t0 = time.perf_counter()
    out = {}
    for key, run in (("roller", lambda: roller([3] if q else [3, 4, 5])),
                     ("rings", lambda: rings([3] if q else [3, 4, 5])),
                     ("shells", lambda: shells([1] if q else [1, 2, 3])),
                     ("hemispheres", lambda: hemispheres([1] if q else [1, 2])),
                     ("stack", lambda: stack(0.1 if q else 0.05)),
                     ("coarse_alone", coarse_alone)):
        t = time.perf_counter()
        out[key] = run()
        out[key]["seconds"] = round(time.perf_counter() - t, 1)
        print(f"({key}: {out[key]['seconds']} s)")
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")
    write_result(__file__, args, out)


if __name__ == "__main__":
    main()
