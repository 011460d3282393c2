"""Contraction per cycle of the linear multigrid on the rectangle and on the Hertz half disk
(levels 3..8; V(1,1), V(2,2), V(3,3), W(3,3), F(3,3)), with setup time, seconds per cycle and
peak memory. Prints a table and writes JSON.

    python benchmarks/linear_multigrid.py [--levels 3 8] [--json out/linear_mg.json]
"""
import argparse
import json
import resource
import time

import numpy as np

from contactmg.generators import HERTZ_TOP, hertz_half_disk, hertz_projector, rectangle
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.problem import ContactProblem, Dirichlet

CYCLES = [("V", 1, 1), ("V", 2, 2), ("V", 3, 3), ("W", 3, 3), ("F", 3, 3)]


def contraction(problem, cycles=14, seed=0):
    """Zero load, random start: the correction norms decay like the error; the rate is the
    geometric mean of the last five ratios."""
    rng = np.random.default_rng(seed)
    u0 = rng.standard_normal(problem.load.shape)
    zero = np.zeros_like(problem.load)
    problem.load, saved = zero, problem.load
    problem._solvers.clear()  # the core solver keeps its own copy of the load
    try:
        res = problem.solve(u0=u0, tol=1e-300, rtol=1e-300, max_cycles=cycles)
    finally:
        problem.load = saved
        problem._solvers.clear()  # the core solver keeps its own copy of the load
    c = res.history["correction_norm"]
    ratios = c[1:] / c[:-1]
    return float(np.exp(np.mean(np.log(ratios[-5:])))), res.solve_seconds / res.cycles


def geometry(name, cell, levels):
    if name == "hertz":
        h = MeshHierarchy.build(hertz_half_disk(cell), levels, projector=hertz_projector())
        bcs = [Dirichlet([HERTZ_TOP], (0.0, 0.0))]
        return h, Material(2000.0, 0.28), bcs
    h = MeshHierarchy.build(rectangle(2, 2, cell=cell), levels)
    return h, Material(2000.0, 0.28), [Dirichlet([4], (0.0, 0.0))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 8])
    ap.add_argument("--cells", nargs="+", default=["triangle"])
    ap.add_argument("--geometries", nargs="+", default=["rectangle", "hertz"])
    ap.add_argument("--json")
    args = ap.parse_args()
    rows = []
    print(f"{'geometry':9} {'cell':8} {'lvl':>3} {'nodes':>8} {'dofs':>9} {'setup s':>8} " +
          " ".join(f"{c}({a},{b}) rate  s/cyc" for c, a, b in CYCLES) + "  peak MB")
    for geo in args.geometries:
        for cell in args.cells:
            for L in range(args.levels[0], args.levels[1] + 1):
                t0 = time.perf_counter()
                h, mat, bcs = geometry(geo, cell, L)
                t0 = time.perf_counter() - (time.perf_counter() - t0)
                row = {"geometry": geo, "cell": cell, "level": L, "nodes": h.finest.num_points,
                       "dofs": 2 * h.finest.num_points}
                line = []
                for c, a, b in CYCLES:
                    p = ContactProblem(h, mat, bcs, cycle=c, nu1=a, nu2=b)
                    if c == "V" and a == 3:
                        p.solver  # noqa: B018 - builds the coarse hierarchy
                        row["setup_seconds"] = time.perf_counter() - t0
                    rate, spc = contraction(p)
                    row[f"{c}({a},{b})"] = {"rate": rate, "seconds_per_cycle": spc}
                    line.append(f"{rate:13.3f} {spc:6.3f}")
                row["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
                rows.append(row)
                print(f"{geo:9} {cell:8} {L:3d} {row['nodes']:8d} {row['dofs']:9d} {row['setup_seconds']:8.2f} "
                      + " ".join(line) + f" {row['peak_rss_mb']:8.0f}", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
