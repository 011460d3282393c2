"""The 3D commands `contactmg sphere` and `contactmg cork`, registered by
main.py; the JSON keys of `contactmg hertz` plus their own."""
from __future__ import annotations

import sys

from . import common as cli

PLOT_SUFFIXES = cli.PLOT_SUFFIXES
MAX_LEVELS_3D = 7


def _common(p, levels_default):
    p.add_argument("--levels", type=cli._positive_int("--levels", 1, MAX_LEVELS_3D), default=levels_default,
                   help="levels in all; level 1 is the coarse mesh")
    p.add_argument("--friction", type=cli._nonneg_float("--friction"), default=0.4,
                   help="Coulomb friction coefficient F (0: frictionless)")
    p.add_argument("--method", choices=["nmg", "fixed-point", "linear", "tnnmg"], default="nmg",
                   help="nmg: Algorithm 2 (nonlinear multigrid); fixed-point: Algorithm 1; linear: the cost "
                        "reference; tnnmg: truncated nonsmooth Newton multigrid")
    cli.add_stop_options(p)
    p.add_argument("--nu1", type=cli._positive_int("--nu1", 0, 100), default=3, help="pre-smoothing steps per level")
    p.add_argument("--nu2", type=cli._positive_int("--nu2", 0, 100), default=3, help="post-smoothing steps per level")
    cli.add_thread_options(p)
    cli.add_report_options(p)
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def add_parsers(sub) -> None:
    """Add the sphere and cork commands."""
    from ..examples import cork
    from ..examples import sphere

    s = sub.add_parser("sphere", help="the Hertz sphere: a half ball pressed onto a rigid plane (3D)")
    s.add_argument("--cell", choices=["tetra", "hexahedron"], default="hexahedron", help="tetrahedra or hexahedra")
    _common(s, sphere.DEFAULT_LEVELS)
    s.add_argument("--displacement", type=cli._nonneg_float("--displacement", positive=True), default=sphere.DISPLACEMENT,
                   help="displacement D of the flat top towards the plane")
    s.add_argument("--hierarchy", choices=list(sphere.HIERARCHIES), default="uniform",
                   help="adaptive: refined by the hierarchical estimator and bisection (tetra only)")
    s.add_argument("--plot", type=cli._with_suffix("--plot", PLOT_SUFFIXES), metavar="PATH",
                   help="write the contact stresses against the distance from the axis (.png, .pdf or .svg)")
    cli.add_path_arguments(s)
    c = sub.add_parser("cork", help="the cork pushed into a narrowing bottle neck (3D, Figure 2 right)")
    _common(c, cork.DEFAULT_LEVELS)
    c.add_argument("--push", type=cli._nonneg_float("--push"), default=cork.PUSH,
                   help="distance D the plunger pushes the cork's top down (mm)")
    c.add_argument("--picture", type=cli._with_suffix("--picture", PLOT_SUFFIXES), metavar="PATH",
                   help="write the picture of the deformed cork and a section against the neck (.png, .pdf or .svg)")
    # load path: push in (--steps), then pull the plunger back to where it started
    c.add_argument("--steps", type=cli._positive_int("--steps", 1, 100000), default=None,
                   help="load path: the push in N equal increments (incremental Coulomb law)")
    c.add_argument("--pull-back", action="store_true", help="after the push, move the top back to its start")
    c.add_argument("--pull-back-steps", dest="shear_steps", type=cli._positive_int("--pull-back-steps", 1, 100000),
                   default=None, help="increments of the pull-back (default 1)")
    c.add_argument("--series", type=cli._with_suffix("--series", (".pvd",)), metavar="PATH",
                   help="load path: a ParaView time series (.pvd collection of VTU files, one per step)")
    c.add_argument("--zone-plot", type=cli._with_suffix("--zone-plot", PLOT_SUFFIXES), metavar="PATH",
                   help="load path: the stick and slip zones against the load step")


