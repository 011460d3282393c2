"""Does Algorithm 1 (fixed point) fail for F = 5 on the finest uniform level that fits?

The paper's Algorithm 1 stops converging for F = 5 from its adaptive level 9 on (44,200 dofs,
refined towards the contact zone). Here the hierarchy is uniform: levels are tried from --start
upwards, each in a fresh process with a time limit per level (--budget seconds, default 600 s for
the two solves). Nothing is tuned: the defaults of the package (tol 1e-11, fixed-point tolerance
1e-9, at most 100 outer iterations) as in Table 1. For each level it reports the fixed-point status, outer
iterations and V-cycles, Algorithm 2's cycles, both solves' times and how well each result satisfies
the discrete contact conditions (contactmg.checks), and the energy-norm difference of the two
results. It stops after the first level that does not finish within the budget, or before a level
whose expected time (5x the last one) exceeds 3x the budget.

    python benchmarks/fixed_point_F5.py [--cell triangle] [--friction 5] [--start 3] [--stop 11] [--budget 600] [--out out]
"""
import argparse
import json
import os
import subprocess
import sys
import time

WORKER = r"""
import json, sys, time, resource
import numpy as np
from contactmg import hertz
from contactmg.checks import contact_conditions
cell, L, F = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
p = hertz.hertz_problem(cell, L, F, coulomb_at_zero=True)
out = {"level": L, "cell": cell, "friction": F, "nodes": int(p.mesh.num_points), "dofs": int(2 * p.mesh.num_points)}
nm = p.solve("nmg")
out.update(setup_seconds=p.setup_seconds, nmg_cycles=nm.cycles, nmg_converged=nm.converged, nmg_seconds=nm.solve_seconds,
           nmg_violation=contact_conditions(p, nm)["max"], nmg_counts=nm.counts())
print(json.dumps({"partial": out}), flush=True)
fp = p.solve("fixed-point")
e = fp.displacement - nm.displacement
en = lambda v: float(np.sqrt(max(v.ravel() @ p.A.matvec(v).ravel(), 0.0)))
out.update(fixed_point_status=fp.status, fixed_point_converged=fp.converged, fixed_point_outer=fp.outer_iterations,
           fixed_point_cycles=fp.cycles, fixed_point_seconds=fp.solve_seconds,
           fixed_point_violation=contact_conditions(p, fp)["max"], fixed_point_counts=fp.counts(),
           relative_difference=en(e) / en(nm.displacement),
           peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
print(json.dumps({"done": out}), flush=True)
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"])
    ap.add_argument("--friction", type=float, default=5.0)
    ap.add_argument("--start", type=int, default=3)
    ap.add_argument("--stop", type=int, default=11)
    ap.add_argument("--budget", type=float, default=600.0, help="seconds per level (both solves)")
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, f"fixed_point_F{a.friction:g}_{a.cell}.json")
    rows, last = [], None
    for L in range(a.start, a.stop + 1):
        if last is not None and 5 * last > 3 * a.budget:
            print(f"not trying level {L}: about {5 * last:.0f} s expected", flush=True)
            break
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-c", WORKER, a.cell, str(L), str(a.friction)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            stdout, stderr = proc.communicate(timeout=a.budget)
            timed_out = False
        except subprocess.TimeoutExpired:
            proc.kill()
            stdout, stderr = proc.communicate()
            timed_out = True
        last = time.perf_counter() - t0
        msgs = [json.loads(s) for s in stdout.splitlines() if s.startswith("{")]
        row = next((m["done"] for m in msgs if "done" in m), None)
        if row is None:
            row = next((m["partial"] for m in msgs if "partial" in m), {"level": L})
            row["fixed_point_status"] = (f"did not finish within {a.budget:.0f} s" if timed_out
                                         else f"worker failed: {stderr.strip().splitlines()[-1] if stderr.strip() else proc.returncode}")
        row["wall_seconds"] = last
        rows.append(row)
        with open(path, "w") as fh:
            json.dump(rows, fh, indent=1)
        print(f"level {L}: {row.get('dofs', 0):,} dofs, wall {last:.0f} s | nmg {row.get('nmg_cycles')} cycles "
              f"{row.get('nmg_seconds', float('nan')):.1f} s, violation {row.get('nmg_violation', float('nan')):.0e} | "
              f"fixed point: {row['fixed_point_status']}, {row.get('fixed_point_outer')} outer, "
              f"{row.get('fixed_point_cycles')} V-cycles, {row.get('fixed_point_seconds', float('nan')):.1f} s, "
              f"violation {row.get('fixed_point_violation', float('nan')):.0e} | "
              f"difference {row.get('relative_difference', float('nan')):.1e} | "
              f"contact nmg {row.get('nmg_counts')} fp {row.get('fixed_point_counts')}", flush=True)
        if "fixed_point_outer" not in row:
            break
    finest = [r for r in rows if "fixed_point_outer" in r]
    if finest:
        r = finest[-1]
        verdict = "fails" if not r["fixed_point_converged"] else "converges"
        print(f"finest level that fits: {r['level']} ({r['dofs']:,} dofs); Algorithm 1 {verdict} there for "
              f"F = {a.friction:g} ({r['fixed_point_status']}, {r['fixed_point_outer']} outer iterations)")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
