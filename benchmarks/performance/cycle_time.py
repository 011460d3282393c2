"""Time per cycle and per solve of the Hertz benchmark over levels, each level in a fresh process
(`contactmg hertz --json -`, so that the peak memory is that level's): dofs, Algorithm 2 cycles,
setup and solve seconds, the linear solve with the contact state known in advance (cycles,
seconds, and the nmg/linear time ratio measured in one process), the asymptotic contraction,
peak memory, and seconds per cycle per million dofs (flat when the cycle is O(n)).

    python benchmarks/performance/cycle_time.py [--cells triangle quad] [--levels 3 9] [--friction 0.4]
        [--quick] [--json PATH]
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402


def run(cell, L, F, method):
    """The command line's JSON of one Hertz solve."""
    r = subprocess.run([sys.executable, "-m", "contactmg", "hertz", "--cell", cell, "--levels", str(L), "--friction",
                        str(F), "--method", method, "--json", "-", "-q"], capture_output=True, text=True)
    if r.returncode not in (0, 3):
        raise RuntimeError(r.stderr)
    return json.loads(r.stdout)


def main():
    ap = parser(__doc__)
    ap.add_argument("--cells", nargs="+", default=["triangle", "quad"])
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 9], help="triangle levels; quads one level fewer")
    ap.add_argument("--friction", type=float, default=0.4)
    a = ap.parse_args()
    if a.quick:
        a.levels = [2, 4]
    rows = []
    print(f"{'cell':>8} {'lvl':>3} {'dofs':>9} {'cyc':>4} {'setup s':>8} {'nmg s':>8} {'lin cyc':>7} {'lin s':>8} "
          f"{'ratio':>6} {'rate':>6} {'peak MB':>8} {'s/cyc/Mdof':>10}")
    for cell in a.cells:
        for L in range(a.levels[0], a.levels[1] + (0 if cell == "quad" else 1)):
            n = run(cell, L, a.friction, "nmg")
            lin = run(cell, L, a.friction, "linear")
            c = np.array([h["correction_norm"] for h in n["history"]])
            rate = float(np.exp(np.mean(np.log(c[-4:] / c[-5:-1])))) if len(c) > 5 else float("nan")
            row = {"cell": cell, "level": L, "dofs": n["dofs"], "cycles": n["cycles"], "converged": n["converged"],
                   "setup_seconds": n["setup_seconds"], "solve_seconds": n["solve_seconds"],
                   "seconds_per_cycle": n["solve_seconds"] / n["cycles"],
                   "linear_cycles": lin["cycles"], "linear_seconds": lin["solve_seconds"],
                   "nmg_over_linear": lin["nmg_over_linear"], "rate": rate, "peak_rss_mb": n["peak_rss_mb"],
                   "seconds_per_cycle_per_mdof": n["solve_seconds"] / n["cycles"] / n["dofs"] * 1e6}
            rows.append(row)
            print(f"{cell:>8} {L:3d} {row['dofs']:9d} {row['cycles']:4d} {row['setup_seconds']:8.2f} "
                  f"{row['solve_seconds']:8.3f} {row['linear_cycles']:7d} {row['linear_seconds']:8.3f} "
                  f"{row['nmg_over_linear']:6.2f} {rate:6.3f} {row['peak_rss_mb']:8.0f} "
                  f"{row['seconds_per_cycle_per_mdof']:10.3f}", flush=True)
    write_result(__file__, a, {"friction": a.friction, "rows": rows})


if __name__ == "__main__":
    main()
