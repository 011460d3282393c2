"""Algorithm 2 on the adaptive Hertz levels with and without the sliding nodes' Petrov-Galerkin
coupling, with the post-smoothing's own omega (issue 11, tenth part) and with the upwind contact
sweep (eleventh part; README "Adaptive hierarchies"): cycles per level and the spread over the
levels, for each variant.

    python benchmarks/petrov_galerkin_variants.py [--levels 3 5 7 9 11] [--frictions 0.08 0.4 ...]
        [--variants off every default split] [--json benchmarks/results/petrov_galerkin_variants.json]

off      no coupling, omega 1.3 before and after the coarse correction (stop 24's default)
every    the coupling in every cycle but the first, omega 1.3 / 1.3
stop25   the coupling, omega 1.3 / 1.5, no upwind contact sweep (stop 25's default)
default  the problem's defaults on a 2D adaptive hierarchy: the coupling, omega 1.3 / 1.5, the
         upwind contact sweep
split    the coupling, omega 1 / 1.7
(off, every and split: without the upwind contact sweep, as they were measured at stop 25)
The hierarchy is hertz_adaptive_hierarchy(11) (cached in out/cache/ by cycle_growth.py); tol 1e-11
from u = 0, F(3,3); every converged result is checked by contactmg.checks.contact_conditions.
Cycle counts do not depend on the machine's load.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))

from bench_json import write_json  # noqa: E402
from cycle_growth import adaptive_hierarchy  # noqa: E402
from contactmg.checks import contact_conditions  # noqa: E402
from contactmg.hertz import hertz_problem_on  # noqa: E402

VARIANTS = {
    "off": dict(petrov_galerkin=False, omega=1.3, omega_post=1.3, upwind_contact_sweep=False),
    "every": dict(petrov_galerkin=True, omega=1.3, omega_post=1.3, upwind_contact_sweep=False),
    "stop25": dict(upwind_contact_sweep=False),
    "default": {},
    "split": dict(petrov_galerkin=True, omega=1.0, omega_post=1.7, upwind_contact_sweep=False),
}
PAPER_FRICTIONS = [0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=PAPER_FRICTIONS)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--max-cycles", type=int, default=200)
    ap.add_argument("--json")
    a = ap.parse_args()
    full = adaptive_hierarchy(max(a.levels))
    rows = []
    print("cycles per level (! not converged) and spread, levels " + " ".join(map(str, a.levels)))
    for name in a.variants:
        for F in a.frictions:
            line, counts = [], []
            for L in a.levels:
                p = hertz_problem_on(full.truncated(L), F)
                r = p.solve("nmg", tol=1e-11, max_cycles=a.max_cycles, threads=1, **VARIANTS[name])
                viol = float(contact_conditions(p, r)["max"]) if r.converged else None
                rows.append({"variant": name, "F": F, "level": L, "dofs": 2 * p.mesh.num_points, "cycles": r.cycles,
                             "converged": bool(r.converged), "violation": viol,
                             "coupled_cycles": (r.extra.get("petrov_galerkin") or {}).get("cycles")})
                line.append(f"{r.cycles}{'' if r.converged else '!'}")
                counts.append(r.cycles)
            print(f"  {name:8} F={F:<5g} " + " / ".join(line) + f"   spread {max(counts) - min(counts)}", flush=True)
    write_json(a.json, rows)


if __name__ == "__main__":
    main()