def _report(args, problem, result, name) -> dict:
    """The keys of `contactmg hertz`, in 3D: the half-widths are radii about the z axis."""
    from ..examples import sphere

    out = cli.hertz_report(args, problem, result)
    for k in ("hertz_halfwidth", "hertz_peak_pressure"):
        out.pop(k, None)
    out["problem"] = name
    out["contact_radius"] = sphere.radius_of(result, (1, 2))
    out["stick_radius"] = sphere.radius_of(result, (1,))
    out["contact_halfwidth"], out["stick_halfwidth"] = out["contact_radius"], out["stick_radius"]
    return out


def _save(fig, path):
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def _finish(args, report, result, label, path=None) -> int:
    if args.json:
        cli._emit_json(args.json, report)
    if args.vtu:
        result.write_vtu(args.vtu)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(f"{label} levels={args.levels} dofs={report['dofs']} F={args.friction} method={args.method}: "
              f"{result.status}, {result.cycles} cycles"
              + (f", {result.outer_iterations} outer iterations" if result.outer_iterations is not None else "")
              + f", setup {result.setup_seconds:.2f} s, solve {result.solve_seconds:.2f} s, "
              f"contact {report['contact_nodes']} (stick {report['stick_nodes']}, slip {report['slip_nodes']})", file=stream)
        if path is not None:
            from . import path as cli_path
            cli_path.print_steps(report, stream)
    converged = path.converged if path is not None else result.converged
    return cli.EXIT_OK if converged else cli.EXIT_NO_CONVERGENCE


def run_sphere(args) -> int:
    """The sphere command: solve the 3D half ball against a plane and report; returns the exit status."""
    from ..examples import sphere

    from . import path as cli_path
    from ..mesh.generators_3d import BALL_TOP

    cli_path.check(args)
    if args.hierarchy == "adaptive" and args.cell != "tetra":
        raise ValueError(f"--hierarchy adaptive is for simplices (bisection of tetrahedra): use --cell tetra, "
                         f"not {args.cell}")
    try:
        problem = sphere.sphere_problem(args.cell, args.levels, args.friction, args.displacement,
                                        coulomb_at_zero=args.method == "fixed-point", cycle=args.cycle, nu1=args.nu1,
                                        nu2=args.nu2, hierarchy=args.hierarchy)
        cli.use_ordering(problem, args)
        cli.release_after_build(problem, args)
    except RuntimeError as e:  # a solve of the adaptive refinement did not converge: no result to report
        print(f"contactmg sphere: {e}", file=sys.stderr)
        return cli.EXIT_NO_CONVERGENCE
    path = None
    if cli_path.wanted(args):
        path = cli_path.solve(args, problem, [BALL_TOP], (0.0, 0.0, -args.displacement), (args.shear or 0.0, 0.0, 0.0),
                              position=sphere.radial_distance, label="distance from the axis")
        result = path.last
    else:
        result = problem.solve(args.method, **cli.stop_fields(args), max_cycles=args.max_cycles, threads=args.threads,
                               ordering=args.ordering)
    report = _report(args, problem, result, "sphere")
    if path is not None:
        cli_path.report(args, path, report, zone=lambda r, states: sphere.radius_of(r, states), radii=True)
    load = float(result.reaction[2])
    report["displacement"] = args.displacement
    report["hertz_radius"] = sphere.hertz_radius(load) if load > 0 else None
    report["hertz_p0"] = sphere.hertz_p0(load) if load > 0 else None
    report["central_pressure"] = sphere.central_pressure(result) if len(result.contact_nodes) else None
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..results.plots_3d import plot_radial_stress

        fig, ax = plt.subplots(figsize=(7, 4))
        hz = {"radius": report["hertz_radius"], "p0": report["hertz_p0"]} if load > 0 else None
        plot_radial_stress(result, ax=ax, hertz=hz)
        ax.set_title(f"Hertz sphere, {args.cell}, level {args.levels}, F = {args.friction}", fontsize=9)
        _save(fig, args.plot)
    label = f"sphere {args.cell}"
    code = _finish(args, report, result, label, path)
    if not args.quiet and report["hertz_radius"]:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(f"  load {load:.6g}, contact radius {report['contact_radius']:.4g} (Hertz {report['hertz_radius']:.4g}), "
              f"central pressure {report['central_pressure']:.4g} (Hertz p0 {report['hertz_p0']:.4g})", file=stream)
    return code


