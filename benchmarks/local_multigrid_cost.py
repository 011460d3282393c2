"""Cost per cycle against dofs: local against full smoothing on graded hierarchies, and against a
uniform hierarchy of about the same dofs (issue 11).

    python benchmarks/local_multigrid_cost.py [--graded-levels 30] [--graded-theta 0.2]
        [--paper-levels 9 10] [--uniform-levels 6 7] [--min-growth 2.5] [--cycle F] [--repeat 3] [--out out]

Hierarchies (Hertz, Coulomb F = 0.4, solved from zero to tol 1e-11):
  graded     hertz_adaptive_hierarchy with a small Doerfler theta (0.2): about 1.3x more nodes per
             level, so 30 levels to 135k dofs -- the strongly graded case where full smoothing costs
             O(L n_L) per cycle
  thinned    the graded hierarchy with its levels kept only where they grew by --min-growth
             (MeshHierarchy.thinned; transfers composed)
  paper      the Table 1 hierarchy (theta = 0.8, about 2.8x per level)
  uniform    uniform refinement
For each, with full smoothing (every row of every coarse level) and with local smoothing
(ContactProblem.local_smoothing: the rows of MeshHierarchy.changed_nodes on coarse levels 1..L-2):
cycles, the fastest seconds per cycle of --repeat solves, microseconds per cycle and dof, and
CPU microseconds per cycle and dof (process time of the fastest solve, one
thread: less sensitive to a loaded machine than the wall clock), and the smoothed rows per cycle counted from the cycle's visits of each level (load-independent:
"rows/dof" = smoothed block rows per cycle / fine nodes; nu1 + nu2 sweeps each).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from contactmg import hertz


def visits(levels: int, cycle: str) -> list:
    """How often one cycle smooths each level (index 0 = coarsest, solved instead; last = fine)."""
    def go(l, kind, out):
        out[l] += 1
        if l == 0:
            return
        for v in range(1 if kind == "V" else 2):
            go(l - 1, "V" if (kind == "F" and v == 1) else kind, out)
    out = [0] * levels
    go(levels - 1, cycle, out)
    return out


def measure(name, h, local, cycle, repeat, friction=0.4):
    p = hertz.hertz_problem_on(h, friction, cycle=cycle)
    p.local_smoothing = local
    p.solver  # built outside the timing
    best, cpu = None, None
    for _ in range(repeat):
        c0 = time.process_time()
        r = p.solve(threads=1)
        c = time.process_time() - c0
        cpu = c if cpu is None else min(cpu, c)
        best = r if best is None or r.solve_seconds < best.solve_seconds else best
    n = p.mesh.num_points
    vis = visits(h.levels, cycle)
    # the coarsest level is solved, not smoothed; the finest smooths every node
    rows = [0] + [len(h.changed_nodes(l)) if local else h.meshes[l].num_points for l in range(1, h.levels - 1)] + [n]
    smoothed = sum(v * r for v, r in zip(vis, rows))
    return {"hierarchy": name, "local": bool(local), "levels": h.levels, "dofs": 2 * n, "cycles": best.cycles,
            "converged": best.converged, "seconds_per_cycle": best.solve_seconds / best.cycles,
            "us_per_cycle_per_dof": 1e6 * best.solve_seconds / best.cycles / (2 * n),
            "cpu_us_per_cycle_per_dof": 1e6 * cpu / best.cycles / (2 * n),
            "smoothed_rows_per_fine_node": smoothed / n,
            "coarse_rows_per_fine_node": sum(m.num_points for m in h.meshes[:-1]) / n}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--graded-levels", type=int, nargs="+", default=[26, 30])
    ap.add_argument("--graded-theta", type=float, default=0.2)
    ap.add_argument("--paper-levels", type=int, nargs="+", default=[9, 10])
    ap.add_argument("--uniform-levels", type=int, nargs="+", default=[6, 7])
    ap.add_argument("--min-growth", type=float, default=2.5)
    ap.add_argument("--cycle", default="F", choices=["V", "W", "F"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    t0 = time.perf_counter()
    graded = hertz.hertz_adaptive_hierarchy(max(a.graded_levels), 0.4, theta=a.graded_theta)
    paper = hertz.hertz_adaptive_hierarchy(max(a.paper_levels), 0.4)
    print(f"hierarchies built in {time.perf_counter() - t0:.1f} s (graded theta = {a.graded_theta}: "
          f"{[m.num_points for m in graded.meshes]} nodes)", flush=True)
    cases = []
    for L in a.graded_levels:
        g = graded.truncated(L)
        cases += [(f"graded L{L}", g), (f"thinned L{L}", g.thinned(a.min_growth))]
    cases += [(f"paper L{L}", paper.truncated(L)) for L in a.paper_levels]
    from contactmg.generators import hertz_half_disk, hertz_projector
    from contactmg.hierarchy import MeshHierarchy
    for L in a.uniform_levels:
        cases.append((f"uniform L{L}", MeshHierarchy.build(hertz_half_disk("triangle"), L,
                                                           projector=hertz_projector(hertz.CENTER, hertz.RADIUS))))
    rows = []
    head = (f"{'hierarchy':>12} {'smoothing':>9} {'levels':>6} {'dofs':>8} {'cycles':>6} {'s/cycle':>8} "
            f"{'us/cyc/dof':>10} {'cpu us':>7} {'rows/dof':>8} {'coarse/fine':>11}")
    print(f"cycle {a.cycle}(3,3), Coulomb F = 0.4; load average {os.getloadavg()[0]:.1f} at the start")
    print(head)
    for name, h in cases:
        for local in ((False, True) if h.kind == "adaptive" else (False,)):
            r = measure(name, h, local, a.cycle, a.repeat)
            rows.append(r)
            print(f"{name:>12} {'local' if local else 'full':>9} {r['levels']:6d} {r['dofs']:8,} {r['cycles']:6d} "
                  f"{r['seconds_per_cycle']:8.4f} {r['us_per_cycle_per_dof']:10.3f} {r['cpu_us_per_cycle_per_dof']:7.3f} "
                  f"{r['smoothed_rows_per_fine_node']:8.2f} {r['coarse_rows_per_fine_node']:11.2f}", flush=True)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    with open(os.path.join(a.out, "local_multigrid_cost.json"), "w") as fh:
        json.dump({"argv": sys.argv[1:], "cycle": a.cycle, "rows": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
