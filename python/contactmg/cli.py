"""Command line: `contactmg hertz`, `contactmg table1` and the 3D `sphere` and `cork` (cli_3d.py; DESIGN section 9)."""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys
from typing import List, Optional

EXIT_OK, EXIT_BAD_INPUT, EXIT_NO_CONVERGENCE = 0, 2, 3
MAX_LEVELS = 12
MAX_CYCLES = 2 ** 31 - 1  # the core counts cycles in a C int
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _positive_int(name, lo=1, hi=None):
    def parse(s):
        try:
            v = int(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be an integer, got {s!r}")
        if v < lo or (hi is not None and v > hi):
            raise argparse.ArgumentTypeError(f"{name} must lie in {lo}..{hi}, got {v}" if hi else f"{name} must be >= {lo}, got {v}")
        return v
    return parse


def _nonneg_float(name, positive=False):
    def parse(s):
        try:
            v = float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {s!r}")
        if not math.isfinite(v) or v < 0 or (positive and v == 0):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number {'>' if positive else '>='} 0, got {s}")
        return v
    return parse


def _writable(path: str) -> str:
    """A path an output can be written to ("-": standard output), checked before any work."""
    if path == "-":
        return path
    if not path.strip():
        raise argparse.ArgumentTypeError("an output path is empty")
    d = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(d):
        raise argparse.ArgumentTypeError(f"cannot write {path}: directory {d} does not exist")
    if not os.access(d, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"cannot write {path}: permission denied")
    if os.path.isdir(path):
        raise argparse.ArgumentTypeError(f"cannot write {path}: it is a directory")
    return path


def _with_suffix(kind: str, suffixes):
    """A writable file path with one of the suffixes (a format that needs a file: no "-")."""
    def parse(path: str) -> str:
        if path == "-" or not path.strip():
            raise argparse.ArgumentTypeError(f"{kind} needs a file path ending in {', '.join(suffixes)}, got {path!r}")
        path = _writable(path)
        if not path.lower().endswith(tuple(suffixes)):
            raise argparse.ArgumentTypeError(f"{kind} {path}: unknown format (use {', '.join(suffixes)})")
        return path
    return parse


def _float(name):
    def parse(s):
        try:
            v = float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {s!r}")
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number, got {s}")
        return v
    return parse


def add_path_arguments(p) -> None:
    """The load path options (issue 12; cli_path.py runs them)."""
    p.add_argument("--steps", type=_positive_int("--steps", 1, 100000), default=None,
                   help="load path: the loading in N equal increments (incremental Coulomb law)")
    p.add_argument("--shear", type=_float("--shear"), default=None,
                   help="after the loading, move the top tangentially (x) by S (Cattaneo-Mindlin)")
    p.add_argument("--shear-steps", type=_positive_int("--shear-steps", 1, 100000), default=None,
                   help="increments of the shear phase (default 1)")
    p.add_argument("--series", type=_with_suffix("--series", (".pvd",)), metavar="PATH",
                   help="load path: a ParaView time series (.pvd collection of VTU files, one per step)")
    p.add_argument("--zone-plot", type=_with_suffix("--zone-plot", PLOT_SUFFIXES), metavar="PATH",
                   help="load path: the stick and slip zones against the load step")


def add_thread_options(p) -> None:
    p.add_argument("--threads", type=_positive_int("--threads", 0, 4096), default=0,
                   help="threads of the sweeps and products (default 0: all cores; the result does not depend on it)")
    p.add_argument("--ordering", choices=["lexicographic", "coloured"], default=None,
                   help="Gauss-Seidel order: colours of the block graph (parallel; the levels stored by colours) "
                        "or lexicographic (default: the problem's, coloured)")


def use_ordering(problem, args) -> None:
    """The problem's solver is built for --ordering (a coloured one stores its levels by colours)."""
    if args.ordering is not None:
        problem.default_ordering = args.ordering


def release_after_build(problem, args) -> None:
    """A single solve (not a load path, which builds a core solver per step, nor --method linear,
    whose second solver needs the transfers again) lets the problem drop the Python copies of the
    coarse meshes and the transfers once its core solver holds its own (issue 15)."""
    from . import cli_path

    if not cli_path.wanted(args) and args.method != "linear":
        problem.release_hierarchy = True


def write_boundary_stress_plot(result, friction: float, path: str) -> None:
    """Figure 2 (middle) of a 2D result: boundary stresses with the stick and slip zones."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .plots import plot_boundary_stress

    fig, ax = plt.subplots(figsize=(7, 4))
    plot_boundary_stress(result, ax=ax, friction=friction, margin=1.5)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Every option's help ends with its default, "(default: 0.4)", unless the help already says
    what the default is or there is none to show (no value, or a flag that is off)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if (not action.option_strings or action.default in (None, False, argparse.SUPPRESS)
                or "default" in text.lower()):
            return text
        return (text + " " if text else "") + "(default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose help shows the defaults (HelpFormatter), for every subcommand."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="contactmg", description="Multigrid for elastic contact with Coulomb friction")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    h = sub.add_parser("hertz", help="the Hertz benchmark of the seed paper")
    h.add_argument("--cell", choices=["triangle", "quad"], default="triangle",
                   help="triangles (P1) or quadrilaterals (Q1)")
    h.add_argument("--levels", type=_positive_int("--levels", 1, MAX_LEVELS), default=6,
                   help="levels in all; level 1 is the coarse mesh")
    h.add_argument("--friction", type=_nonneg_float("--friction"), default=0.4,
                   help="Coulomb friction coefficient F (0: frictionless)")
    h.add_argument("--method", choices=["nmg", "fixed-point", "linear", "tnnmg"], default="nmg",
                   help="nmg: Algorithm 2 (nonlinear multigrid); fixed-point: Algorithm 1; linear: the cost "
                        "reference; tnnmg: truncated nonsmooth Newton multigrid")
    h.add_argument("--tol", type=_nonneg_float("--tol", positive=True), default=1e-11,
                   help="stop when the correction's energy norm ||u^{k+1} - u^k||_A falls below this")
    h.add_argument("--max-cycles", type=_positive_int("--max-cycles", 1, MAX_CYCLES), default=200,
                   help="stop as not converged after this many cycles")
    h.add_argument("--cycle", choices=["V", "W", "F"], default="F", help="multigrid cycle type")
    h.add_argument("--nu1", type=_positive_int("--nu1", 0, 100), default=3, help="pre-smoothing steps per level")
    h.add_argument("--nu2", type=_positive_int("--nu2", 0, 100), default=3, help="post-smoothing steps per level")
    h.add_argument("--hierarchy", choices=["uniform", "adaptive"], default="uniform",
                   help="uniform refinement, or adaptive (hierarchical estimator, newest-vertex bisection)")
    h.add_argument("--linear", choices=["pcg", "cycle", "coarse"], default=None,
                   help="the linear correction of --method tnnmg (default pcg: conjugate gradients with the "
                        "line-smoothed truncated linear cycle; coarse: the coarse levels alone)")
    add_thread_options(h)
    h.add_argument("--json", type=_writable, metavar="PATH|-",
                   help="write the report as JSON to PATH (-: standard output)")
    h.add_argument("--vtu", type=_with_suffix("--vtu", (".vtu",)), metavar="PATH",
                   help="write the mesh with displacement, stresses and contact states (ParaView)")
    h.add_argument("--plot", type=_with_suffix("--plot", PLOT_SUFFIXES), metavar="PATH",
                   help="write the boundary stresses with the stick and slip zones (.png, .pdf or .svg)")
    add_path_arguments(h)
    h.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    t = sub.add_parser("table1", help="Table 1 and Figure 1 of the paper: both algorithms over levels and F")
    t.add_argument("--levels", type=_positive_int("--levels", 1, MAX_LEVELS), nargs="+", default=None,
                   help="the levels of the table (default: 3 5 7 9 11 on the adaptive hierarchy, 2-8 on the "
                        "uniform one)")
    t.add_argument("--frictions", type=_nonneg_float("--frictions", positive=True), nargs="+", default=None,
                   help="the friction coefficients (default: the paper's ten, 0.08 0.4 0.7 0.9 1 1.1 2 5 8 40)")
    t.add_argument("--cell", choices=["triangle", "quad"], default="triangle",
                   help="triangles (P1) or quadrilaterals (Q1)")
    t.add_argument("--hierarchy", choices=["uniform", "adaptive"], default=None,
                   help="adaptive (default for triangles, levels 3 5 7 9 11) or uniform (levels 2-8)")
    t.add_argument("--jobs", type=_positive_int("--jobs", 1, 64), default=min(2, os.cpu_count() or 1),
                   help="worker processes for the runs (default: 2 or the cores, if fewer)")
    t.add_argument("--json", type=_writable, metavar="PATH|-",
                   help="write the report as JSON to PATH (-: standard output)")
    t.add_argument("--plot", type=_with_suffix("--plot", PLOT_SUFFIXES), metavar="PATH",
                   help="write Table 1 and Figure 1 as one picture (.png, .pdf or .svg)")
    t.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    from . import cli_3d
    cli_3d.add_parsers(sub)
    from . import cylinders
    cylinders.add_parser(sub)
    from . import spheres
    spheres.add_parser(sub)
    return p


def peak_rss_mb() -> float:
    """Peak resident memory of this process in MB: VmHWM of its own address space where Linux
    tells it (ru_maxrss keeps the parent's peak across fork and exec: a command started from a
    large Python process reported that process's memory), else ru_maxrss."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def hertz_report(args, problem, result) -> dict:
    from . import hertz
    from .results import SLIP, STICK

    c = result.counts()
    reaction = result.reaction
    load = float(reaction[1])
    sn = result.normal_stress
    out = {
        "problem": "hertz", "dim": problem.mesh.dim, "cell": args.cell, "levels": args.levels,
        "nodes": int(problem.mesh.num_points), "dofs": int(problem.mesh.num_points * problem.mesh.dim),
        "method": args.method, "friction": args.friction, "tol": args.tol, "converged": result.converged,
        "status": result.status, "cycles": result.cycles, "outer_iterations": result.outer_iterations,
        "setup_seconds": result.setup_seconds, "solve_seconds": result.solve_seconds,
        "history": [{"cycle": int(k), "correction_norm": float(v), "seconds": float(s)}
                    for k, v, s in zip(result.history["cycle"], result.history["correction_norm"], result.history["seconds"])],
        "contact_nodes": c["contact_nodes"], "stick_nodes": c["stick_nodes"], "slip_nodes": c["slip_nodes"],
        # the contract's definition (largest |x| of a zone node), for every single-solve command
        "contact_halfwidth": result.halfwidth((STICK, SLIP)), "stick_halfwidth": result.halfwidth((STICK,)),
        "reaction": [float(v) for v in reaction],
        "max_normal_stress": float(abs(sn).max()) if len(sn) else 0.0,
        "coarse_rebuilds": result.rebuilds,
        "cycle_type": f"{args.cycle}({args.nu1},{args.nu2})",
        "hertz_halfwidth": hertz.halfwidth(load) if load > 0 else None,
        "hertz_peak_pressure": hertz.peak_pressure(load) if load > 0 else None,
        "peak_rss_mb": peak_rss_mb(),
        "threads": result.extra.get("threads"), "ordering": result.extra.get("ordering"),
        "hierarchy": problem.hierarchy.kind,
    }
    if args.method == "tnnmg" and "linear_iterations" in result.history:  # issue 14: its linear correction
        out["linear_correction"] = getattr(args, "linear", None) or "pcg"
        out["linear_cycles"] = int(sum(result.history["linear_iterations"]))
    if problem.hierarchy.estimated_error:
        out["estimated_error"] = [float(e) for e in problem.hierarchy.estimated_error]
    ref = result.extra.get("reference")
    if ref is not None:  # --method linear: the nmg solve that gave the contact state, same process
        out["nmg_cycles"] = ref["cycles"]
        out["nmg_solve_seconds"] = ref["solve_seconds"]
        out["nmg_over_linear"] = ref["solve_seconds"] / result.solve_seconds if result.solve_seconds > 0 else None
    return out


def _emit_json(path: str, obj: dict) -> None:
    text = json.dumps(obj, indent=1)
    if path == "-":
        sys.stdout.write(text + "\n")
    else:
        with open(path, "w") as fh:
            fh.write(text + "\n")


def run_hertz(args) -> int:
    from . import cli_path
    from .hertz import hertz_problem

    cli_path.check(args)
    if args.linear is not None and args.method != "tnnmg":
        raise ValueError("--linear chooses the linear correction of --method tnnmg")
    problem = hertz_problem(args.cell, args.levels, args.friction, coulomb_at_zero=args.method == "fixed-point",
                            cycle=args.cycle, nu1=args.nu1, nu2=args.nu2, hierarchy=args.hierarchy)
    use_ordering(problem, args)
    release_after_build(problem, args)
    if cli_path.wanted(args):
        from .generators import HERTZ_TOP
        from .hertz import TOP_DISPLACEMENT

        path = cli_path.solve(args, problem, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), (args.shear or 0.0, 0.0))
        result = path.last
    else:
        extra = {} if args.linear is None else {"linear": args.linear}
        result = problem.solve(args.method, tol=args.tol, max_cycles=args.max_cycles, threads=args.threads,
                               ordering=args.ordering, **extra)
    report = hertz_report(args, problem, result)
    if cli_path.wanted(args):
        cli_path.report(args, path, report)
    if args.json:
        _emit_json(args.json, report)
    if args.vtu:
        result.write_vtu(args.vtu)
    if args.plot:
        write_boundary_stress_plot(result, args.friction, args.plot)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(f"hertz {args.cell} levels={args.levels} dofs={report['dofs']} F={args.friction} method={args.method}: "
              f"{result.status}, {result.cycles} cycles"
              + (f", {result.outer_iterations} outer iterations" if result.outer_iterations is not None else "")
              + f", setup {result.setup_seconds:.2f} s, solve {result.solve_seconds:.2f} s, "
              f"contact {report['contact_nodes']} (stick {report['stick_nodes']}, slip {report['slip_nodes']}), "
              f"reaction {report['reaction'][1]:.6g}", file=stream)
    if cli_path.wanted(args) and not args.quiet:
        cli_path.print_steps(report, sys.stderr if args.json == "-" else sys.stdout)
    return EXIT_OK if (path.converged if cli_path.wanted(args) else result.converged) else EXIT_NO_CONVERGENCE


def main(argv: Optional[List[str]] = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "hertz":
            return run_hertz(args)
        if args.command == "cylinders":
            from .cylinders import run_cylinders
            return run_cylinders(args)
        if args.command == "spheres":
            from .spheres import run_spheres
            return run_spheres(args)
        from .cli_3d import COMMANDS
        if args.command in COMMANDS:
            return COMMANDS[args.command](args)
        from .table1 import run_table1
        return run_table1(args)
    except (ValueError, TypeError, MemoryError) as e:
        print(f"contactmg {args.command}: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"contactmg {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
