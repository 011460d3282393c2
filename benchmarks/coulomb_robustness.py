"""Algorithm 2 on the Coulomb cases that stalled or were slow (issue 14 part 1), with the before
figures measured with the core of main before this change (benchmarks/results/coulomb_robustness_before.json).

    python benchmarks/coulomb_robustness.py [--cases adaptive9 uniform8 ...] [--out out] [--save-as NAME]

Cases: adaptive Hertz level 9 (59k dofs) at F = 5, 8, 20, 40, 100; adaptive level 11 (465k dofs) at
F = 5, 8, 40; uniform triangles level 8 / 9 at F = 5 (592k / 2.36M dofs); the tetrahedral sphere level
3 (129k dofs) at F = 0.4 and 40. Every result is checked by contactmg.checks.contact_conditions
(relative violation <= 1e-6 counts as verified). Seconds are wall clock on a shared machine.
"""
import argparse
import json
import os
import sys
import time

from contactmg.checks import VIOLATION_TOL, contact_conditions
from contactmg.hertz import hertz_adaptive_hierarchy, hertz_problem

HERE = os.path.dirname(os.path.abspath(__file__))
BEFORE = os.path.join(HERE, "results", "coulomb_robustness_before.json")


def cases(names):
    if "adaptive9" in names or "adaptive11" in names:
        levels = 11 if "adaptive11" in names else 9
        h = hertz_adaptive_hierarchy(levels, 0.4)
        if "adaptive9" in names:
            for F in (5.0, 8.0, 20.0, 40.0, 100.0):
                yield f"adaptive L9 F={F:g}", lambda F=F: hertz_problem(friction=F, hierarchy=h.truncated(9), coulomb_at_zero=True)
        if "adaptive11" in names:
            for F in (5.0, 8.0, 40.0):
                yield f"adaptive L11 F={F:g}", lambda F=F: hertz_problem(friction=F, hierarchy=h, coulomb_at_zero=True)
    for L in (8, 9):
        if f"uniform{L}" in names:
            yield f"uniform tri L{L} F=5", lambda L=L: hertz_problem(levels=L, friction=5.0)
    if "sphere3" in names:
        from contactmg.sphere import sphere_problem
        for F in (0.4, 40.0):
            yield f"sphere tetra L3 F={F:g}", lambda F=F: sphere_problem("tetra", 3, F)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", nargs="+", default=["adaptive9", "uniform8", "sphere3"],
                    help="adaptive9 adaptive11 uniform8 uniform9 sphere3")
    ap.add_argument("--max-cycles", type=int, default=200)
    ap.add_argument("--out", default="out")
    ap.add_argument("--save-as", default="coulomb_robustness", help="JSON name under --out")
    a = ap.parse_args()
    before = json.load(open(BEFORE)) if os.path.exists(BEFORE) else {}
    rows = {}
    print(f"{'case':26s} {'dofs':>9s} {'before':>22s} {'cycles':>7s} {'status':>12s} {'violation':>9s} {'seconds':>8s}")
    for name, make in cases(a.cases):
        p = make()
        t = time.perf_counter()
        r = p.solve(max_cycles=a.max_cycles)
        sec = time.perf_counter() - t
        v = contact_conditions(p, r)["max"]
        ok = r.converged and v <= VIOLATION_TOL
        rows[name] = {"dofs": int(p.load.size), "cycles": r.cycles, "converged": r.converged, "verified": bool(ok),
                      "status": r.status, "violation": v, "seconds": sec}
        b = before.get(name)
        bs = "-" if b is None else (f"{b['cycles']}" if b["verified"] else f"{b['status'][:14]} ({b['cycles']})")
        print(f"{name:26s} {p.load.size:9d} {bs:>22s} {r.cycles:7d} {('verified' if ok else r.status[:12]):>12s} "
              f"{v:9.1e} {sec:8.1f}", flush=True)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, a.save_as + ".json"), "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    sys.exit(main())
