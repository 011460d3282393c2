"""The `run` command: solve the model of a model file (model_file.py) in its load steps, write the
outputs it asks for and report."""
from __future__ import annotations

import os
import sys
import time

import numpy as np

from ..mesh.io import write_mesh
from ..results.series import write_pvd_collection
from ..solve.loadpath import LoadPath
from ..solve.solver import Solver
from . import common as cli
from .model_file import Model, read_model


def add_run_parser(sub) -> None:
    """Add the run command."""
    r = sub.add_parser("run", help="solve the contact problem described by a model file (TOML)")
    r.add_argument("model", metavar="MODEL.toml", help="the model file (docs/guide/model-file.md)")
    r.add_argument("--json", type=cli._writable, metavar="PATH|-",
                   help="write the report as JSON to PATH (-: standard output); output.json of the file is "
                        "written as well")
    r.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def solve_model(model: Model):
    """The results of the model's steps (a list of ContactResult) and the wall seconds of the solve:
    one solve for one step, a proportional LoadPath (1/count .. 1 of every load and prescribed
    displacement) otherwise."""
    t0 = time.perf_counter()
    if model.steps > 1:
        path = LoadPath.proportional(model.problem, model.steps)
        # the file's method, else the path's default for the problem (that of a single solve, nmg
        # where that is tnnmg: load steps need a slip origin)
        results = path.solve(options=model.options).steps
    else:
        res = Solver(model.problem, model.options).solve()
        res.extra.update(step=1, parameter=1.0)
        results = [res]
    return results, time.perf_counter() - t0


def _vec(v) -> list:
    return [float(x) for x in np.asarray(v, dtype=float)]


def model_report(model: Model, results, seconds: float, read_seconds: float = 0.0,
                 command_seconds: float = None) -> dict:
    """The JSON report of a run (the command-line contract's keys of `run`): `seconds` the wall time
    of the solve (the load path's), `read_seconds` that of reading the model file and its meshes
    (less the hierarchies and the assembly, which setup_seconds counts), `command_seconds` that of
    the whole command (default: the solve's)."""
    p, res = model.problem, results[-1]
    names = [b.name for b in model.bodies]
    c = res.counts()
    reactions = []
    for key, force in res.reactions().items():
        body, tags = key if p.multibody else (0, key)
        reactions.append({"body": names[body], "tags": list(tags) if isinstance(tags, tuple) else [tags],
                          "force": _vec(force)})
    # the elastic supports carry load too: without them the forces of the report do not balance the load
    spring_forces = []
    for key, force in res.spring_forces().items():
        body, tag = key if p.multibody else (0, key)
        spring_forces.append({"body": names[body], "tags": [int(tag)], "force": _vec(force)})
    contact_forces = {k: _vec(v) for k, v in res.contact_forces().items()}
    check = {k: float(v) for k, v in res.check().items()}
    converged = len(results) == model.steps and all(r.converged for r in results)
    sn = res.normal_stress
    return {
        "command": "run", "model": model.path, "description": model.description, "dim": p.mesh.dim,
        "cell": p.mesh.cell_type,
        "bodies": [{"name": b.name, "mesh": b.mesh_file, "levels": b.levels, "hierarchy": b.hierarchy,
                    "nodes": int(b.mesh.num_points), "cells": int(b.mesh.num_cells)} for b in model.bodies],
        "levels": max(b.levels for b in model.bodies),
        # the levels the solver's cycle runs on: with those made below the mesh (problem.notes says why)
        "multigrid_levels": len(p.transfers) + 1, "notes": list(p.notes),
        "nodes": int(p.mesh.num_points), "dofs": int(p.mesh.num_points * p.mesh.dim),
        "method": res.method, "law": p.law, "friction": model.friction,
        "tol": model.options.stop[0], "rtol": model.options.stop[1],
        "converged": converged, "status": res.status, "cycles": res.cycles,
        "cycles_per_step": [int(r.cycles) for r in results],
        # the layout of the load path commands' reports (cli/path.py): a row per step solved, the path's totals
        "steps": [{"step": int(r.extra["step"]), "parameter": float(r.extra["parameter"]), "cycles": int(r.cycles),
                   "converged": bool(r.converged), "status": r.status, "solve_seconds": float(r.solve_seconds),
                   **r.counts()} for r in results],
        "path": {"steps": model.steps, "steps_solved": len(results), "converged": converged,
                 "total_cycles": int(sum(r.cycles for r in results)), "seconds": seconds,
                 "parameters": [float(r.extra["parameter"]) for r in results]},
        "setup_seconds": float(results[0].setup_seconds), "solve_seconds": float(sum(r.solve_seconds for r in results)),
        "read_seconds": float(read_seconds),
        # the wall time of the command (reading, set-up, solve, the outputs other than this report): on a
        # large mesh the reading alone took a quarter of it, which the solve's time left out
        "seconds": float(seconds if command_seconds is None else command_seconds),
        "contact_nodes": c["contact_nodes"], "stick_nodes": c["stick_nodes"], "slip_nodes": c["slip_nodes"],
        "contact_extent": float(res.contact_extent),
        "contact_forces": contact_forces, "reactions": reactions, "spring_forces": spring_forces,
        "load": _vec(res.canonical_load().sum(axis=0)),
        "max_normal_stress": float(abs(sn).max()) if len(sn) else 0.0,
        "max_von_mises": float(res.von_mises().max(initial=0.0)),
        "check": check, "check_max": check.get("max", 0.0),
        "peak_rss_mb": cli.peak_rss_mb(),
        "threads": res.extra.get("threads"), "ordering": res.extra.get("ordering"),
        "outputs": model.outputs.files(),
    }


