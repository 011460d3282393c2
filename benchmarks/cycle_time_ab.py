"""Issue 15: seconds per cycle of the default solver (coloured, stored by colours) of Hertz triangles
F = 0.4 on 1 and 2 threads, one process per build, for A/B comparisons between two builds run in
alternating processes (the machine may be shared: the load average is printed with every row).

    python benchmarks/cycle_time_ab.py [--levels 8 9] [--repeats 3] [--threads 1 2] [--sphere tetra:3] [--label L] [--json out.json]

Medians over --repeats solves of one solver; also the fine sweep (ms), the phases of a cycle (ms)
and the core's stream triad on 1 and 2 threads at the start (and its 4-piece read where the build
has it). Runs with any build of the core (it uses no switch that a build may lack).
"""
from __future__ import annotations

import argparse
import json
import os

import numpy as np

from contactmg import _core
from contactmg.hertz import hertz_problem
from contactmg.sphere import sphere_problem

PHASES = ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check")


def load() -> str:
    return "%.2f" % os.getloadavg()[0]


def measure(p, case, repeats, threads):
    p.default_ordering = "coloured"
    p.solver
    rs = {t: [] for t in threads}
    for _ in range(repeats):
        for t in threads:
            rs[t].append(p.solve("nmg", ordering="coloured", threads=t))
    out = []
    nu = p.default_cycle.nu1 + p.default_cycle.nu2
    for t, v in rs.items():
        out.append(dict(case=case, threads=t, cycles=[r.cycles for r in v],
                        seconds_per_cycle=float(np.median([r.solve_seconds / r.cycles for r in v])),
                        seconds_per_cycle_all=[r.solve_seconds / r.cycles for r in v],
                        ms_per_fine_sweep=1e3 * float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (nu * r.cycles)
                                                                 for r in v])),
                        phase_ms={k: round(1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in v])), 2) for k in PHASES},
                        load=load()))
        print(json.dumps(out[-1]), flush=True)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="*", default=[8, 9])
    ap.add_argument("--sphere", nargs="*", default=[], help="cell:level, e.g. tetra:3")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--label", default="")
    ap.add_argument("--json")
    a = ap.parse_args()
    res = {"label": a.label, "core": _core.__file__, "load_before": load(),
           "stream": {f"core_{t}": _core.testing.stream_triad(40_000_000, 5, t) for t in (1, 2)}, "rows": []}
    if hasattr(_core.testing, "stream_read"):  # the read reference of issue 15 (builds from perf6 on)
        res["stream"].update({f"core_read_{t}": _core.testing.stream_read(40_000_000, 5, t, 4) for t in (1, 2)})
    print(a.label, "stream GB/s", res["stream"], "load", load(), flush=True)
    for lev in a.levels:
        res["rows"] += measure(hertz_problem("triangle", lev, 0.4), f"hertz-2d-L{lev}", a.repeats, a.threads)
    for s in a.sphere:
        cell, lev = s.split(":")
        res["rows"] += measure(sphere_problem(cell=cell, levels=int(lev), friction=0.4), f"sphere-{cell}-L{lev}", a.repeats, a.threads)
    res["load_after"] = load()
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
