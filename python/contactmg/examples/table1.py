"""Table 1 and Figure 1 of the paper: Algorithm 1 (fixed point) and Algorithm 2 (nmg) on the Hertz
benchmark over levels and friction coefficients.

`table1(levels, frictions)` returns a dict (the JSON of `contactmg table1`, the command-line contract) whose
per-run lists are indexed [friction][level]:

    levels, frictions, cell, tol, nodes, dofs                      (nodes/dofs: one per level)
    fixed_point_iterations   outer iterations of Algorithm 1, None where it did not converge
    fixed_point_vcycles      its total V-cycles (counted also where it did not converge)
    fixed_point_status       the solver's status text
    fixed_point_seconds      solve time
    fixed_point_violation    relative violation of the discrete contact conditions (checks.py)
    nmg_vcycles, nmg_converged, nmg_status, nmg_seconds, nmg_violation   the same for Algorithm 2
    seconds                  wall time of the whole table (setup included)

The violation columns are computed from the returned displacement alone (residual A u - f and the
Coulomb conditions, relative to the largest contact force): a solve can meet its stopping test
||u^{k+1} - u^k||_A <= tol on an iterate the cycle merely maps back onto itself.
"""
from __future__ import annotations

import json
import sys
import time
from typing import Dict, Sequence

from ..results.checks import VIOLATION_TOL, contact_conditions
from ..examples.hertz import ADAPTIVE_FRICTION, ADAPTIVE_THETA, PAPER_FRICTIONS, hertz_adaptive_hierarchy, hertz_problem
from ..mesh.hierarchy import MeshHierarchy
from ..solve.options import options_from

# Measured on 2 cores (triangles, the ten coefficients of the paper): levels 2-7 take about 40 s,
# levels 2-8 (up to 592,130 dofs, the size of the paper's finest level) 3 minutes (level 9: 23 more).
DEFAULT_LEVELS = (2, 3, 4, 5, 6, 7, 8)
# The adaptive table (the default of `contactmg table1`, as in the paper): the paper's levels.
DEFAULT_ADAPTIVE_LEVELS = (3, 5, 7, 9, 11)
# Algorithm 1 in the adaptive table stops as not converging when the relative change of s_n has
# not fallen over this many outer iterations (FixedPointStep; 0 would run every failing solve to
# fixed_point_max, tens of minutes each at F >= 5 on level 11).
FIXED_POINT_STALL_WINDOW = 5
# A "converged" nmg run whose displacement violates the contact conditions by more than
# VIOLATION_TOL (relative, checks.py) is not a solution: run_table1 then exits with status 3.

_PER_RUN = ("fixed_point_iterations", "fixed_point_vcycles", "fixed_point_status", "fixed_point_seconds",
            "fixed_point_violation", "nmg_vcycles", "nmg_converged", "nmg_status", "nmg_seconds", "nmg_violation")


