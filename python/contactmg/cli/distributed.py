"""The hertz and sphere commands on several MPI ranks (`mpirun -n N contactmg hertz ...`): the
distributed solve (contactmg.distributed), the same JSON keys as on one process plus `ranks` and
the per-rank seconds and memory; rank 0 alone prints and writes. What is not distributed yet (other
methods, adaptive hierarchies, load paths, plots) ends with exit status 2 and one line that says so."""
from __future__ import annotations

import sys

from .common import (EXIT_BAD_INPUT, EXIT_NO_CONVERGENCE, EXIT_OK, _emit_json, make_output_folders, peak_rss_mb,
                     stop_fields)


def wanted() -> bool:
    """Whether this process is one of several MPI ranks."""
    from ..distributed.comm import launched_by_mpi
    if not launched_by_mpi():
        return False
    from ..distributed import get_comm
    return get_comm().size > 1


def refuse(args) -> int:
    """A command that does not run distributed, started on several ranks: one line from rank 0 and
    exit status 2 on every rank (each rank would otherwise solve the whole problem alone)."""
    from ..distributed import get_comm
    if get_comm().rank == 0:
        print(f"contactmg {args.command}: error: {args.command} is not distributed yet (on several ranks only hertz "
              "and sphere run): run it on one rank, without mpirun", file=sys.stderr)
    return EXIT_BAD_INPUT


def _refuse_unsupported(args) -> None:
    if args.method != "nmg":
        raise ValueError(f"--method {args.method} is not distributed yet: the distributed solve is nmg (truncated "
                         "monotone multigrid); run on one rank")
    if getattr(args, "hierarchy", "uniform") != "uniform":
        raise ValueError("--hierarchy adaptive is not distributed yet: run on one rank")
    if getattr(args, "plot", None):
        raise ValueError("--plot is not distributed yet: write --vtu and plot it, or run on one rank")
    for name in ("steps", "shear", "load_path", "path"):
        if getattr(args, name, None):
            raise ValueError("load paths are not distributed yet: run on one rank")
    if args.command == "sphere":
        from ..examples import sphere
        if args.displacement != sphere.DISPLACEMENT:
            raise ValueError("--displacement is not distributed yet (the sphere's default only): run on one rank")


def run(args) -> int:
    """The command on the ranks of COMM_WORLD; returns the exit status (the same on every rank)."""
    from ..distributed import DistributedError, get_comm
    from ..distributed.comm import op
    from ..examples.distributed import hertz, sphere
    from ..model.friction import Coulomb
    from ..solve.options import SolverOptions

    comm = get_comm()
    try:
        _refuse_unsupported(args)  # the same arguments, the same answer on every rank
        make_output_folders(args)  # every rank: a folder that exists already is no error
    except ValueError as e:
        if comm.rank == 0:
            print(f"contactmg {args.command}: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:  # the distributed errors reach every rank together (raise_together)
        make = hertz if args.command == "hertz" else sphere
        problem = make(args.levels, args.cell, Coulomb(args.friction) if args.friction > 0 else None, comm)
        stop = stop_fields(args)
        result = problem.solve(SolverOptions(method="nmg", cycle=args.cycle, nu1=args.nu1, nu2=args.nu2,
                                             max_cycles=args.max_cycles, **stop))
    except DistributedError as e:
        if comm.rank == 0:
            message = str(e).split(": ", 2)[-1]
            print(f"contactmg {args.command}: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    seconds = comm.gather(result.seconds, root=0)
    memory = comm.gather(result.memory_bytes, root=0)
    rss = comm.allreduce(peak_rss_mb(), op=op(comm, "MAX"))
    if args.vtu:
        result.write_vtu(args.vtu)
    if comm.rank != 0:
        return EXIT_OK if result.converged else EXIT_NO_CONVERGENCE
    fine = problem.hierarchy.levels[-1]
    d = problem.fine.d
    report = {
        "problem": args.command, "dim": d, "cell": args.cell, "levels": args.levels,
        "nodes": int(fine.num_global_nodes), "dofs": int(fine.num_global_nodes * d), "method": "nmg",
        "friction": args.friction, "tol": stop.get("tol", 0.0), "rtol": stop.get("rtol", 0.0),
        "converged": result.converged, "status": result.status, "cycles": result.cycles, "outer_iterations": None,
        "setup_seconds": problem.assembly_seconds + problem.hierarchy.build_seconds + result.build_seconds,
        "solve_seconds": result.seconds,
        "history": [{"cycle": h["cycle"], "correction_norm": h["correction_norm"], "seconds": h["seconds"]}
                    for h in result.history],
        "contact_nodes": result.contact_nodes, "stick_nodes": result.stick_nodes, "slip_nodes": result.slip_nodes,
        "contact_halfwidth": result.contact_halfwidth, "stick_halfwidth": result.stick_halfwidth,
        "reaction": [float(v) for v in result.reaction], "max_normal_stress": result.max_normal_stress,
        "coarse_rebuilds": result.rebuilds, "cycle_type": f"{args.cycle}({args.nu1},{args.nu2})", "peak_rss_mb": rss, "threads": 1,
        "ordering": "hashed", "hierarchy": "uniform",
        "ranks": comm.size, "rank_solve_seconds": seconds, "rank_memory_bytes": memory,
        "phase_seconds": result.phase_seconds, "exchanges": result.exchanges, "whole_levels": result.whole_levels,
    }
    if args.command == "hertz":
        from ..examples import hertz as h
        load = report["reaction"][1]
        report["hertz_halfwidth"] = h.halfwidth(load) if load > 0 else None
        report["hertz_peak_pressure"] = h.peak_pressure(load) if load > 0 else None
    else:
        from ..examples import sphere as s
        report["displacement"] = s.DISPLACEMENT
        report["contact_radius"], report["stick_radius"] = result.contact_halfwidth, result.stick_halfwidth
        load = report["reaction"][2]
        report["hertz_radius"] = s.hertz_radius(load) if load > 0 else None
        report["hertz_p0"] = s.hertz_p0(load) if load > 0 else None
        report["central_pressure"] = result.central_pressure if result.contact_nodes else None
    if args.json:
        _emit_json(args.json, report)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(f"{args.command} {args.cell} levels={args.levels} dofs={report['dofs']} ranks={comm.size}: "
              f"{result.status}, {result.cycles} cycles, solve {result.seconds:.2f} s, contact "
              f"{result.contact_nodes}, reaction {report['reaction'][d - 1]:.6g}", file=stream)
    return EXIT_OK if result.converged else EXIT_NO_CONVERGENCE
