"""Issue 15 (branch perf4): the run-time switches of a cycle's passes, cumulatively, in one process,
interleaved (the machine may be shared: the load average is printed; medians over --repeats).

    python benchmarks/cycle_switches.py [--case hertz:9] [--case tetra:4] [--repeats 3] [--threads 1 2] [--json out.json]

Configurations, each adding one switch to the previous:
  base      colours stored in the user's numbering (_core._locality_order(False)), coarse sweeps per
            row (_level_sweep_generic(True)), no prefetch of the matrix values (_prefetch_value_rows(0))
  +coarse   the coarse sweeps' range kernel
  +values   the matrix values prefetched 16 rows ahead
  +locality each colour stored in the level's locality order (a second solver, built with it)
The prefetch of x (forced inline) and the kept A (G(x) - x) of the restart test are in every row.
Per row: cycles, s/cycle, ms per fine sweep (from the cycle's phases), the phases (ms per cycle).
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
CONFIGS = (("base", False, True, 0), ("+coarse", False, False, 0), ("+values", False, False, 16), ("+locality", True, False, 16))


def make(case):
    kind, lev = case.split(":")
    if kind == "hertz":
        return hertz_problem("triangle", int(lev), 0.4)
    return sphere_problem(cell=kind, levels=int(lev), friction=0.4)


def run(case, repeats, threads):
    solvers = {}
    old = (_core._locality_order(), _core._level_sweep_generic(), _core._prefetch_value_rows())
    try:
        for local in (False, True):
            _core._locality_order(local)
            p = make(case)
            p.default_ordering = "coloured"
            p.solver
            solvers[local] = p
        rows = {}
        for _ in range(repeats):
            for t in threads:
                for name, local, generic, ahead in CONFIGS:
                    _core._level_sweep_generic(generic)
                    _core._prefetch_value_rows(ahead)
                    rows.setdefault((name, t), []).append(solvers[local].solve("nmg", ordering="coloured", threads=t))
    finally:
        _core._locality_order(old[0]), _core._level_sweep_generic(old[1]), _core._prefetch_value_rows(old[2])
    out = []
    nu = solvers[False].default_cycle.nu1 + solvers[False].default_cycle.nu2
    for (name, t), rs in rows.items():
        out.append(dict(case=case, config=name, threads=t, cycles=[r.cycles for r in rs],
                        seconds_per_cycle=float(np.median([r.solve_seconds / r.cycles for r in rs])),
                        seconds_per_cycle_all=[r.solve_seconds / r.cycles for r in rs],
                        ms_per_fine_sweep=1e3 * float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (nu * r.cycles)
                                                                 for r in rs])),
                        phase_ms={k: round(1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in rs])), 2) for k in PHASES},
                        load="%.2f" % os.getloadavg()[0]))
        print(json.dumps(out[-1]), flush=True)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", action="append", default=None)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--json")
    a = ap.parse_args()
    res = {"load_before": "%.2f" % os.getloadavg()[0], "stream": {f"core_{t}": _core.testing.stream_triad(40_000_000, 5, t) for t in (1, 2)},
           "rows": []}
    print("stream GB/s", res["stream"], "load", res["load_before"], flush=True)
    for case in a.case or ["hertz:9"]:
        res["rows"] += run(case, a.repeats, a.threads)
    res["load_after"] = "%.2f" % os.getloadavg()[0]
    print("\n| case | threads | config | cycles | s/cycle | ms/fine sweep | coarse correction ms | norm ms | load |\n|---|---|---|---|---|---|---|---|---|")
    for r in res["rows"]:
        print(f"| {r['case']} | {r['threads']} | {r['config']} | {r['cycles'][0]} | {r['seconds_per_cycle']:.3f} | {r['ms_per_fine_sweep']:.1f} | "
              f"{r['phase_ms']['coarse_correction']:.1f} | {r['phase_ms']['norm']:.1f} | {r['load']} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
