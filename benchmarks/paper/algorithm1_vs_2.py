"""Algorithm 1 (fixed point on the normal stresses, one monotone multigrid solve of a Tresca problem
per outer iteration) against Algorithm 2 (nmg) at one friction coefficient, on uniform Hertz levels
up to the finest that fits a time budget: whether and how fast each converges, how well each result
satisfies the discrete contact conditions, and the energy-norm difference of the two results.

The paper's Algorithm 1 stops converging at F = 5 from its adaptive level 9 on. Nothing is tuned:
the package's defaults (tol 1e-11, fixed-point tolerance 1e-9, at most 100 outer iterations). Each
level runs in a fresh process with a time limit (--budget seconds for both solves); the run stops
after the first level that does not finish, or before a level whose expected time (5x the last)
exceeds 3x the budget.

    python benchmarks/paper/algorithm1_vs_2.py [--cell triangle] [--friction 5] [--levels 3 11]
        [--budget 600] [--quick] [--json PATH]
"""
import json
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

WORKER = r"""
import json, sys, resource
import numpy as np
from contactmg.examples import hertz
from contactmg.results.checks import contact_conditions
cell, L, F = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
p = hertz.hertz_problem(cell, L, F, coulomb_at_zero=True)
out = {"level": L, "cell": cell, "friction": F, "dofs": int(2 * p.mesh.num_points)}
nm = p.solve("nmg")
out.update(nmg_cycles=nm.cycles, nmg_converged=nm.converged, nmg_seconds=nm.solve_seconds,
           nmg_violation=contact_conditions(p, nm)["max"])
print(json.dumps({"partial": out}), flush=True)
fp = p.solve("fixed-point")
en = lambda v: float(np.sqrt(max(v.ravel() @ p.A.matvec(v).ravel(), 0.0)))
out.update(fixed_point_status=fp.status, fixed_point_converged=fp.converged, fixed_point_outer=fp.outer_iterations,
           fixed_point_cycles=fp.cycles, fixed_point_seconds=fp.solve_seconds,
           fixed_point_violation=contact_conditions(p, fp)["max"],
           relative_difference=en(fp.displacement - nm.displacement) / en(nm.displacement),
           peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
print(json.dumps({"done": out}), flush=True)
"""


def run_level(cell, L, F, budget):
    """One level in a fresh process: the worker's row, with the fixed point's status on a timeout."""
    proc = subprocess.Popen([sys.executable, "-c", WORKER, cell, str(L), str(F)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        stdout, stderr = proc.communicate(timeout=budget)
        timed_out = False
    except subprocess.TimeoutExpired:
        proc.kill()
        stdout, stderr = proc.communicate()
        timed_out = True
    msgs = [json.loads(s) for s in stdout.splitlines() if s.startswith("{")]
    row = next((m["done"] for m in msgs if "done" in m), None)
    if row is None:
        row = next((m["partial"] for m in msgs if "partial" in m), {"level": L})
        row["fixed_point_status"] = (f"did not finish within {budget:.0f} s" if timed_out else
                                     f"worker failed: {stderr.strip().splitlines()[-1] if stderr.strip() else proc.returncode}")
    return row


def main():
    ap = parser(__doc__)
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"])
    ap.add_argument("--friction", type=float, default=5.0)
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 11], help="first and last level to try")
    ap.add_argument("--budget", type=float, default=600.0, help="seconds per level (both solves)")
    a = ap.parse_args()
    if a.quick:
        a.levels, a.budget = [3, 4], 60.0
    rows, last = [], None
    for L in range(a.levels[0], a.levels[1] + 1):
        if last is not None and 5 * last > 3 * a.budget:
            print(f"not trying level {L}: about {5 * last:.0f} s expected", flush=True)
            break
        t0 = time.perf_counter()
        row = run_level(a.cell, L, a.friction, a.budget)
        last = row["wall_seconds"] = time.perf_counter() - t0
        rows.append(row)
        print(f"level {L}: {row.get('dofs', 0):,} dofs | Alg. 2 {row.get('nmg_cycles')} cycles "
              f"{row.get('nmg_seconds', float('nan')):.2f} s, violation {row.get('nmg_violation', float('nan')):.0e} | "
              f"Alg. 1: {row['fixed_point_status']}, {row.get('fixed_point_outer')} outer, "
              f"{row.get('fixed_point_cycles')} V-cycles, {row.get('fixed_point_seconds', float('nan')):.2f} s | "
              f"difference {row.get('relative_difference', float('nan')):.1e}", flush=True)
        if "fixed_point_outer" not in row:
            break
    write_result(__file__, a, {"cell": a.cell, "friction": a.friction, "rows": rows})


if __name__ == "__main__":
    main()
