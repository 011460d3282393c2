"""The cycle's options that the package keeps, each switched against the default on the cases it
was made for: Algorithm 2's cycles (converged results checked against the discrete contact
conditions), milliseconds per cycle and the largest difference of the solution from the default's.

Variants (solve keywords; the default resolves each None from the problem):
  default           the problem's defaults
  no_petrov_galerkin   petrov_galerkin=False: no Petrov-Galerkin coupling of the sliding nodes
  no_upwind         upwind_contact_sweep=False: the contact nodes in the plain sweep order
  omega_1.3         omega = omega_post = 1.3: no separate over-relaxation after the coarse correction
  projected_on/off  projected_coarse_correction=True / False (default: on where a frame is rotated)
  V(3,3)            cycle="V" instead of the F-cycle

Cases: the adaptive Hertz hierarchy over levels (where the coupling, the upwind sweep and the post
omega are on by default), uniform Hertz triangles, the adaptive tetrahedral sphere and the cork
(rotated contact frames). tol 1e-11 from u = 0, one thread: the cycle counts do not depend on the
machine's load, the milliseconds do.

    python benchmarks/methods/cycle_options.py [--cases adaptive uniform sphere cork]
        [--levels 3 5 7 9 11] [--frictions 0.4 2 5 40] [--variants ...] [--quick] [--json PATH]
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg.results.checks import VIOLATION_TOL, contact_conditions  # noqa: E402
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem, hertz_problem_on  # noqa: E402

VARIANTS = {
    "default": {},
    "no_petrov_galerkin": dict(petrov_galerkin=False),
    "no_upwind": dict(upwind_contact_sweep=False),
    "omega_1.3": dict(omega=1.3, omega_post=1.3),
    "projected_on": dict(projected_coarse_correction=True),
    "projected_off": dict(projected_coarse_correction=False),
    "V(3,3)": dict(cycle="V"),
}


def cases(which, levels, frictions, uniform_levels, sphere_level, cork_level):
    """(case name, F, problem factory) for the selected case families."""
    if "adaptive" in which:
        h = hertz_adaptive_hierarchy(max(levels), 0.4)
        for F in frictions:
            for L in levels:
                yield f"hertz adaptive L{L}", F, lambda L=L, F=F: hertz_problem_on(h.truncated(L), F)
    if "uniform" in which:
        for F in frictions:
            for L in uniform_levels:
                yield f"hertz uniform L{L}", F, lambda L=L, F=F: hertz_problem("triangle", L, F)
    if "sphere" in which:
        from contactmg.examples.sphere import sphere_adaptive_hierarchy, sphere_problem_on
        hs = sphere_adaptive_hierarchy(sphere_level, 0.4)
        for F in (0.4, 1.0):
            yield f"sphere tetra adaptive L{sphere_level}", F, lambda F=F: sphere_problem_on(hs, F)
    if "cork" in which:
        from contactmg.examples.cork import cork_problem
        for F in (0.0, 0.4):
            yield f"cork L{cork_level}", F, lambda F=F: cork_problem(cork_level, F)


def main():
    ap = parser(__doc__)
    ap.add_argument("--cases", nargs="+", default=["adaptive", "uniform", "sphere", "cork"],
                    choices=["adaptive", "uniform", "sphere", "cork"])
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11], help="adaptive Hertz levels")
    ap.add_argument("--uniform-levels", type=int, nargs="+", default=[5, 7])
    ap.add_argument("--sphere-level", type=int, default=3)
    ap.add_argument("--cork-level", type=int, default=3)
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.4, 2.0, 5.0, 40.0])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--max-cycles", type=int, default=200)
    a = ap.parse_args()
    if a.quick:
        a.levels, a.uniform_levels, a.sphere_level, a.cork_level, a.frictions = [3, 5], [3], 2, 1, [0.4, 5.0]
    rows = []
    print(f"{'case':28} {'F':>5} " + " ".join(f"{v:>18}" for v in a.variants) + "   (cycles, ms/cycle; ! failed)")
    for name, F, make in cases(a.cases, a.levels, a.frictions, a.uniform_levels, a.sphere_level, a.cork_level):
        p = make()
        row, ref, cells = {"case": name, "F": F, "dofs": int(p.load.size), "variants": {}}, None, []
        for v in a.variants:
            r = p.solve("nmg", tol=1e-11, max_cycles=a.max_cycles, threads=1, **VARIANTS[v])
            u = np.asarray(r.displacement)
            ref = u if ref is None else ref
            viol = float(contact_conditions(p, r)["max"])
            ok = bool(r.converged and viol <= VIOLATION_TOL)
            row["variants"][v] = {"cycles": int(r.cycles), "converged": bool(r.converged), "verified": ok,
                                  "violation": viol, "ms_per_cycle": 1e3 * r.solve_seconds / max(r.cycles, 1),
                                  "difference": float(np.abs(u - ref).max() / max(np.abs(ref).max(), 1e-300))}
            cells.append(f"{r.cycles:>5}{'' if ok else '!'} {row['variants'][v]['ms_per_cycle']:8.2f}ms")
        rows.append(row)
        print(f"{name:28} {F:5g} " + " ".join(f"{c:>18}" for c in cells), flush=True)
    write_result(__file__, a, {"variants": {v: VARIANTS[v] for v in a.variants}, "rows": rows})


if __name__ == "__main__":
    main()