def table1(levels: Sequence[int] = DEFAULT_LEVELS, frictions: Sequence[float] = PAPER_FRICTIONS,
           cell: str = "triangle", progress: bool = True, tol: float = 1e-11, fixed_point_tol: float = 1e-9,
           fixed_point_max: int = 100, max_cycles: int = 200, hierarchy="uniform", jobs: int = 1,
           fixed_point_stall_window: int = 0) -> Dict:
    """Runs Algorithm 1 ("fixed-point") and Algorithm 2 ("nmg") for every (friction, level) of the
    Hertz benchmark from u = 0 (tqdm progress bar on standard error unless progress=False).
    hierarchy: "uniform", "adaptive" (one hierarchy, hertz_adaptive_hierarchy refined for
    F = ADAPTIVE_FRICTION, for every F; the JSON gains estimated_error per level) or a
    MeshHierarchy of the half disk with at least max(levels) levels.
    jobs: worker processes for the (friction, level) runs (each one thread; 1: in this process);
    the counts do not depend on it. fixed_point_stall_window: Algorithm 1 stops as not converging
    once its change of s_n has not fallen over that many outer iterations (0: off).
    Returns the dict described in the module docstring."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    levels, frictions = [int(L) for L in levels], [float(F) for F in frictions]
    out = {"problem": "hertz", "cell": cell, "levels": levels, "frictions": frictions, "tol": tol,
           "fixed_point_tol": fixed_point_tol, "fixed_point_max": fixed_point_max, "nodes": [], "dofs": []}
    full = None
    if isinstance(hierarchy, MeshHierarchy):
        full = hierarchy
    elif hierarchy == "adaptive":
        full = hertz_adaptive_hierarchy(max(levels), ADAPTIVE_FRICTION, cell=cell)
        out.update(adaptive_theta=ADAPTIVE_THETA, adaptive_friction=ADAPTIVE_FRICTION)
    elif hierarchy != "uniform":
        raise ValueError(f"hierarchy must be 'uniform', 'adaptive' or a MeshHierarchy, got {hierarchy!r}")
    out["hierarchy"] = "uniform" if full is None else full.kind
    out["fixed_point_stall_window"] = fixed_point_stall_window
    if full is not None:
        if max(levels) > full.levels:
            raise ValueError(f"the hierarchy has {full.levels} levels, fewer than the {max(levels)} asked for")
        out["hierarchy_seconds"] = full.build_seconds
        if full.estimated_error:
            out["estimated_error"] = [float(full.estimated_error[L - 1]) for L in levels]
    rows = {k: [[None] * len(levels) for _ in frictions] for k in _PER_RUN}
    opts = dict(tol=tol, max_cycles=max_cycles, fixed_point_tol=fixed_point_tol, fixed_point_max=fixed_point_max,
                fixed_point_stall_window=fixed_point_stall_window)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1, got {jobs!r}")
    # the dearest runs (finest levels, large F) first, so that the workers finish together
    tasks = sorted(((j, i) for j in range(len(levels)) for i in range(len(frictions))),
                   key=lambda ji: (-levels[ji[0]], -frictions[ji[1]]))
    nodes = [None] * len(levels)
    bar = tqdm(total=len(tasks), disable=not progress, desc="table1", unit="run", file=sys.stderr)

    def store(j, i, run):
        nodes[j] = run.pop("nodes")
        out["cycle_type"] = run.pop("cycle_type")
        for k, v in run.items():
            rows[k][i][j] = v
        bar.set_postfix(level=levels[j], F=frictions[i])
        bar.update()

    try:
        if jobs == 1:
            for j, i in tasks:
                store(j, i, _run_one(cell, levels[j], frictions[i], full, opts, 0))
        else:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            # spawn, not fork: the parent's OpenMP thread pool does not survive a fork
            with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn"),
                                     initializer=_init_worker, initargs=(full,)) as pool:
                futures = {pool.submit(_run_in_worker, cell, levels[j], frictions[i], opts): (j, i) for j, i in tasks}
                from concurrent.futures import as_completed
                for fut in as_completed(futures):
                    j, i = futures[fut]
                    store(j, i, fut.result())
    finally:
        bar.close()
    out["nodes"] = [int(n) for n in nodes]
    out["dofs"] = [int(n) * 2 for n in nodes]
    out.update(rows)
    out["seconds"] = time.perf_counter() - t0
    return out


_WORKER_HIERARCHY = None


def _init_worker(full):
    global _WORKER_HIERARCHY
    _WORKER_HIERARCHY = full


def _run_in_worker(cell, L, F, opts):
    return _run_one(cell, L, F, _WORKER_HIERARCHY, opts, 1)


def _run_one(cell: str, L: int, F: float, full, opts: Dict, threads: int) -> Dict:
    """Both algorithms on level L (of `full`, or uniform when None) at friction F."""
    p = hertz_problem(cell, L, F, coulomb_at_zero=True, hierarchy="uniform" if full is None else full.truncated(L))
    fp_kw = dict(opts)
    if not fp_kw.get("fixed_point_stall_window"):
        fp_kw.pop("fixed_point_stall_window", None)  # a core without the option
    fp = p.solve("fixed-point", threads=threads, **fp_kw)
    nm = p.solve("nmg", tol=opts["tol"], max_cycles=opts["max_cycles"], threads=threads)
    return {"nodes": int(p.mesh.num_points), "cycle_type": _cycle_type(p),
            "fixed_point_iterations": fp.outer_iterations if fp.converged else None,
            "fixed_point_vcycles": fp.cycles, "fixed_point_status": fp.status,
            "fixed_point_seconds": fp.solve_seconds, "fixed_point_violation": contact_conditions(p, fp)["max"],
            "nmg_vcycles": nm.cycles, "nmg_converged": nm.converged, "nmg_status": nm.status,
            "nmg_seconds": nm.solve_seconds, "nmg_violation": contact_conditions(p, nm)["max"]}


def merge_levels(a: Dict, b: Dict) -> Dict:
    """The table of a's levels followed by b's (same frictions and cell), e.g. to grow a table one
    level at a time."""
    if a["frictions"] != b["frictions"] or a["cell"] != b["cell"]:
        raise ValueError("tables with different frictions or cells cannot be merged")
    out = dict(a)
    for k in ("levels", "nodes", "dofs"):
        out[k] = list(a[k]) + list(b[k])
    for k in _PER_RUN:
        out[k] = [list(ra) + list(rb) for ra, rb in zip(a[k], b[k])]
    out["seconds"] = a.get("seconds", 0.0) + b.get("seconds", 0.0)
    return out


def table1_figure(table: Dict):
    """The matplotlib Figure (not attached to pyplot) of Table 1 and Figure 1: Figure 1 left split
    into Algorithm 1's and Algorithm 2's cycles (top row, each with its own y scale, one legend
    right of them), Table 1 (bottom left) and Algorithm 1's outer iterations as 3D bars (Figure 1
    right, bottom right). Returns (figure, {"table", "alg1", "alg2", "bars"} -> axes)."""
    from matplotlib.figure import Figure

    from ..results.plots import plot_convergence, plot_fixed_point_iterations, plot_table1

    fig = Figure(figsize=(15, 11), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=(1.0, 1.15))
    alg1, alg2 = top.subplots(1, 2)
    tab = bottom.add_subplot(1, 2, 1)
    bars = bottom.add_subplot(1, 2, 2, projection="3d")
    plot_convergence(table, axes=(alg1, alg2))
    plot_table1(table, ax=tab)
    plot_fixed_point_iterations(table, ax=bars, annotate=False)  # the numbers are in the table beside
    hier = table.get("hierarchy")
    fig.suptitle(f"Hertz benchmark, {table.get('cell', 'triangle')}s" + (f", {hier} hierarchy" if hier else "")
                 + ": Algorithm 1 (fixed point) and Algorithm 2 (nonlinear multigrid)", fontsize=13)
    return fig, {"table": tab, "alg1": alg1, "alg2": alg2, "bars": bars}


def save_figures(table: Dict, path: str, dpi: int = 110) -> None:
    """One image at `path` (table1_figure): Figure 1 left as two panels, Algorithm 1 and Algorithm
    2 apart (top), Table 1 and Figure 1 right (bottom). Uses matplotlib's Figure directly, so it
    neither needs nor changes a pyplot backend."""
    fig, _ = table1_figure(table)
    fig.savefig(path, dpi=dpi)


def failed_runs(table: Dict, violation_tol: float = VIOLATION_TOL):
    """(F, level, why) of every nmg run that did not converge or whose result is not a solution."""
    bad = []
    for i, F in enumerate(table["frictions"]):
        for j, L in enumerate(table["levels"]):
            if not table["nmg_converged"][i][j]:
                bad.append((F, L, table["nmg_status"][i][j]))
            elif table["nmg_violation"][i][j] > violation_tol:
                bad.append((F, L, f"stopped as converged, but violates the contact conditions by "
                                  f"{table['nmg_violation'][i][j]:.1e} (relative)"))
    return bad


def run_table1(args) -> int:
    """`contactmg table1`: runs table1() over args.levels (default DEFAULT_ADAPTIVE_LEVELS on the
    adaptive hierarchy -- the default for triangles --, DEFAULT_LEVELS on the uniform one) and
    args.frictions (default the paper's ten coefficients) for args.cell, in args.jobs processes; writes the JSON to
    args.json ("-": standard output) and, with args.plot, one image at that path (save_figures:
    Figure 1 left as two panels, Table 1, Figure 1 right). Prints the table as text unless args.quiet (to standard
    error when the JSON goes to standard output). Exit status 0, or 3 when some nmg run did not
    converge or stopped on an iterate that is not a solution (relative violation of the contact
    conditions > VIOLATION_TOL); the JSON and the figure are written in either case."""
    kw = {}
    hierarchy = getattr(args, "hierarchy", None)
    if hierarchy is None:  # adaptive by default, as in the paper; quadrilaterals refine uniformly only
        hierarchy = "adaptive" if args.cell == "triangle" else "uniform"
    if hierarchy == "adaptive" and args.cell != "triangle":
        raise ValueError(f"--hierarchy adaptive is for triangles (newest-vertex bisection), not --cell {args.cell}")
    if hierarchy == "adaptive":
        kw.update(levels=DEFAULT_ADAPTIVE_LEVELS, fixed_point_stall_window=FIXED_POINT_STALL_WINDOW)
    if args.levels:
        kw["levels"] = args.levels
    if args.frictions:
        kw["frictions"] = args.frictions
    jobs = getattr(args, "jobs", 1) or 1
    table = table1(cell=args.cell, progress=not args.quiet, hierarchy=hierarchy, jobs=jobs, **kw)
    if args.json == "-":
        sys.stdout.write(json.dumps(table, indent=1) + "\n")
        sys.stdout.flush()
    elif args.json:
        with open(args.json, "w") as fh:
            json.dump(table, fh, indent=1)
            fh.write("\n")
    if args.plot:
        save_figures(table, args.plot)
    bad = failed_runs(table)
    stream = sys.stderr if args.json == "-" else sys.stdout
    if not args.quiet:
        print(format_table(table), file=stream)
    for F, L, why in bad:
        print(f"contactmg table1: nmg at F = {F:g}, level {L}: {why}", file=sys.stderr)
    return 3 if bad else 0


def format_table(table: Dict) -> str:
    """Text form: outer iterations of Algorithm 1 (V-cycles of Algorithm 1 / of Algorithm 2);
    a "!" marks an nmg run that did not converge or whose result violates the contact conditions."""
    bad = {(F, L) for F, L, _ in failed_runs(table)}
    head = "F \\ dofs " + "".join(f"{d:>20,}" for d in table["dofs"])
    lines = [head]
    for i, F in enumerate(table["frictions"]):
        cells = []
        for j, L in enumerate(table["levels"]):
            it = table["fixed_point_iterations"][i][j]
            mark = "!" if (F, L) in bad else ""
            cells.append(f"{(it if it is not None else 'no conv.')!s:>8} ({table['fixed_point_vcycles'][i][j]}/"
                         f"{table['nmg_vcycles'][i][j]}{mark})")
        lines.append(f"{F:<9g}" + "".join(f"{c:>20}" for c in cells))
    lines.append(f"levels {table['levels']}, {table['cell']}s; {table.get('seconds', 0):.1f} s")
    return "\n".join(lines)


def _cycle_type(p) -> str:
    """The problem's default cycle as written in the table, e.g. F(3,3)."""
    o = options_from(p.default_options)
    return f"{o.cycle}({o.nu1},{o.nu2})"
