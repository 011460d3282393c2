"""Issue 15: interleaved A/B of one process-wide switch of the core (e.g. _fused_residual_restriction)
on one solver per case, Hertz triangles F = 0.4, coloured stored by colours: solves alternate
between the switch on and off (the machine may be shared: the load average is recorded with every
solve), medians over --repeats of seconds per cycle and of the phases (ms per cycle); the core's
triad and 4-piece read at the start and the end.

    python benchmarks/switch_ab.py --switch _fused_residual_restriction [--levels 8 9] [--repeats 4]
        [--threads 1] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import os

import numpy as np

from contactmg import _core
from contactmg.hertz import hertz_problem

PHASES = ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check")


def load() -> float:
    return round(os.getloadavg()[0], 2)


def rates() -> dict:
    return {"core_triad_1": _core.testing.stream_triad(40_000_000, 5, 1), "core_read_1": _core.testing.stream_read(40_000_000, 5, 1, 4)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--switch", required=True)
    ap.add_argument("--levels", type=int, nargs="+", default=[8, 9])
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json")
    a = ap.parse_args()
    sw = getattr(_core, a.switch)
    old = sw()
    res = {"switch": a.switch, "threads": a.threads, "stream_before": rates(), "load_before": load(), "rows": []}
    print(res["stream_before"], "load", res["load_before"], flush=True)
    for lev in a.levels:
        p = hertz_problem("triangle", lev, 0.4)
        p.default_ordering = "coloured"
        p.solver
        p.solve("nmg", ordering="coloured", threads=a.threads)  # the workspace's first touch outside the timings
        runs = {True: [], False: []}
        for rep in range(a.repeats):
            for on in ((True, False) if rep % 2 == 0 else (False, True)):
                sw(on)
                r = p.solve("nmg", ordering="coloured", threads=a.threads)
                runs[on].append(dict(cycles=r.cycles, spc=r.solve_seconds / r.cycles, load=load(),
                                     phase_ms={k: 1e3 * r.phase_seconds.get(k, 0.0) / r.cycles for k in PHASES}))
                print(lev, on, runs[on][-1]["cycles"], round(runs[on][-1]["spc"], 4), runs[on][-1]["load"], flush=True)
        for on, rs in runs.items():
            row = dict(case=f"hertz-2d-L{lev}", dofs=2 * p.mesh.num_points, on=on, cycles=[r["cycles"] for r in rs],
                       seconds_per_cycle=float(np.median([r["spc"] for r in rs])), seconds_per_cycle_all=[r["spc"] for r in rs],
                       phase_ms={k: round(float(np.median([r["phase_ms"][k] for r in rs])), 2) for k in PHASES},
                       loads=[r["load"] for r in rs])
            row["phase_ms"]["other"] = round(1e3 * row["seconds_per_cycle"] - sum(row["phase_ms"].values()), 2)
            res["rows"].append(row)
            print(json.dumps(row), flush=True)
    sw(old)
    res["stream_after"], res["load_after"] = rates(), load()
    print(res["stream_after"], "load", res["load_after"])
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
