"""Two elastic half-disks pressed together (the two-body Hertz problem) and `contactmg cylinders`.

The upper body is the Hertz half-disk of the seed paper (centre (0, 0.4), radius 0.4, its arc
below, the nonmortar side); the lower one is its mirror image below y = 0 (centre (0, -0.4)),
meshed differently (5 k instead of 4 k arc segments on ring k) so the interface does not match,
the mortar side. Their flat faces are moved towards each other by 0.005 each."""
from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from .friction import Coulomb, Frictionless
from .generators import HERTZ_ARC, HERTZ_TOP, hertz_projector, polar_half_disk
from .hertz_fit import elliptic_fit
from .hierarchy import MeshHierarchy
from .material import Material
from .mesh import Mesh
from .problem import Dirichlet
# two_body (scipy.sparse, the mortar modules) is imported where a problem is built: the command line
# builds this module's parser for every command, and scipy cost a `contactmg hertz` process 32 MiB (issue 15)

E, NU, RADIUS = 2000.0, 0.28, 0.4
FACE_DISPLACEMENT = 0.005
# the possible contact zone: the nonmortar arc within |x| < ZONE (the Hertz half-width is ~0.03)
ZONE = 0.5 * RADIUS
SEARCH = RADIUS


def lower_half_disk(segments: int = 5) -> Mesh:
    """The mirror image of the polar Hertz half-disk below y = 0: centre (0, -0.4), arc on top."""
    m = polar_half_disk((0.0, 0.4), RADIUS, rings=3, segments=segments)
    pts = m.points * [1.0, -1.0]
    cy = -0.4

    def tagger(mid):
        return np.where(np.abs(mid[:, 1] - cy) < 1e-12 * RADIUS, HERTZ_TOP, HERTZ_ARC)

    return Mesh.from_cells(pts, m.cells[:, ::-1].copy(), "triangle", tagger)


def cylinders_problem(levels: int = 5, friction: float = 0.4, E2: float = E, nu2: float = NU, coulomb_at_zero=False,
                      cycle: str = "F", smooth: int = 3, upper_segments: int = 4, lower_segments: int = 5,
                      tied_correction: bool = True) -> TwoBodyProblem:
    if isinstance(friction, bool) or not isinstance(friction, (int, float)) or not math.isfinite(friction) or friction < 0:
        raise ValueError(f"the friction coefficient must be a finite number >= 0, got {friction!r}")
    from .two_body import Body, ContactPair, TwoBodyProblem

    upper = MeshHierarchy.build(polar_half_disk((0.0, 0.4), RADIUS, rings=3, segments=upper_segments), levels,
                                projector=hertz_projector((0.0, 0.4), RADIUS))
    lower = MeshHierarchy.build(lower_half_disk(lower_segments), levels, projector=hertz_projector((0.0, -0.4), RADIUS))
    bodies = [Body(upper, Material(E, NU), [Dirichlet([HERTZ_TOP], (0.0, -FACE_DISPLACEMENT))]),
              Body(lower, Material(E2, nu2), [Dirichlet([HERTZ_TOP], (0.0, FACE_DISPLACEMENT))])]
    pair = ContactPair(0, 1, [HERTZ_ARC], [HERTZ_ARC], search=SEARCH, region=lambda mid: np.abs(mid[:, 0]) < ZONE)
    law = Coulomb(friction) if (friction > 0 or coulomb_at_zero) else Frictionless()
    p = TwoBodyProblem(bodies, pair, law, cycle=cycle, nu1=smooth, nu2=smooth, tied_correction=tied_correction)
    p.benchmark = "hertz"  # zones centred on x = 0
    return p


def effective_modulus(m1: Material, m2: Material) -> float:
    """E* with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (plane strain)."""
    return 1.0 / ((1 - m1.nu ** 2) / m1.E + (1 - m2.nu ** 2) / m2.E)


