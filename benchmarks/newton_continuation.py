"""Does the discrete Coulomb problem on adaptive Hertz level 11 have a solution at F = 40? Semismooth
Newton on the whole problem (coulomb_newton_diagnosis.semismooth_newton: Alart-Curnier, sparse
direct solves, Armijo on |phi|^2) with continuation in F from a saved solution (default: the fourth
part's F = 20 Newton solution, out/cache/nw_F20.npy), in steps of --ratio, halving a step whose
Newton solve does not converge (issue 11, eighth part; docs/history/adaptive.md).

    python benchmarks/newton_continuation.py [--start out/cache/nw_F20.npy] [--from-F 20] [--to-F 40]
        [--ratio 1.1] [--json PATH] [--deadline-seconds 1500]
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from coulomb_newton_diagnosis import ac_residual, hertz_system, hierarchy, semismooth_newton  # noqa: E402
from contactmg.hertz import hertz_problem_on  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--start", default=os.path.join("out", "cache", "nw_F20.npy"))
    ap.add_argument("--level", type=int, default=11)
    ap.add_argument("--from-F", type=float, default=20.0)
    ap.add_argument("--to-F", type=float, default=40.0)
    ap.add_argument("--ratio", type=float, default=1.1)
    ap.add_argument("--steps", type=int, default=25)
    ap.add_argument("--deadline-seconds", type=float, default=1500)
    ap.add_argument("--json")
    a = ap.parse_args()
    t0 = time.perf_counter()
    H = hierarchy(a.level)
    p = hertz_problem_on(H, a.from_F)
    S = hertz_system(p)
    x = S["D"] * np.load(a.start).ravel()
    scale = float(np.abs(ac_residual(S, a.from_F, S["fixed_values"].copy())).max())
    tol = 1e-10 * scale
    r0 = float(np.linalg.norm(ac_residual(S, a.from_F, x)))
    print(f"start: |phi| at F = {a.from_F:g} {r0:.1e} (tol {tol:.1e})", flush=True)
    out = {"start": a.start, "from_F": a.from_F, "tol": tol, "phi_start": r0, "steps": []}
    F, dF = a.from_F, a.from_F * (a.ratio - 1)
    while F < a.to_F and time.perf_counter() - t0 < a.deadline_seconds and dF > 1e-3 * a.from_F:
        Fn = min(F + dF, a.to_F)
        ts = time.perf_counter()
        xn, hist, counts = semismooth_newton(S, Fn, x.copy(), max_steps=a.steps, tol=tol)
        ok = hist[-1] <= tol
        rec = {"F": Fn, "converged": ok, "newton_steps": len(hist) - 1, "phi": hist[-1], "counts": counts,
               "seconds": time.perf_counter() - ts}
        out["steps"].append(rec)
        print(f"F = {Fn:.3f}: {'converged' if ok else 'failed'} in {len(hist) - 1} steps, |phi| {hist[-1]:.1e}, "
              f"active / stick / slip {counts}, {rec['seconds']:.0f} s", flush=True)
        if ok:
            x, F = xn, Fn
            dF *= 1.2
        else:
            dF /= 2
        if a.json:
            with open(a.json, "w") as fh:
                json.dump(out, fh, indent=1)
    out["reached_F"] = F
    print(f"reached F = {F:g}", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
