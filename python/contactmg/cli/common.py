"""What every command shares: argument types, exit statuses, the JSON report of a contact solve and its writers."""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys

from ..solve.options import options_from
from .stop import stop_fields


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


class OutputPath(str):
    """A file path an option writes to (checked by _writable): its missing folders are made by
    make_output_folders once the whole command line has been parsed."""


def _writable(path: str) -> str:
    """A path an output can be written to ("-": standard output), checked before any work. Folders
    that do not exist yet are fine where the nearest existing one is a writable directory: they are
    made before the command runs (make_output_folders), not here, so that a command line refused
    for another argument leaves nothing behind."""
    if path == "-":
        return path
    if not path.strip():
        raise argparse.ArgumentTypeError("an output path is empty")
    d = os.path.dirname(os.path.abspath(path))
    existing = d
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise argparse.ArgumentTypeError(f"cannot write {path}: {existing} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"cannot write {path}: permission denied")
    if os.path.isdir(path):
        raise argparse.ArgumentTypeError(f"cannot write {path}: it is a directory")
    return OutputPath(path)


def make_output_folders(args) -> None:
    """Make the missing folders of every output path of the parsed command line (--json out/x.json
    writes into a new out/); ValueError where one cannot be made."""
    for value in vars(args).values():
        for path in value if isinstance(value, list) else [value]:
            if isinstance(path, OutputPath):
                folder = os.path.dirname(os.path.abspath(path))
                try:
                    os.makedirs(folder, exist_ok=True)
                except OSError as e:
                    raise ValueError(f"cannot make the folder {folder} for {path}: {e.strerror}") from None


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
    """The load path options (path.py runs them)."""
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


def add_stop_options(p) -> None:
    """Add --tol, --max-cycles and --cycle: when a solve stops and which multigrid cycle it runs."""
    p.add_argument("--tol", type=_nonneg_float("--tol", positive=True), default=None,
                   help="stop when the correction's energy norm ||u^{k+1} - u^k||_A falls below this; without "
                        "--rtol the paper's stop (default: 1e-11)")
    p.add_argument("--rtol", type=_nonneg_float("--rtol", positive=True), default=None,
                   help="stop when the correction's energy norm falls below this times the larger of the first "
                        "correction's and ||u||_A (the same cycles in any units)")
    p.add_argument("--max-cycles", type=_positive_int("--max-cycles", 1, MAX_CYCLES), default=200,
                   help="stop as not converged after this many cycles")
    p.add_argument("--cycle", choices=["V", "W", "F"], default="F", help="multigrid cycle type")


def add_report_options(p) -> None:
    """Add --json and --vtu: the report as JSON and the solution for ParaView."""
    p.add_argument("--json", type=_writable, metavar="PATH|-",
                   help="write the report as JSON to PATH (-: standard output)")
    p.add_argument("--vtu", type=_with_suffix("--vtu", (".vtu",)), metavar="PATH",
                   help="write the mesh with displacement, stresses and contact states (ParaView)")


def add_thread_options(p) -> None:
    """Add --threads and --ordering to a command's parser."""
    p.add_argument("--threads", type=_positive_int("--threads", 0, 4096), default=0,
                   help="threads of the sweeps and products (default 0: all cores; the result does not depend on it)")
    p.add_argument("--ordering", choices=["lexicographic", "coloured", "hashed"], default=None,
                   help="Gauss-Seidel order: colours of the block graph (parallel; the levels stored by colours), "
                        "lexicographic, or hashed (the colours of a run on MPI ranks) (default: the problem's, coloured)")


def use_ordering(problem, args) -> None:
    """The problem's solver is built for --ordering (a coloured one stores its levels by colours)."""
    if args.ordering is not None:
        problem.default_options = options_from(problem.default_options).replace(ordering=args.ordering)


def release_after_build(problem, args) -> None:
    """A single solve (not a load path, nor --method linear, whose second solver needs the transfers
    again) lets the problem drop the Python copies of the coarse meshes and the transfers once its
    core solver holds its own (0011-memory-release)."""
    from ..cli import path as cli_path

    if not cli_path.wanted(args) and args.method != "linear":
        problem.default_options = options_from(problem.default_options).replace(release_hierarchy=True)


def write_boundary_stress_plot(result, friction: float, path: str) -> None:
    """Figure 2 (middle) of a 2D result: boundary stresses with the stick and slip zones."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..results.plots import plot_boundary_stress

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
    """The JSON report of a 2D contact solve (the command-line contract's keys)."""
    from ..examples import hertz
    from ..results.result import SLIP, STICK

    c = result.counts()
    reaction = result.reaction
    load = float(reaction[1])
    sn = result.normal_stress
    out = {
        "problem": "hertz", "dim": problem.mesh.dim, "cell": args.cell, "levels": args.levels,
        "nodes": int(problem.mesh.num_points), "dofs": int(problem.mesh.num_points * problem.mesh.dim),
        "method": args.method, "friction": args.friction, "tol": stop_fields(args).get("tol", 0.0),
        "rtol": stop_fields(args).get("rtol", 0.0), "converged": result.converged,
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
        "hierarchy": problem.hierarchy.kind, "ranks": 1,
    }
    if args.method == "tnnmg" and "linear_iterations" in result.history:  # its linear correction
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
