"""Scaling of the Hertz benchmark: for each level (a fresh process each, so peak memory is per
level) the nmg solve (Algorithm 2) and the linear reference with the contact state known in
advance: dofs, cycles, setup and solve seconds, nmg/linear time ratio, asymptotic contraction,
peak RSS, seconds per cycle per million dofs.

    python benchmarks/scaling.py [--cell triangle] [--levels 3 9] [--friction 0.4] [--out out]
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np


def run(cell, L, F, method):
    r = subprocess.run([sys.executable, "-m", "contactmg", "hertz", "--cell", cell, "--levels", str(L), "--friction",
                        str(F), "--method", method, "--json", "-", "-q"], capture_output=True, text=True)
    if r.returncode not in (0, 3):
        raise RuntimeError(r.stderr)
    return json.loads(r.stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cell", default="triangle")
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 9])
    ap.add_argument("--friction", type=float, default=0.4)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    print(f"{'lvl':>3} {'dofs':>9} {'cyc':>4} {'setup s':>8} {'nmg s':>8} {'lin cyc':>7} {'lin s':>8} {'ratio':>6} "
          f"{'rate':>6} {'peak MB':>8} {'s/cyc/Mdof':>10} {'conv':>5}")
    for L in range(a.levels[0], a.levels[1] + 1):
        n = run(a.cell, L, a.friction, "nmg")
        lin = run(a.cell, L, a.friction, "linear")
        c = np.array([h["correction_norm"] for h in n["history"]])
        rate = float(np.exp(np.mean(np.log(c[-4:] / c[-5:-1])))) if len(c) > 5 else float("nan")
        row = {"level": L, "dofs": n["dofs"], "cycles": n["cycles"], "setup_seconds": n["setup_seconds"],
               "solve_seconds": n["solve_seconds"], "linear_cycles": lin["cycles"], "linear_seconds": lin["solve_seconds"],
               # the nmg solve inside the linear run (same process, same warm caches) against the linear solve
               "ratio": lin["nmg_over_linear"], "rate": rate, "peak_rss_mb": n["peak_rss_mb"],
               "seconds_per_cycle_per_mdof": n["solve_seconds"] / n["cycles"] / n["dofs"] * 1e6,
               "converged": n["converged"]}
        rows.append(row)
        print(f"{L:3d} {row['dofs']:9d} {row['cycles']:4d} {row['setup_seconds']:8.2f} {row['solve_seconds']:8.3f} "
              f"{row['linear_cycles']:7d} {row['linear_seconds']:8.3f} {row['ratio']:6.2f} {rate:6.3f} "
              f"{row['peak_rss_mb']:8.0f} {row['seconds_per_cycle_per_mdof']:10.3f} {str(row['converged']):>5}", flush=True)
    with open(os.path.join(a.out, f"scaling_{a.cell}.json"), "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