def _prepare_folders(model: Model) -> None:
    """Make the output files' folders (the file names them relative to itself) before the solve, so
    that a path that cannot be written fails at once (exit 2), not after the work."""
    for kind, path in model.outputs.files().items():
        folder = os.path.dirname(path)
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError as e:
            raise ValueError(f"{model.path}: output.{kind}: cannot make the folder {folder}: {e.strerror}") from None
        if not os.access(folder, os.W_OK) or os.path.isdir(path):
            raise ValueError(f"{model.path}: output.{kind}: cannot write {path}")


def write_outputs(model: Model, results) -> None:
    """The VTU of the last step, the PVD series of every step and the boundary stress plot."""
    out, res = model.outputs, results[-1]
    if out.vtu:
        res.write_vtu(out.vtu)
    if out.pvd:
        frames = [(r.extra["parameter"], r.mesh, r.point_data()) for r in results]
        write_pvd_collection(out.pvd, frames, write_mesh)
    if out.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..results.plots import plot_boundary_stress

        fig, ax = plt.subplots(figsize=(7, 4))
        plot_boundary_stress(res, ax=ax, friction=model.friction.get("coefficient"))
        ax.set_title(f"{os.path.basename(model.path)}: boundary stresses, step {len(results)}", fontsize=9)
        fig.tight_layout()
        fig.savefig(out.plot, dpi=150)
        plt.close(fig)


def run_model(args) -> int:
    """The run command: read the model file, solve, write, report; returns the exit status."""
    t0 = time.perf_counter()
    model = read_model(args.model)
    # read_model builds the hierarchies and assembles the problem too; those count in setup_seconds
    read_seconds = max(0.0, time.perf_counter() - t0 - model.problem.assembly_seconds)
    _prepare_folders(model)
    results, solve_wall = solve_model(model)
    write_outputs(model, results)
    seconds = time.perf_counter() - t0
    report = model_report(model, results, solve_wall, read_seconds, seconds)
    for path in (model.outputs.json, args.json):
        if path:
            cli._emit_json(path, report)
    stream = sys.stderr if args.json == "-" else sys.stdout
    if model.outputs.summary and not args.quiet:
        print(results[-1].summary(), file=stream)
    if not args.quiet:
        print(f"run {model.path}: {len(model.bodies)} bodies, dofs={report['dofs']}, method={report['method']}, "
              f"{report['law']}: {'converged' if report['converged'] else 'NOT converged'}, steps "
              f"{len(results)}/{model.steps}, cycles per step {' '.join(map(str, report['cycles_per_step']))}, "
              f"{seconds:.2f} s", file=stream)
    return cli.EXIT_OK if report["converged"] else cli.EXIT_NO_CONVERGENCE
