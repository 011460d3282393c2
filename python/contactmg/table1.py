"""Table 1 and Figure 1 of the paper: Algorithm 1 (fixed point) and Algorithm 2 (nmg) on the Hertz
benchmark over levels and friction coefficients."""
from __future__ import annotations

import json
import sys
import time
from typing import Dict, Sequence

from .hertz import PAPER_FRICTIONS, hertz_problem

DEFAULT_LEVELS = (2, 3, 4, 5, 6, 7)


def table1(levels: Sequence[int] = DEFAULT_LEVELS, frictions: Sequence[float] = PAPER_FRICTIONS,
           cell: str = "triangle", progress: bool = True, tol: float = 1e-11) -> Dict:
    """Runs both algorithms for every (friction, level). Lists are indexed [friction][level].
    fixed_point_iterations is None where Algorithm 1 did not converge (its V-cycles still count)."""
    from tqdm import tqdm

    levels, frictions = list(levels), list(frictions)
    out = {"problem": "hertz", "cell": cell, "levels": levels, "frictions": frictions, "tol": tol,
           "nodes": [], "dofs": [], "fixed_point_iterations": [], "fixed_point_vcycles": [], "fixed_point_status": [],
           "fixed_point_seconds": [], "nmg_vcycles": [], "nmg_converged": [], "nmg_seconds": []}
    bar = tqdm(total=len(levels) * len(frictions), disable=not progress, desc="table1", unit="run", file=sys.stderr)
    rows = {k: [[None] * len(levels) for _ in frictions] for k in
            ("fixed_point_iterations", "fixed_point_vcycles", "fixed_point_status", "fixed_point_seconds",
             "nmg_vcycles", "nmg_converged", "nmg_seconds")}
    for j, L in enumerate(levels):
        for i, F in enumerate(frictions):
            p = hertz_problem(cell, L, F, coulomb_at_zero=True)
            if i == 0:
                out["nodes"].append(int(p.mesh.num_points))
                out["dofs"].append(int(p.mesh.num_points * p.mesh.dim))
            fp = p.solve("fixed-point", tol=tol)
            nm = p.solve("nmg", tol=tol)
            rows["fixed_point_iterations"][i][j] = fp.outer_iterations if fp.converged else None
            rows["fixed_point_vcycles"][i][j] = fp.cycles
            rows["fixed_point_status"][i][j] = fp.status
            rows["fixed_point_seconds"][i][j] = fp.solve_seconds
            rows["nmg_vcycles"][i][j] = nm.cycles
            rows["nmg_converged"][i][j] = nm.converged
            rows["nmg_seconds"][i][j] = nm.solve_seconds
            bar.set_postfix(level=L, F=F)
            bar.update()
    bar.close()
    out.update(rows)
    return out


def save_figures(table: Dict, path: str) -> None:
    """One PNG with Table 1, Figure 1 left and Figure 1 right."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .plots import plot_convergence, plot_fixed_point_iterations, plot_table1

    fig = plt.figure(figsize=(16, 5.5))
    ax0 = fig.add_subplot(1, 3, 1)
    ax1 = fig.add_subplot(1, 3, 2)
    ax2 = fig.add_subplot(1, 3, 3, projection="3d")
    plot_table1(table, ax=ax0)
    plot_convergence(table, ax=ax1)
    plot_fixed_point_iterations(table, ax=ax2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def run_table1(args) -> int:
    t0 = time.perf_counter()
    kw = {}
    if args.levels:
        kw["levels"] = args.levels
    if args.frictions:
        kw["frictions"] = args.frictions
    table = table1(cell=args.cell, progress=not args.quiet, **kw)
    table["seconds"] = time.perf_counter() - t0
    if args.json == "-":
        sys.stdout.write(json.dumps(table, indent=1) + "\n")
    elif args.json:
        with open(args.json, "w") as fh:
            json.dump(table, fh, indent=1)
    if args.plot:
        save_figures(table, args.plot)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(format_table(table), file=stream)
    return 0 if all(all(r) for r in table["nmg_converged"]) else 3


def format_table(table: Dict) -> str:
    """Text form: outer iterations of Algorithm 1 (V-cycles of Algorithm 1 / of Algorithm 2)."""
    head = "F \\ dofs " + "".join(f"{d:>18,}" for d in table["dofs"])
    lines = [head]
    for i, F in enumerate(table["frictions"]):
        cells = []
        for j in range(len(table["levels"])):
            it = table["fixed_point_iterations"][i][j]
            nm = table["nmg_vcycles"][i][j] if table["nmg_converged"][i][j] else "no conv."
            cells.append(f"{(it if it is not None else 'no conv.')!s:>8} ({table['fixed_point_vcycles'][i][j]}/{nm})")
        lines.append(f"{F:<9g}" + "".join(f"{c:>18}" for c in cells))
    return "\n".join(lines)
