"""Algorithm 2 with and without the sliding nodes' Petrov-Galerkin coupling on level L-1 in settled
cycles (solve(petrov_galerkin=True); issue 11, seventh part; docs/history/adaptive.md).

    python benchmarks/settled_petrov_galerkin.py [--levels 3 5 7 9 11] [--frictions 0.4 2 5 8]
        [--modes off on] [--hierarchy adaptive|uniform] [--json benchmarks/results/....json]

Each run: adaptive (or uniform) Hertz triangles, F(3,3), tol 1e-11, from u = 0, one thread, one
process (runs one after another). Per run: cycles = settling + settled (settling: up to the last
rebuild of the coarse problem, i.e. the truncation's last change; settled rate: geometric mean of
the settled correction ratios, as benchmarks/friction_growth_diagnosis.py), the cycles that carried
the coupling, the cycle where the fallback switched it off, the independent check's violation
(contactmg.checks.contact_conditions; '!' = not converged or violation > 1e-8) and, for "on", the
largest difference of the displacement from the "off" run's relative to its largest entry.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from friction_growth_diagnosis import split_history  # noqa: E402


def run(H, L, F, pg, max_cycles=200):
    from contactmg.checks import contact_conditions
    from contactmg.hertz import hertz_problem

    p = hertz_problem("triangle", L, F, coulomb_at_zero=True, hierarchy="uniform" if H is None else H.truncated(L))
    t = time.perf_counter()
    r = p.solve("nmg", tol=1e-11, max_cycles=max_cycles, threads=1, petrov_galerkin=pg)
    sec = time.perf_counter() - t
    viol = float(contact_conditions(p, r)["max"])
    n, last, settled, rate, ratios = split_history(r.history)
    pgh = np.asarray(r.history["petrov_galerkin"])
    off = np.nonzero(pgh == 2)[0]
    return {"level": L, "F": F, "petrov_galerkin": pg, "dofs": 2 * p.mesh.num_points, "cycles": int(r.cycles),
            "converged": bool(r.converged), "ok": bool(r.converged) and viol <= 1e-8, "status": r.status,
            "violation": viol, "seconds": sec, "settling": last, "settled": settled, "settled_rate": rate,
            "pg_cycles": int(np.count_nonzero(pgh)), "fallback_cycle": int(off[0]) + 1 if len(off) else None,
            "slip": int(r.history["slip"][-1]),
            "history": {"correction_norm": [float(x) for x in r.history["correction_norm"]],
                        "rebuilt": [bool(x) for x in r.history["rebuilt"]], "petrov_galerkin": [int(x) for x in pgh],
                        "slip": [int(x) for x in r.history["slip"]]}}, np.asarray(r.displacement)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.4, 2.0, 5.0, 8.0])
    ap.add_argument("--modes", nargs="+", choices=["off", "on"], default=["off", "on"])
    ap.add_argument("--hierarchy", choices=["adaptive", "uniform"], default="adaptive")
    ap.add_argument("--max-cycles", type=int, default=200)
    ap.add_argument("--json")
    a = ap.parse_args()
    H = None
    if a.hierarchy == "adaptive":
        from cycle_growth import adaptive_hierarchy
        H = adaptive_hierarchy(max(11, max(a.levels)))
    rows = []
    print("| L | F | mode | cycles = settling + settled (rate) | PG cycles | fallback | violation | |u - u_off| | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for L in a.levels:
        for F in a.frictions:
            u_off = None
            for mode in a.modes:
                r, u = run(H, L, F, mode == "on", a.max_cycles)
                if mode == "off":
                    u_off = u
                diff = float(np.abs(u - u_off).max() / np.abs(u_off).max()) if (mode == "on" and u_off is not None) else None
                r["relative_difference_to_off"] = diff
                rows.append(r)
                print(f"| {L} | {F:g} | {mode} | {r['cycles']}{'' if r['ok'] else '!'} = {r['settling']} + {r['settled']} "
                      f"({r['settled_rate']:.3f}) | {r['pg_cycles']} | {r['fallback_cycle'] or '-'} | {r['violation']:.1e} | "
                      f"{'-' if diff is None else f'{diff:.1e}'} | {r['seconds']:.1f} |", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"hierarchy": a.hierarchy, "runs": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
