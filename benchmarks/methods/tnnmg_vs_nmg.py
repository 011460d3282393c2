"""Algorithm 2 ("nmg") and truncated nonsmooth Newton multigrid ("tnnmg") side by side: cycles,
linear cycles, solve seconds and agreement of the solutions, over the paper's friction coefficients
on uniform Hertz hierarchies (triangles and quadrilaterals) and on the hard scenes of
methods/robustness.py (nearly incompressible material, flat layers), for TNNMG's linear corrections:

    tnnmg         the default: PCG preconditioned by the truncated linear cycle with line smoothing
    tnnmg-cycle   one truncated linear cycle (line-smoothed) per step
    tnnmg-coarse  the coarse levels alone, point smoothing

    python benchmarks/methods/tnnmg_vs_nmg.py [--tri 3 7] [--quad 3 6] [--stress-level 7]
        [--methods nmg tnnmg ...] [--locking] [--quick] [--json PATH]

"cycles" are the steps of the method (a TNNMG step: nonlinear sweeps, the linear correction, the
line search, sweeps); "linear" counts the linear cycles the corrections applied (for nmg: one per
cycle). --locking adds the energy per level at nu = 0.28 and 0.49 (P1 and Q1): whether the
discretization locks as nu -> 1/2.
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402
from robustness import hertz_scene, layer  # noqa: E402

from contactmg.examples import hertz  # noqa: E402
from contactmg.results.checks import contact_conditions  # noqa: E402

METHODS = {"nmg": ("nmg", {}), "tnnmg": ("tnnmg", {}), "tnnmg-cycle": ("tnnmg", {"linear": "cycle"}),
           "tnnmg-coarse": ("tnnmg", {"linear": "coarse", "lines": False})}


def compare(name, problem, rows, max_cycles, methods):
    """Solves `problem` with every method and appends a row each, agreement measured against nmg."""
    res = {m: problem.solve(METHODS[m][0], max_cycles=max_cycles, **METHODS[m][1]) for m in methods}
    ref = res.get("nmg")
    for m, r in res.items():
        agree = (float(np.abs(ref.displacement - r.displacement).max() / max(np.abs(ref.displacement).max(), 1e-300))
                 if ref is not None and ref.converged and r.converged else float("nan"))
        lin = int(np.sum(r.history["linear_iterations"])) if r.method == "tnnmg" else r.cycles
        row = {"case": name, "method": m, "converged": r.converged, "status": r.status, "cycles": r.cycles,
               "linear_cycles": lin, "seconds": r.solve_seconds, "violation": contact_conditions(problem, r)["max"],
               "agreement": agree, "dofs": 2 * problem.mesh.num_points}
        rows.append(row)
        print(f"{name:26s} {m:12s} {('ok' if r.converged else r.status[:12]):>12s} {r.cycles:6d} {lin:6d} "
              f"{r.solve_seconds:8.2f} {row['violation']:9.1e} {agree:9.1e}", flush=True)


def locking(rows, tri, quad):
    """Whether the discretization locks as nu -> 1/2: the energy of the frictionless Hertz scene
    (displacement-driven: a stiffer discretization stores more) per level, P1 triangles and Q1 quads,
    nu = 0.28 and 0.49, and its relative change from the level below."""
    print(f"\n{'cell':8s} {'nu':>5s} {'level':>5s} {'dofs':>9s} {'energy':>12s} {'change':>8s}")
    for cell, (l0, l1) in (("triangle", tri), ("quad", quad)):
        for nu in (0.28, 0.49):
            last = None
            for L in range(l0, l1 + 1):
                p = hertz_scene(hertz.hertz_problem(cell, L, 0.0).hierarchy, F=0.0, nu=nu)
                r = p.solve("tnnmg", max_cycles=300)
                e = float(r.history["energy"][-1])
                change = float("nan") if last is None else (last - e) / abs(e)
                rows.append({"case": f"locking {cell} nu={nu} L{L}", "energy": e, "change": change,
                             "dofs": 2 * p.mesh.num_points, "converged": r.converged})
                print(f"{cell:8s} {nu:5.2f} {L:5d} {2 * p.mesh.num_points:9,d} {e:12.6e} {change:8.4f}", flush=True)
                last = e


def main():
    ap = parser(__doc__)
    ap.add_argument("--tri", type=int, nargs=2, default=(3, 7))
    ap.add_argument("--quad", type=int, nargs=2, default=(3, 6))
    ap.add_argument("--frictions", type=float, nargs="*", default=list(hertz.PAPER_FRICTIONS))
    ap.add_argument("--stress-level", type=int, default=7)
    ap.add_argument("--layer-level", type=int, default=5)
    ap.add_argument("--methods", nargs="*", default=list(METHODS), choices=list(METHODS))
    ap.add_argument("--max-cycles", type=int, default=300)
    ap.add_argument("--locking", action="store_true", help="also the energy per level at nu = 0.28 / 0.49, P1 and Q1")
    a = ap.parse_args()
    if a.quick:
        a.tri, a.quad, a.frictions, a.stress_level, a.layer_level = (2, 3), (2, 2), [0.4, 5.0], 3, 2
    rows = []
    print(f"{'case':26s} {'method':12s} {'status':>12s} {'cycles':>6s} {'linear':>6s} {'seconds':>8s} "
          f"{'violation':>9s} {'|du|/|u|':>9s}")
    for cell, (l0, l1) in (("triangle", a.tri), ("quad", a.quad)):
        for L in range(l0, l1 + 1):
            for F in a.frictions:
                compare(f"hertz {cell} L{L} F={F:g}", hertz.hertz_problem(cell, L, F), rows, a.max_cycles, a.methods)
    if a.stress_level > 0:
        s = a.stress_level
        h = hertz.hertz_problem("triangle", s, 0.4).hierarchy
        hq = hertz.hertz_problem("quad", s - 1, 0.4).hierarchy  # about as many dofs as triangles on level s
        for name, make in ((f"nu=0.45 tri L{s}", lambda: hertz_scene(h, nu=0.45)),
                           (f"nu=0.49 tri L{s}", lambda: hertz_scene(h, nu=0.49)),
                           (f"nu=0.45 quad L{s - 1}", lambda: hertz_scene(hq, nu=0.45)),
                           (f"nu=0.49 quad L{s - 1}", lambda: hertz_scene(hq, nu=0.49)),
                           (f"layer aspect 8 L{a.layer_level}", lambda: layer(8, a.layer_level)),
                           (f"layer aspect 32 L{a.layer_level}", lambda: layer(32, a.layer_level))):
            compare(name, make(), rows, a.max_cycles, a.methods)
    if a.locking:
        locking(rows, (4, a.stress_level), (3, a.stress_level - 1))
    write_result(__file__, a, rows)


if __name__ == "__main__":
    main()
