"""Algorithm 2 ("nmg") and truncated nonsmooth Newton multigrid ("tnnmg", issue 14) side by side:
cycles, solve seconds, agreement, over the paper's friction coefficients on uniform Hertz
hierarchies (triangles and quads) and the stress cases of benchmarks/stress.py.

    python benchmarks/tnnmg_compare.py [--tri 3 7] [--quad 3 6] [--stress-level 7] [--out out]

Timings are wall-clock seconds on whatever else the machine is running (state it when quoting).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import stress  # noqa: E402

from contactmg import hertz  # noqa: E402
from contactmg.checks import contact_conditions  # noqa: E402

METHODS = ("nmg", "tnnmg")


def compare(name, problem, rows, max_cycles):
    res = {m: problem.solve(m, max_cycles=max_cycles) for m in METHODS}
    a, b = res["nmg"], res["tnnmg"]
    agree = (float(np.abs(a.displacement - b.displacement).max() / max(np.abs(a.displacement).max(), 1e-300))
             if a.converged and b.converged else float("nan"))
    for m, r in res.items():
        row = {"case": name, "method": m, "converged": r.converged, "status": r.status, "cycles": r.cycles,
               "seconds": r.solve_seconds, "violation": contact_conditions(problem, r)["max"], "agreement": agree}
        rows.append(row)
        print(f"{name:28s} {m:6s} {('ok' if r.converged else r.status[:12]):>12s} {r.cycles:6d} {r.solve_seconds:8.2f} "
              f"{row['violation']:9.1e} {agree:9.1e}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tri", type=int, nargs=2, default=(3, 7))
    ap.add_argument("--quad", type=int, nargs=2, default=(3, 6))
    ap.add_argument("--frictions", type=float, nargs="*", default=list(hertz.PAPER_FRICTIONS))
    ap.add_argument("--stress-level", type=int, default=7)
    ap.add_argument("--max-cycles", type=int, default=300)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    rows = []
    print(f"{'case':28s} {'method':6s} {'status':>12s} {'cycles':>6s} {'seconds':>8s} {'violation':>9s} {'|du|/|u|':>9s}")
    for cell, (l0, l1) in (("triangle", a.tri), ("quad", a.quad)):
        for L in range(l0, l1 + 1):
            for F in a.frictions:
                compare(f"hertz {cell} L{L} F={F:g}", hertz.hertz_problem(cell, L, F), rows, a.max_cycles)
    if a.stress_level > 0:
        h = hertz.hertz_problem("triangle", a.stress_level, 0.4).hierarchy
        for name, make in ((f"nu=0.45 L{a.stress_level}", lambda: stress.hertz_scene(h, nu=0.45)),
                           (f"nu=0.49 L{a.stress_level}", lambda: stress.hertz_scene(h, nu=0.49)),
                           ("layer quads aspect 8", lambda: stress.layer(8)),
                           ("layer quads aspect 32", lambda: stress.layer(32))):
            compare(name, make(), rows, a.max_cycles)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "tnnmg_compare.json"), "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
