"""Issue-2 table: the linear multigrid on the Hertz hierarchy (Dirichlet top, no contact), one level
per fresh process so that peak memory is per level: nodes, dofs, setup seconds, seconds per cycle,
contraction per cycle (default F(3,3) and V(3,3)), peak RSS, seconds per cycle per million dofs.

    python benchmarks/linear_levels.py --levels 3 9 [--cell triangle] [--json out/linear_levels.json]
"""
import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys, time
import numpy as np
sys.path.insert(0, "benchmarks")
from linear_multigrid import contraction
from contactmg.generators import HERTZ_TOP, hertz_half_disk, hertz_projector
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.problem import ContactProblem, Dirichlet
L, cell = int(sys.argv[1]), sys.argv[2]
t0 = time.perf_counter()
h = MeshHierarchy.build(hertz_half_disk(cell), L, projector=hertz_projector())
p = ContactProblem(h, Material(2000.0, 0.28), [Dirichlet([HERTZ_TOP], (0.0, -0.005))])
p.solver
setup = time.perf_counter() - t0
res = p.solve(tol=1e-11)
out = {"level": L, "cell": cell, "nodes": h.finest.num_points, "dofs": 2 * h.finest.num_points,
       "setup_seconds": setup, "cycles": res.cycles, "solve_seconds": res.solve_seconds,
       "seconds_per_cycle": res.solve_seconds / res.cycles}
for cyc in ("F", "V"):
    q = ContactProblem(h, Material(2000.0, 0.28), [Dirichlet([HERTZ_TOP], (0.0, 0.0))], cycle=cyc)
    out[f"rate_{cyc}33"], out[f"seconds_per_{cyc}_cycle"] = contraction(q, cycles=14)
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 9])
    ap.add_argument("--cell", default="triangle")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    print(f"{'lvl':>3} {'nodes':>9} {'dofs':>9} {'setup s':>8} {'cycles':>6} {'s/F-cyc':>8} {'rate F':>7} "
          f"{'s/V-cyc':>8} {'rate V':>7} {'peak MB':>8} {'s/cyc/Mdof':>10}")
    for L in range(a.levels[0], a.levels[1] + 1):
        r = json.loads(subprocess.run([sys.executable, "-c", CHILD, str(L), a.cell], capture_output=True, text=True,
                                      check=True).stdout.strip().splitlines()[-1])
        rows.append(r)
        print(f"{L:3d} {r['nodes']:9d} {r['dofs']:9d} {r['setup_seconds']:8.2f} {r['cycles']:6d} "
              f"{r['seconds_per_cycle']:8.3f} {r['rate_F33']:7.3f} {r['seconds_per_V_cycle']:8.3f} {r['rate_V33']:7.3f} "
              f"{r['peak_rss_mb']:8.0f} {r['seconds_per_cycle'] / r['dofs'] * 1e6:10.3f}", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
