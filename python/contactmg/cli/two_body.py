"""The two-body commands: `contactmg cylinders` and `contactmg spheres`."""
from __future__ import annotations

import argparse
import sys

import numpy as np

from ..examples import cylinders, sphere, spheres
from ..results.hertz_fit import elliptic_fit, radial_elliptic_fit
from . import common as cli
from . import three_d as cli_3d


# -- cylinders ---------------------------------------------------------------------------------
def add_cylinders_parser(sub):
    """Add the cylinders command."""
    c = sub.add_parser("cylinders", help="two elastic half-disks in contact (dual mortar, non-matching meshes)")
    c.add_argument("--levels", type=cli._positive_int("--levels", 1, cli.MAX_LEVELS), default=5,
                   help="levels in all; level 1 is the coarse mesh")
    c.add_argument("--friction", type=cli._nonneg_float("--friction"), default=0.4,
                   help="Coulomb friction coefficient F (0: frictionless)")
    c.add_argument("--method", choices=["nmg", "fixed-point", "linear", "tnnmg"], default="nmg",
                   help="nmg: Algorithm 2 with the tied coarse correction of two bodies; tnnmg: truncated nonsmooth Newton multigrid")
    c.add_argument("--E2", type=cli._nonneg_float("--E2", positive=True), default=cylinders.E, help="Young's modulus of the lower body")
    c.add_argument("--nu2", type=float, default=cylinders.NU, help="Poisson's ratio of the lower body")
    cli.add_stop_options(c)
    cli.add_report_options(c)
    c.add_argument("--plot", type=cli._with_suffix("--plot", cli.PLOT_SUFFIXES), metavar="PATH",
                   help="write the boundary stresses with the stick and slip zones (.png, .pdf or .svg)")
    c.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def run_cylinders(args) -> int:
    """The cylinders command: solve two cylinders in contact and report; returns the exit status."""
    if not (-1.0 < args.nu2 < 0.5):
        raise ValueError(f"--nu2: Poisson's ratio must lie in (-1, 0.5), got {args.nu2}")
    problem = cylinders.cylinders_problem(args.levels, args.friction, args.E2, args.nu2,
                                coulomb_at_zero=args.method == "fixed-point", cycle=args.cycle)
    result = problem.solve(args.method, **cli.stop_fields(args), max_cycles=args.max_cycles)
    ns = argparse.Namespace(**vars(args))
    ns.cell, ns.nu1, ns.nu2 = "triangle", 3, 3  # cli.hertz_report's cycle_type: the smoothing steps
    report = cli.hertz_report(ns, problem, result)
    load = report["reaction"][1]
    m1, m2 = problem.bodies[0].material, problem.bodies[1].material
    report.update({
        "problem": "cylinders", "E2": args.E2, "nu2": args.nu2, "bodies": 2,
        "nonmortar_nodes": int(len(problem.contact.nodes)),
        "hertz_halfwidth": cylinders.two_body_halfwidth(load, cylinders.RADIUS, cylinders.RADIUS, m1, m2) if load > 0 else None,
        "hertz_p0": cylinders.two_body_peak_pressure(load, cylinders.RADIUS, cylinders.RADIUS, m1, m2) if load > 0 else None,
    })
    report["hertz_peak_pressure"] = report["hertz_p0"]
    # the Hertz ellipse fitted to every contact node (hertz_fit.py): the nodal maximum and the last
    # contact node converge slowly / by mesh sizes, the fit from the whole zone
    active = result.contact_state > 0
    a_fit, p0_fit, _ = elliptic_fit(problem.mesh.points[problem.contact.nodes[active], 0],
                                    np.abs(result.normal_stress[active]))
    report["fitted_halfwidth"] = a_fit if np.isfinite(a_fit) else None
    report["fitted_peak_pressure"] = p0_fit if np.isfinite(p0_fit) else None
    if args.json:
        cli._emit_json(args.json, report)
    if args.vtu:
        problem.write_vtu(args.vtu, result)
    if args.plot:
        cli.write_boundary_stress_plot(result, args.friction, args.plot)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        hw, p0 = report["hertz_halfwidth"], report["hertz_p0"]
        print(f"cylinders levels={args.levels} dofs={report['dofs']} F={args.friction} E2={args.E2} nu2={args.nu2} "
              f"method={args.method}: {result.status}, {result.cycles} cycles, setup {result.setup_seconds:.2f} s, "
              f"solve {result.solve_seconds:.2f} s, contact {report['contact_nodes']} (stick {report['stick_nodes']}, "
              f"slip {report['slip_nodes']}), reaction {load:.6g}, half-width {report['contact_halfwidth']:.4g}"
              + (f" (fitted {a_fit:.4g})" if np.isfinite(a_fit) else "") + (f" (Hertz {hw:.4g})" if hw else "")
              + f", max p {report['max_normal_stress']:.4g}" + (f" (fitted {p0_fit:.4g})" if np.isfinite(p0_fit) else "")
              + (f" (Hertz {p0:.4g})" if p0 else ""), file=stream)
    return cli.EXIT_OK if result.converged else cli.EXIT_NO_CONVERGENCE