def two_body_halfwidth(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """a = sqrt(4 P R* / (pi E*)), 1/R* = 1/R1 + 1/R2."""
    Rs = 1.0 / (1.0 / R1 + 1.0 / R2)
    return math.sqrt(4 * load * Rs / (math.pi * effective_modulus(m1, m2)))


def two_body_peak_pressure(load: float, R1: float, R2: float, m1: Material, m2: Material) -> float:
    """p0 = 2 P / (pi a)."""
    return 2 * load / (math.pi * two_body_halfwidth(load, R1, R2, m1, m2))


# -- the command ---------------------------------------------------------------------------------
def add_parser(sub):
    from .cli import MAX_CYCLES as max_cycles, MAX_LEVELS as max_levels, PLOT_SUFFIXES as plot_suffixes
    from .cli import _nonneg_float as nonneg_float, _positive_int as positive_int
    from .cli import _with_suffix as with_suffix, _writable as writable

    c = sub.add_parser("cylinders", help="two elastic half-disks in contact (dual mortar, non-matching meshes)")
    c.add_argument("--levels", type=positive_int("--levels", 1, max_levels), default=5,
                   help="levels in all; level 1 is the coarse mesh")
    c.add_argument("--friction", type=nonneg_float("--friction"), default=0.4,
                   help="Coulomb friction coefficient F (0: frictionless)")
    c.add_argument("--method", choices=["nmg", "fixed-point", "linear", "tnnmg"], default="nmg",
                   help="nmg: Algorithm 2 with the tied coarse correction of two bodies; tnnmg: truncated nonsmooth Newton multigrid")
    c.add_argument("--E2", type=nonneg_float("--E2", positive=True), default=E, help="Young's modulus of the lower body")
    c.add_argument("--nu2", type=float, default=NU, help="Poisson's ratio of the lower body")
    c.add_argument("--tol", type=nonneg_float("--tol", positive=True), default=1e-11,
                   help="stop when the correction's energy norm ||u^{k+1} - u^k||_A falls below this")
    c.add_argument("--max-cycles", type=positive_int("--max-cycles", 1, max_cycles), default=200,
                   help="stop as not converged after this many cycles")
    c.add_argument("--cycle", choices=["V", "W", "F"], default="F", help="multigrid cycle type")
    c.add_argument("--json", type=writable, metavar="PATH|-",
                   help="write the report as JSON to PATH (-: standard output)")
    c.add_argument("--vtu", type=with_suffix("--vtu", (".vtu",)), metavar="PATH",
                   help="write the mesh with displacement, stresses and contact states (ParaView)")
    c.add_argument("--plot", type=with_suffix("--plot", plot_suffixes), metavar="PATH",
                   help="write the boundary stresses with the stick and slip zones (.png, .pdf or .svg)")
    c.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def run_cylinders(args) -> int:
    from .cli import EXIT_NO_CONVERGENCE, EXIT_OK, _emit_json, hertz_report, write_boundary_stress_plot

    if not (-1.0 < args.nu2 < 0.5):
        raise ValueError(f"--nu2: Poisson's ratio must lie in (-1, 0.5), got {args.nu2}")
    problem = cylinders_problem(args.levels, args.friction, args.E2, args.nu2,
                                coulomb_at_zero=args.method == "fixed-point", cycle=args.cycle)
    result = problem.solve(args.method, tol=args.tol, max_cycles=args.max_cycles)
    ns = argparse.Namespace(**vars(args))
    ns.cell, ns.nu1, ns.nu2 = "triangle", 3, 3  # hertz_report's cycle_type: the smoothing steps
    report = hertz_report(ns, problem, result)
    load = report["reaction"][1]
    m1, m2 = problem.bodies[0].material, problem.bodies[1].material
    report.update({
        "problem": "cylinders", "E2": args.E2, "nu2": args.nu2, "bodies": 2,
        "nonmortar_nodes": int(len(problem.contact.nodes)),
        "hertz_halfwidth": two_body_halfwidth(load, RADIUS, RADIUS, m1, m2) if load > 0 else None,
        "hertz_p0": two_body_peak_pressure(load, RADIUS, RADIUS, m1, m2) if load > 0 else None,
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
        _emit_json(args.json, report)
    if args.vtu:
        problem.write_vtu(args.vtu, result)
    if args.plot:
        write_boundary_stress_plot(result, args.friction, args.plot)
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
    return EXIT_OK if result.converged else EXIT_NO_CONVERGENCE
