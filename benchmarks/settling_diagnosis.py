"""What changes in Algorithm 2's settling cycles on adaptive Hertz level 11 at F = 5 / 8 (issue 11,
seventh part; docs/history/adaptive.md): the contact state of every contact node after every cycle.

    python benchmarks/settling_diagnosis.py [--level 11] [--frictions 5 8] [--json ...]

The core reports only counts per cycle, so the state after cycle k is taken from a solve stopped
after k cycles (max_cycles = k) by a fresh core solver each time (a kept one's incremental coarse
updates depend on the solves before: the trajectory would not be the same bit for bit); F(3,3),
from u = 0, one thread. Per cycle: the nodes that changed state (free / stick / slip) and the
transitions, the outermost contact node on each side (the contact edge), the stick-slip boundary,
the correction norm. Costs sum_k k cycles (level 11, F = 8: about 1,500 cycles, 5 min).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

NAMES = {0: "free", 1: "stick", 2: "slip"}


def states(L, F, H, n_max):
    from contactmg.hertz import hertz_problem

    p = hertz_problem("triangle", L, F, coulomb_at_zero=True, hierarchy=H.truncated(L))
    nodes = p.contact.nodes
    x = p.mesh.points[nodes, 0]
    full = p.solve("nmg", tol=1e-11, max_cycles=n_max, threads=1)
    n = int(full.cycles)
    out = []
    for k in range(1, n + 1):
        p._solvers.clear()  # a fresh core solver: the same trajectory as the full solve's first k cycles
        r = p.solve("nmg", tol=1e-11, max_cycles=k, threads=1)
        out.append(np.asarray(r.node_state)[nodes].astype(int))
    p._solvers.clear()
    again = p.solve("nmg", tol=1e-11, max_cycles=n_max, threads=1)
    assert again.cycles == n, "a fresh solver does not repeat the trajectory"
    return x, np.array(out), full


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--frictions", type=float, nargs="+", default=[5.0, 8.0])
    ap.add_argument("--json")
    a = ap.parse_args()
    from cycle_growth import adaptive_hierarchy
    H = adaptive_hierarchy(max(11, a.level))
    res = []
    for F in a.frictions:
        t0 = time.perf_counter()
        x, S, full = states(a.level, F, H, 200)
        c = full.history["correction_norm"]
        print(f"\nlevel {a.level}, F = {F:g}: {len(S)} cycles ({time.perf_counter() - t0:.0f} s); final: "
              + ", ".join(f"{np.count_nonzero(S[-1] == s)} {NAMES[s]}" for s in (0, 1, 2)))
        print("| cycle | correction | changed | transitions | contact edge x (left / right) | slip x range | changed x |")
        print("|---|---|---|---|---|---|---|")
        rows = []
        prev = np.zeros_like(S[0])
        for k, s in enumerate(S):
            ch = np.nonzero(s != prev)[0]
            trans = {}
            for i in ch:
                key = f"{NAMES[prev[i]]}->{NAMES[s[i]]}"
                trans[key] = trans.get(key, 0) + 1
            act = np.nonzero(s > 0)[0]
            slip = np.nonzero(s == 2)[0]
            edge = (float(x[act].min()), float(x[act].max())) if len(act) else (np.nan, np.nan)
            sl = (float(x[slip].min()), float(x[slip].max())) if len(slip) else (np.nan, np.nan)
            cx = sorted(set(np.round(x[ch], 5).tolist()))
            rows.append({"cycle": k + 1, "correction_norm": float(c[k]), "changed": int(len(ch)), "transitions": trans,
                         "edge": edge, "slip_range": sl, "changed_x": cx,
                         "changed_nodes": [int(i) for i in ch]})
            print(f"| {k + 1} | {c[k]:.1e} | {len(ch)} | " + ", ".join(f"{t} {m}" for t, m in sorted(trans.items()))
                  + f" | {edge[0]:+.4f} / {edge[1]:+.4f} | {sl[0]:+.4f} .. {sl[1]:+.4f} | "
                  + " ".join(f"{v:+.4f}" for v in cx[:8]) + (" ..." if len(cx) > 8 else "") + " |", flush=True)
            prev = s
        # the nodes that changed state most often, where they sit
        flips = (S[1:] != S[:-1]).sum(axis=0)
        top = np.argsort(-flips)[:12]
        print("most changes: " + ", ".join(f"x={x[i]:+.4f} ({flips[i]}x, final {NAMES[S[-1][i]]})" for i in top if flips[i] > 0))
        res.append({"level": a.level, "F": F, "cycles": len(S), "rows": rows,
                    "most_changes": [{"x": float(x[i]), "changes": int(flips[i]), "final": NAMES[int(S[-1][i])]}
                                     for i in top if flips[i] > 0]})
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