def cork_report(args, problem, result) -> dict:
    """The keys of `contactmg hertz` for the cork, whose zones are bands around its side: the
    half-widths (largest |x| of a zone node: the cork's radius, whatever the zone) are null, and
    cork.zone_measures gives what the zones measure (contact_area, stick_area, slip_area,
    contact_length, stick_length, contact_z_range, stick_z_range)."""
    from ..examples import cork

    out = cli.hertz_report(args, problem, result)
    for k in ("hertz_halfwidth", "hertz_peak_pressure"):
        out.pop(k, None)
    out["problem"] = "cork"
    out["contact_halfwidth"] = out["stick_halfwidth"] = None
    out.update(cork.zone_measures(result))
    return out


def run_cork(args) -> int:
    """The cork command: solve the cork pushed into a bottle neck and report; returns the exit status."""
    from ..examples import cork

    args.cell = "hexahedron"
    from . import path as cli_path
    from ..mesh.generators_3d import CORK_TOP

    args.shear = None  # the cork's second phase is the pull-back
    if args.shear_steps is not None and not args.pull_back:
        raise ValueError("--pull-back-steps needs --pull-back")
    cli_path.check(args)
    problem = cork.cork_problem(args.levels, args.friction, args.push, coulomb_at_zero=args.method == "fixed-point",
                                cycle=args.cycle, nu1=args.nu1, nu2=args.nu2)
    cli.use_ordering(problem, args)
    cli.release_after_build(problem, args)
    path = None
    if cli_path.wanted(args):
        path = cli_path.solve(args, problem, [CORK_TOP], (0.0, 0.0, -args.push), (0.0, 0.0, args.push),
                              position=lambda r: r.mesh.points[r.contact_nodes, 2], label="z")
        result = path.last
    else:
        result = problem.solve(args.method, **cli.stop_fields(args), max_cycles=args.max_cycles, threads=args.threads,
                               ordering=args.ordering)
    report = cork_report(args, problem, result)
    if path is not None:
        # the contract's zone keys stay, null: the zones are bands around the side (zone_measures)
        cli_path.report(args, path, report, zone=lambda r, states: None)
        for row, r in zip(report["steps"], path.steps):
            row["push_force"] = cork.push_force(problem, r)
            row.update(cork.zone_measures(r))
    report["push"] = args.push
    report["push_force"] = cork.push_force(problem, result)
    report["material"] = {"E": problem.material.E, "nu": problem.material.nu}
    if args.picture:
        write_cork_picture(problem, result, args, args.picture)
    code = _finish(args, report, result, "cork", path)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        print(f"  push force {report['push_force']:.6g} N for D = {args.push} mm", file=stream)
    return code


def cork_figure(problem, result, friction: float, push: float):
    """The cork's picture (a matplotlib Figure, not attached to pyplot): the deformed cork in 3D
    coloured by contact state (left) and its side against the neck's tapered wall in a meridian
    section coloured by contact pressure (right; lengths in mm, stresses in MPa, the cork's units).
    Returns (figure, 3D axes, section axes)."""
    from matplotlib.figure import Figure

    from ..examples import cork
    from ..results.plots_3d import plot_cork, plot_cork_section

    fig = Figure(figsize=(13, 7.5), layout="constrained")
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    neck = cork.neck()
    plot_cork(problem, result, ax=ax3, neck=neck)
    plot_cork_section(result, neck, ax=ax2, radius=cork.RADIUS)
    fig.suptitle(f"cork pushed {push:g} mm into the neck, F = {friction:g}", fontsize=12)
    return fig, ax3, ax2


def write_cork_picture(problem, result, args, path) -> None:
    """`cork --picture PATH`: cork_figure written to PATH."""
    fig, _, _ = cork_figure(problem, result, args.friction, args.push)
    fig.savefig(path, dpi=120)


COMMANDS = {"sphere": run_sphere, "cork": run_cork}
