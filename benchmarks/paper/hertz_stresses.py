"""The Hertz benchmark's contact stresses and discretization error, level by level, on the uniform
and the adaptive hierarchy: the contact half-width, the peak pressure and the pressure profile
(largest deviation over the contact nodes, relative to p0) against Hertz's formulas for the
computed load, and the energy-norm error against a finer level of the same hierarchy (the level's
solution interpolated up the hierarchy), with its rate in dofs.

    python benchmarks/paper/hertz_stresses.py [--hierarchies uniform adaptive] [--levels 3 7]
        [--adaptive-levels 3 11] [--reference 9] [--adaptive-reference 13] [--friction 0]
        [--quick] [--json PATH]
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg.examples import hertz  # noqa: E402


def energy(problem, v):
    """||v||_A of a displacement v on the problem's finest level."""
    return float(np.sqrt(max(float(np.sum(v * problem.A.matvec(v))), 0.0)))


def levels_of(kind, levels, reference, friction, cell):
    """Rows of one hierarchy: per level the solve, the stresses against Hertz and the energy error."""
    if kind == "adaptive":
        h = hertz.hertz_adaptive_hierarchy(reference, friction if friction > 0 else hertz.ADAPTIVE_FRICTION)
        problem = lambda L: hertz.hertz_problem(levels=L, friction=friction, hierarchy=h.truncated(L))  # noqa: E731
    else:
        problem = lambda L: hertz.hertz_problem(cell, L, friction)  # noqa: E731
    ref_p = problem(reference)
    ref = ref_p.solve()
    transfers = ref_p.hierarchy.transfers
    norm = energy(ref_p, ref.displacement)
    rows = []
    for L in range(levels[0], levels[1] + 1):
        p = problem(L)
        r = p.solve()
        u = r.displacement
        for T in transfers[L - 1:]:
            u = T.matrix() @ u
        load = float(r.reaction[1])
        x = p.mesh.points[r.contact_nodes, 0]
        p0 = hertz.peak_pressure(load)
        profile = float(np.max(np.abs(-np.asarray(r.normal_stress) - hertz.pressure(x, load)))) / p0
        rows.append({"hierarchy": kind, "level": L, "dofs": 2 * p.mesh.num_points, "cycles": int(r.cycles),
                     "converged": bool(r.converged), "seconds": r.setup_seconds + r.solve_seconds,
                     "energy_error": energy(ref_p, u - ref.displacement) / norm,
                     "halfwidth": r.contact_halfwidth, "hertz_halfwidth": hertz.halfwidth(load),
                     "peak_pressure": float(-np.min(r.normal_stress)), "hertz_peak_pressure": p0,
                     "pressure_profile_error": profile})
        w = rows[-1]
        print(f"{kind:>8} {L:3d} {w['dofs']:9,} {w['cycles']:6d} {w['energy_error']:10.3e} {w['halfwidth']:8.5f} "
              f"{w['hertz_halfwidth']:8.5f} {w['peak_pressure']:8.2f} {p0:8.2f} {profile:8.3f}", flush=True)
    d = np.log([w["dofs"] for w in rows])
    e = np.log([w["energy_error"] for w in rows])
    slope = float(np.polyfit(d[-3:], e[-3:], 1)[0]) if len(rows) >= 2 else None
    print(f"{kind}: energy error ~ dofs^{slope:.2f} (last levels); reference level {reference}, "
          f"{2 * ref_p.mesh.num_points:,} dofs")
    return {"rows": rows, "slope_vs_dofs": slope, "reference_level": reference,
            "reference_dofs": 2 * ref_p.mesh.num_points}


def main():
    ap = parser(__doc__)
    ap.add_argument("--hierarchies", nargs="+", choices=["uniform", "adaptive"], default=["uniform", "adaptive"])
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 7], help="uniform levels (first last)")
    ap.add_argument("--reference", type=int, default=9, help="uniform reference level")
    ap.add_argument("--adaptive-levels", type=int, nargs=2, default=[3, 11])
    ap.add_argument("--adaptive-reference", type=int, default=13)
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"])
    ap.add_argument("--friction", type=float, default=0.0)
    a = ap.parse_args()
    if a.quick:
        a.levels, a.reference, a.adaptive_levels, a.adaptive_reference = [2, 4], 5, [3, 5], 7
    print(f"{'hier':>8} {'lvl':>3} {'dofs':>9} {'cycles':>6} {'energy err':>10} {'a':>8} {'a Hertz':>8} "
          f"{'p0':>8} {'p0 Hertz':>8} {'p(x) err':>8}")
    out = {"friction": a.friction}
    for kind in a.hierarchies:
        lv, ref = (a.levels, a.reference) if kind == "uniform" else (a.adaptive_levels, a.adaptive_reference)
        out[kind] = levels_of(kind, lv, ref, a.friction, a.cell)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