# -- spheres -----------------------------------------------------------------------------------
def add_spheres_parser(sub):
    """Add the spheres command."""
    c = sub.add_parser("spheres", help="two elastic hemispheres in contact (3D dual mortar, non-matching meshes)")
    c.add_argument("--cell", choices=["tetra", "hexahedron"], default="hexahedron", help="tetrahedra or hexahedra")
    c.add_argument("--levels", type=cli._positive_int("--levels", 1, 7), default=spheres.DEFAULT_LEVELS,
                   help="levels in all; level 1 is the coarse mesh")
    c.add_argument("--friction", type=cli._nonneg_float("--friction"), default=0.4,
                   help="Coulomb friction coefficient F (0: frictionless)")
    c.add_argument("--method", choices=["nmg", "fixed-point", "linear", "tnnmg"], default="nmg",
                   help="nmg: Algorithm 2 (nonlinear multigrid); fixed-point: Algorithm 1; linear: the cost "
                        "reference; tnnmg: truncated nonsmooth Newton multigrid")
    c.add_argument("--E2", type=cli._nonneg_float("--E2", positive=True), default=spheres.E, help="Young's modulus of the lower body")
    c.add_argument("--nu2", type=float, default=spheres.NU, help="Poisson's ratio of the lower body")
    c.add_argument("--displacement", type=cli._nonneg_float("--displacement", positive=True), default=spheres.DISPLACEMENT,
                   help="displacement of each flat face towards the other")
    cli.add_stop_options(c)
    cli.add_thread_options(c)
    cli.add_report_options(c)
    c.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def run_spheres(args) -> int:
    """The spheres command: solve two half balls in contact and report; returns the exit status."""
    if not (-1.0 < args.nu2 < 0.5):
        raise ValueError(f"--nu2: Poisson's ratio must lie in (-1, 0.5), got {args.nu2}")
    problem = spheres.spheres_problem(args.cell, args.levels, args.friction, args.E2, args.nu2, args.displacement,
                              coulomb_at_zero=args.method == "fixed-point", cycle=args.cycle)
    result = problem.solve(args.method, **cli.stop_fields(args), max_cycles=args.max_cycles, threads=args.threads,
                           ordering=args.ordering)
    ns = argparse.Namespace(**vars(args))
    ns.nu1, ns.nu2 = 3, 3  # hertz_report's cycle_type: the smoothing steps
    report = cli_3d._report(ns, problem, result, "spheres")
    load = float(result.reaction[2])
    m1, m2 = problem.bodies[0].material, problem.bodies[1].material
    report.update({
        "E2": args.E2, "nu2": args.nu2, "bodies": 2, "nonmortar_nodes": int(len(problem.contact.nodes)),
        "displacement": args.displacement,
        "hertz_radius": spheres.two_body_radius(load, spheres.RADIUS, spheres.RADIUS, m1, m2) if load > 0 else None,
        "hertz_p0": spheres.two_body_p0(load, spheres.RADIUS, spheres.RADIUS, m1, m2) if load > 0 else None,
        "central_pressure": sphere.central_pressure(result) if len(result.contact_nodes) else None,
        "check_violation": spheres.check_conditions(problem, result)["max"],
    })
    # the Hertz profile fitted to every contact node (hertz_fit.py): the central nodal multiplier
    # converges slowly, the fit takes the whole zone
    active = result.contact_state > 0
    xy = problem.mesh.points[problem.contact.nodes[active], :2]
    a_fit, p0_fit = radial_elliptic_fit(np.hypot(xy[:, 0], xy[:, 1]), np.abs(result.normal_stress[active]))
    report["fitted_radius"] = a_fit if np.isfinite(a_fit) else None
    report["fitted_peak_pressure"] = p0_fit if np.isfinite(p0_fit) else None
    if args.json:
        cli._emit_json(args.json, report)
    if args.vtu:
        problem.write_vtu(args.vtu, result)
    if not args.quiet:
        stream = sys.stderr if args.json == "-" else sys.stdout
        a, p0 = report["hertz_radius"], report["hertz_p0"]
        print(f"spheres {args.cell} levels={args.levels} dofs={report['dofs']} F={args.friction} E2={args.E2} "
              f"nu2={args.nu2} method={args.method}: {result.status}, {result.cycles} cycles, setup "
              f"{result.setup_seconds:.2f} s, solve {result.solve_seconds:.2f} s, contact {report['contact_nodes']} "
              f"(stick {report['stick_nodes']}, slip {report['slip_nodes']}), load {load:.6g}, contact radius "
              f"{report['contact_radius']:.4g}" + (f" (Hertz {a:.4g})" if a else "")
              + (f", central pressure {report['central_pressure']:.4g}" if report["central_pressure"] is not None else "")
              + (f" (Hertz p0 {p0:.4g})" if p0 else ""), file=stream)
    return cli.EXIT_OK if result.converged else cli.EXIT_NO_CONVERGENCE
