"""Two elastic bodies pressed together through the dual mortar, over levels, for equal and unequal
materials (E2 = 2 E1, nu2 = 0.2):

cylinders  two half disks (2D, non-matching meshes, `contactmg cylinders`): per level and F, the
           cycles of Algorithm 2 with the tied coarse correction (the default) and without it, of
           TNNMG, and of the linear solve with the final contact state known; at F = 0 the contact
           half-width and peak pressure against the two-body Hertz formulas (the last contact node
           and the largest nodal multiplier, and the ellipse fitted to all contact nodes).
spheres    two hemispheres (3D, `contactmg spheres`), one level per fresh process: nonmortar nodes,
           Algorithm 2 cycles and asymptotic contraction per F, the linear solve's cycles (F = 0.4),
           the independent check's largest violation, setup and solve seconds (one thread), peak
           memory, and the frictionless solve against the two-body Hertz formulas (p0 and a).

    python benchmarks/three_d/two_bodies.py [--parts cylinders spheres] [--cylinder-levels 3 6]
        [--sphere-levels 2 3] [--frictions 0 0.4 2] [--quick] [--json PATH]
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, run_child, write_result  # noqa: E402

from contactmg.examples.cylinders import RADIUS, cylinders_problem, two_body_halfwidth, two_body_peak_pressure  # noqa: E402
from contactmg.results.hertz_fit import elliptic_fit  # noqa: E402

MATERIALS = {"equal": (2000.0, 0.28), "unequal": (4000.0, 0.2)}


def cylinders(levels, frictions):
    """Rows per (materials, F, level) of the 2D cylinders."""
    rows = []
    print(f"{'materials':>9} {'F':>4} {'lvl':>3} {'dofs':>8} {'nmg':>4} {'untied':>6} {'tnnmg':>5} {'lin':>4} "
          f"{'a err':>7} {'a fit':>7} {'p0 err':>7} {'p0 fit':>7}")
    for name, (E2, nu2) in MATERIALS.items():
        for F in frictions:
            for L in range(levels[0], levels[1] + 1):
                row = {"materials": name, "E2": E2, "nu2": nu2, "F": F, "level": L}
                for key, method, tied in (("nmg", "nmg", True), ("nmg_untied", "nmg", False), ("tnnmg", "tnnmg", True)):
                    p = cylinders_problem(levels=L, friction=F, E2=E2, nu2=nu2, tied_correction=tied)
                    r = p.solve(method)
                    row[key] = r.cycles if r.converged else None
                    if key == "nmg":
                        row["dofs"] = 2 * p.mesh.num_points
                        row["nmg_seconds_per_cycle"] = r.solve_seconds / r.cycles
                        row["linear"] = p.solve("linear", reference=r).cycles
                        if F == 0.0:
                            P = float(r.reaction[1])
                            m1, m2 = p.bodies[0].material, p.bodies[1].material
                            a_h = two_body_halfwidth(P, RADIUS, RADIUS, m1, m2)
                            p0_h = two_body_peak_pressure(P, RADIUS, RADIUS, m1, m2)
                            x = p.mesh.points[p.contact.nodes, 0]
                            lam, active = -np.asarray(r.normal_stress), np.asarray(r.contact_state) > 0
                            a_fit, p0_fit, _ = elliptic_fit(x[active], lam[active])
                            row.update(halfwidth_error=np.abs(x[active]).max() / a_h - 1, halfwidth_fit_error=a_fit / a_h - 1,
                                       p0_error=lam.max() / p0_h - 1, p0_fit_error=p0_fit / p0_h - 1)
                rows.append(row)
                acc = (" ".join(f"{100 * row[k]:6.1f}%" for k in ("halfwidth_error", "halfwidth_fit_error", "p0_error",
                                                                   "p0_fit_error")) if F == 0.0 else "")
                print(f"{name:>9} {F:4g} {L:3d} {row['dofs']:8d} {str(row['nmg']):>4} {str(row['nmg_untied']):>6} "
                      f"{str(row['tnnmg']):>5} {row['linear']:4d} {acc}", flush=True)
    return rows


SPHERES_CHILD = r"""
import json, resource, sys, time
import numpy as np
from contactmg.examples import spheres
from contactmg.examples.sphere import central_pressure, radius_of
from contactmg.results.result import STICK, SLIP
L, E2, nu2 = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
frictions = [float(f) for f in sys.argv[4].split(",")]
out = {"level": L, "E2": E2, "nu2": nu2, "cycles": {}, "rate": {}, "solve_seconds": {}, "converged": {}, "violation": {}}
for F in frictions:
    t0 = time.perf_counter()
    p = spheres.spheres_problem(levels=L, friction=F, E2=E2, nu2=nu2)
    p.solver.core
    out["setup_seconds"] = time.perf_counter() - t0
    res = p.solve(tol=1e-11, max_cycles=200, threads=1)
    out["nodes"], out["dofs"], out["nonmortar_nodes"] = p.mesh.num_points, 3 * p.mesh.num_points, len(p.contact.nodes)
    c = np.asarray(res.history["correction_norm"], float)
    c = c[c > 0]
    q = c[1:] / c[:-1]
    out["rate"][F] = float(np.exp(np.mean(np.log(q[-5:])))) if len(q) else None
    out["cycles"][F], out["solve_seconds"][F], out["converged"][F] = res.cycles, res.solve_seconds, res.converged
    out["violation"][F] = spheres.check_conditions(p, res)["max"]
    if F == 0.0:
        P = float(res.reaction[2])
        m1, m2 = p.bodies[0].material, p.bodies[1].material
        out["hertz_p0_error"] = central_pressure(res) / spheres.two_body_p0(P, spheres.RADIUS, spheres.RADIUS, m1, m2) - 1
        out["hertz_radius_error"] = radius_of(res, (STICK, SLIP)) / spheres.two_body_radius(P, spheres.RADIUS, spheres.RADIUS, m1, m2) - 1
    if F == 0.4:
        lin = p.solve("linear", tol=1e-11, reference=res, threads=1)
        out["linear_cycles"], out["linear_seconds"] = lin.cycles, lin.solve_seconds
    del p, res
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def spheres(levels, frictions):
    """Rows per (materials, level) of the 3D spheres, each level in a fresh process."""
    rows, fs = [], ",".join(str(f) for f in frictions)
    print(f"{'materials':>9} {'lvl':>3} {'dofs':>9} {'nm':>5} " + " ".join(f"{'F=' + format(f, 'g'):>6}" for f in frictions)
          + f" {'lin':>4} {'viol':>8} {'setup s':>7} {'solve s':>8} {'MB':>6}")
    for name, (E2, nu2) in MATERIALS.items():
        for L in range(levels[0], levels[1] + 1):
            r = run_child(SPHERES_CHILD, L, E2, nu2, fs)
            if "error" in r:
                print(f"{name:>9} {L:3d} failed: {r['error']}")
                continue
            r["materials"] = name
            rows.append(r)
            cyc = " ".join(f"{r['cycles'][str(f)] if r['converged'][str(f)] else 'x':>6}" for f in frictions)
            print(f"{name:>9} {L:3d} {r['dofs']:9,} {r['nonmortar_nodes']:5d} {cyc} {r.get('linear_cycles', '-'):>4} "
                  f"{max(r['violation'].values()):8.1e} {r['setup_seconds']:7.1f} {sum(r['solve_seconds'].values()):8.1f} "
                  f"{r['peak_rss_mb']:6.0f}", flush=True)
    return rows


def main():
    ap = parser(__doc__)
    ap.add_argument("--parts", nargs="+", choices=["cylinders", "spheres"], default=["cylinders", "spheres"])
    ap.add_argument("--cylinder-levels", type=int, nargs=2, default=[3, 6])
    ap.add_argument("--sphere-levels", type=int, nargs=2, default=[2, 3])
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.0, 0.4, 2.0])
    a = ap.parse_args()
    if a.quick:
        a.cylinder_levels, a.sphere_levels, a.frictions = [2, 3], [1, 1], [0.0, 0.4]
    out = {"frictions": a.frictions}
    if "cylinders" in a.parts:
        out["cylinders"] = cylinders(a.cylinder_levels, a.frictions)
    if "spheres" in a.parts:
        out["spheres"] = spheres(a.sphere_levels, a.frictions)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
