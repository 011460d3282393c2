"""Table 1 and Figure 1 of the paper: Algorithm 1 (fixed point, outer iterations and V-cycles) and
Algorithm 2 (nmg cycles) for the ten friction coefficients of the paper on the Hertz benchmark,
level by level, on the uniform or the adaptive hierarchy, every Algorithm 2 result checked against
the discrete contact conditions. Prints the table next to the paper's.

    python benchmarks/paper/table1.py [--hierarchy uniform|adaptive] [--levels 2 3 ...]
        [--frictions ...] [--budget-minutes 20] [--plot out/table1.png] [--quick] [--json PATH]

Without --levels, levels 2, 3, ... (adaptive: 3, 5, 7, ...) are run while about 10x the previous
level's time still fits in the budget (2 cores: uniform levels 2-8 take 3 minutes, level 9 alone
23; adaptive levels 3-9 about 5 minutes, level 11 about an hour). Exit status 3 when an
Algorithm 2 run did not converge or failed the check.
"""
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg.examples.hertz import ADAPTIVE_FRICTION, PAPER_FRICTIONS, hertz_adaptive_hierarchy  # noqa: E402
from contactmg.examples.table1 import (FIXED_POINT_STALL_WINDOW, failed_runs, format_table, merge_levels,  # noqa: E402
                              save_figures, table1)

# Table 1 of the paper (fixed-point iterations, TOL = 1e-9; None = no convergence) on its adaptive
# levels 3, 5, 7, 9, 11.
PAPER_DOFS = [94, 830, 4674, 44200, 334818]
PAPER_TABLE1 = {0.08: [1, 5, 6, 6, 6], 0.4: [1, 5, 10, 10, 10], 0.7: [1, 5, 8, 12, 13], 0.9: [1, 6, 9, 15, 15],
                1.0: [1, 6, 10, 10, 16], 1.1: [1, 6, 10, 16, 18], 2.0: [1, 6, 8, 19, 33], 5.0: [1, 2, 2, None, None],
                8.0: [1, 2, 2, None, None], 40.0: [1, 2, 2, None, None]}


def paper_text():
    """The paper's Table 1 as text."""
    fmt = lambda v: "no conv." if v is None else str(v)  # noqa: E731
    lines = ["paper, Table 1 (adaptive levels 3, 5, 7, 9, 11): fixed-point iterations",
             "F \\ dofs " + "".join(f"{d:>10,}" for d in PAPER_DOFS)]
    lines += [f"{F:<9g}" + "".join(f"{fmt(v):>10}" for v in row) for F, row in PAPER_TABLE1.items()]
    return "\n".join(lines)


def main():
    ap = parser(__doc__)
    ap.add_argument("--hierarchy", choices=["uniform", "adaptive"], default="uniform")
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"], help="uniform hierarchy only")
    ap.add_argument("--levels", type=int, nargs="+", default=None)
    ap.add_argument("--frictions", type=float, nargs="+", default=list(PAPER_FRICTIONS))
    ap.add_argument("--budget-minutes", type=float, default=20.0)
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (one thread each)")
    ap.add_argument("--plot", default=None, help="PNG of Table 1 and Figure 1")
    a = ap.parse_args()
    adaptive = a.hierarchy == "adaptive"
    if a.quick:
        a.levels = a.levels or ([3, 4] if adaptive else [2, 3])
        a.frictions = [0.4, 5.0]
    candidates = a.levels or (range(3, 13, 2) if adaptive else range(2, 13))
    hierarchy = "uniform"
    if adaptive:
        hierarchy = hertz_adaptive_hierarchy(max(candidates) if a.levels else 11, ADAPTIVE_FRICTION)
    t0, budget = time.perf_counter(), 60 * a.budget_minutes
    table, last = None, None
    for L in candidates:
        spent = time.perf_counter() - t0
        if a.levels is None and last is not None and spent + 10 * last > budget:
            print(f"stopping before level {L}: about {10 * last:.0f} s expected, {budget - spent:.0f} s left", flush=True)
            break
        t = table1(levels=[L], frictions=a.frictions, cell=a.cell if not adaptive else "triangle", progress=False,
                   hierarchy=hierarchy, jobs=a.jobs,
                   fixed_point_stall_window=FIXED_POINT_STALL_WINDOW if adaptive else 0)
        last = t["seconds"]
        table = t if table is None else merge_levels(table, t)
        print(f"level {L}: {t['dofs'][0]:,} dofs, {last:.1f} s; fixed-point iterations "
              f"{[row[0] for row in t['fixed_point_iterations']]}; Alg. 2 cycles {[r[0] for r in t['nmg_vcycles']]}",
              flush=True)
    table["hierarchy"] = a.hierarchy
    print(format_table(table))
    print(paper_text())
    failed = failed_runs(table)
    for F, L, why in failed:
        print(f"nmg at F = {F:g}, level {L}: {why}")
    if a.plot:
        save_figures(table, a.plot)
    write_result(__file__, a, table)
    return 3 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
