"""Algorithm 2 alone on the adaptive Hertz levels (issue 11's target: flat over levels 3-11 for the
ten paper coefficients, spread <= 4 cycles), every result checked by contactmg.checks.

    python benchmarks/adaptive_coulomb_levels.py [--levels 3 5 7 9 11] [--frictions ...]
        [--max-cycles 200] [--jobs 2] [--json benchmarks/results/adaptive_coulomb_levels.json]
        [--label after] [--hierarchy adaptive|uniform]

The hierarchy is hertz_adaptive_hierarchy(11, 0.4) (the one of `contactmg table1`), cached in
out/cache/hertz_adaptive_11.pkl by benchmarks/cycle_growth.py. Each run: F(3,3), tol 1e-11, from
u = 0, one thread (cycle counts do not depend on the machine's load; seconds do). Prints the table
F x level with the spread (max - min over the levels) and "!" for a run that did not converge or
failed the check (relative violation > 1e-8).
"""
import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

sys.path.insert(0, os.path.dirname(__file__))

PAPER = [0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0]
_H = None


def _init(kind="adaptive"):
    global _H
    if kind == "uniform":
        _H = "uniform"  # hertz_problem builds the uniform hierarchy of each level
        return
    from cycle_growth import adaptive_hierarchy
    _H = adaptive_hierarchy(11)


def run(L, F, max_cycles):
    from contactmg.checks import contact_conditions
    from contactmg.hertz import hertz_problem

    p = hertz_problem("triangle", L, F, coulomb_at_zero=True, hierarchy="uniform" if _H == "uniform" else _H.truncated(L))
    t = time.perf_counter()
    r = p.solve("nmg", tol=1e-11, max_cycles=max_cycles, threads=1)
    sec = time.perf_counter() - t
    viol = contact_conditions(p, r)["max"]
    return {"level": L, "F": F, "dofs": 2 * p.mesh.num_points, "cycles": int(r.cycles), "converged": bool(r.converged),
            "status": r.status, "violation": float(viol), "seconds": sec,
            "history": [float(x) for x in r.history["correction_norm"]]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=PAPER)
    ap.add_argument("--max-cycles", type=int, default=200)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--label", default="")
    ap.add_argument("--hierarchy", choices=["adaptive", "uniform"], default="adaptive")
    ap.add_argument("--json")
    a = ap.parse_args()
    tasks = sorted(((L, F) for L in a.levels for F in a.frictions), key=lambda t: (-t[0], -t[1]))
    rows = []
    with ProcessPoolExecutor(a.jobs, initializer=_init, initargs=(a.hierarchy,)) as pool:
        futs = [pool.submit(run, L, F, a.max_cycles) for L, F in tasks]
        for f in as_completed(futs):
            r = f.result()
            rows.append(r)
            print(f"  L{r['level']:<2} F={r['F']:<5} {r['cycles']:4d}{'' if r['converged'] else '!'} "
                  f"viol {r['violation']:.1e}  {r['seconds']:.1f}s", flush=True)
    print(f"\nAlgorithm 2 cycles {a.label} (F(3,3), tol 1e-11; '!' not converged or check failed)")
    print("| F | " + " | ".join(f"L{L}" for L in a.levels) + " | spread |")
    for F in a.frictions:
        cells, ok = [], True
        for L in a.levels:
            r = next(x for x in rows if x["level"] == L and x["F"] == F)
            good = r["converged"] and r["violation"] <= 1e-8
            ok &= good
            cells.append(f"{r['cycles']}{'' if good else '!'}")
        c = [next(x for x in rows if x["level"] == L and x["F"] == F)["cycles"] for L in a.levels]
        print(f"| {F:g} | " + " | ".join(cells) + f" | {max(c) - min(c) if ok else '-'} |")
    if a.json:
        os.makedirs(os.path.dirname(a.json) or ".", exist_ok=True)
        with open(a.json, "w") as fh:
            json.dump({"label": a.label, "hierarchy": a.hierarchy, "levels": a.levels, "frictions": a.frictions, "runs": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
