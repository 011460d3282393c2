"""The `contactmg` command: the parser of every command and the dispatch to them."""
from __future__ import annotations

import argparse
import os
import sys
import warnings
from typing import List, Optional

from .common import (EXIT_BAD_INPUT, EXIT_NO_CONVERGENCE, EXIT_OK, MAX_LEVELS, PLOT_SUFFIXES, _Parser, _emit_json, _nonneg_float, _positive_int, _with_suffix, _writable, add_path_arguments, add_report_options, add_stop_options, add_thread_options, hertz_report, make_output_folders, release_after_build, stop_fields, use_ordering, write_boundary_stress_plot)


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
    add_stop_options(h)
    h.add_argument("--nu1", type=_positive_int("--nu1", 0, 100), default=3, help="pre-smoothing steps per level")
    h.add_argument("--nu2", type=_positive_int("--nu2", 0, 100), default=3, help="post-smoothing steps per level")
    h.add_argument("--hierarchy", choices=["uniform", "adaptive"], default="uniform",
                   help="uniform refinement, or adaptive (hierarchical estimator, newest-vertex bisection)")
    h.add_argument("--linear", choices=["pcg", "cycle", "coarse"], default=None,
                   help="the linear correction of --method tnnmg (default pcg: conjugate gradients with the "
                        "line-smoothed truncated linear cycle; coarse: the coarse levels alone)")
    add_thread_options(h)
    add_report_options(h)
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
    from . import three_d as cli_3d
    cli_3d.add_parsers(sub)
    from . import two_body
    two_body.add_cylinders_parser(sub)
    two_body.add_spheres_parser(sub)
    from . import run_model
    run_model.add_run_parser(sub)
    return p


def run_hertz(args) -> int:
    """The hertz command: solve the Hertz benchmark and report; returns the exit status."""
    from ..cli import path as cli_path
    from ..examples.hertz import hertz_problem

    cli_path.check(args)
    if args.linear is not None and args.method != "tnnmg":
        raise ValueError("--linear chooses the linear correction of --method tnnmg")
    problem = hertz_problem(args.cell, args.levels, args.friction, coulomb_at_zero=args.method == "fixed-point",
                            cycle=args.cycle, nu1=args.nu1, nu2=args.nu2, hierarchy=args.hierarchy)
    use_ordering(problem, args)
    release_after_build(problem, args)
    if cli_path.wanted(args):
        from ..mesh.generators import HERTZ_TOP
        from ..examples.hertz import TOP_DISPLACEMENT

        path = cli_path.solve(args, problem, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), (args.shear or 0.0, 0.0))
        result = path.last
    else:
        extra = {} if args.linear is None else {"linear": args.linear}
        result = problem.solve(args.method, **stop_fields(args), max_cycles=args.max_cycles, threads=args.threads,
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


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning of a command as one line: the user of the command line has no use for the Python
    source line that the warnings module prints by default."""
    text = " ".join(str(message).split())
    try:
        print(f"contactmg: warning: {text}", file=file if file is not None else sys.stderr)
    except OSError:  # standard error closed: the warning is lost, as the default would lose it
        pass


def main(argv: Optional[List[str]] = None) -> int:
    """The command line: parse `argv` and run the command; returns the exit status. Warnings print as
    one line `contactmg: warning: ...` while it runs; the library's own format is restored after (a
    caller in the same process keeps it)."""
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _main(argv)


def _main(argv: Optional[List[str]]) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    from . import distributed
    if distributed.wanted():
        return distributed.run(args) if args.command in ("hertz", "sphere") else distributed.refuse(args)
    try:
        make_output_folders(args)
        if args.command == "hertz":
            return run_hertz(args)
        if args.command == "cylinders":
            from .two_body import run_cylinders
            return run_cylinders(args)
        if args.command == "spheres":
            from .two_body import run_spheres
            return run_spheres(args)
        if args.command == "run":
            from .run_model import run_model
            return run_model(args)
        from .three_d import COMMANDS
        if args.command in COMMANDS:
            return COMMANDS[args.command](args)
        from ..examples.table1 import run_table1
        return run_table1(args)
    except (ValueError, TypeError, MemoryError) as e:
        print(f"contactmg {args.command}: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"contactmg {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
