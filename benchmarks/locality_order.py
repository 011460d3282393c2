"""Issue 15: each colour of a level stored by colours in the level's locality order (reverse
Cuthill-McKee of the fine level, the coarse levels in the order of their nodes' heaviest children,
renumbering.hpp; the colouring itself unchanged) against the same storage in the user's numbering
within a colour (main before it), in one process, interleaved (the machine may be shared: the load
average is printed with every row; medians over --repeats).

    python benchmarks/locality_order.py [--levels 8 9] [--levels3d] [--repeats 3] [--threads 1 2] [--json out.json]

`_core._locality_order(False)` builds a solver the old way; each row: cycles, s/cycle, ms per fine
sweep, the phases of a cycle (ms), the model bytes of a cycle (parallel_bandwidth.cycle_bytes) over its
time and the cycle's time over the time to stream those bytes at the core's triad rate measured at
the start (same thread count).
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from parallel_bandwidth import cycle_bytes, load, stream_rates  # noqa: E402

from contactmg import _core  # noqa: E402

PHASES = ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check")


def run(make, label, repeats, threads, stream):
    problems = {}
    old = _core._locality_order()
    try:
        for local in (False, True):
            _core._locality_order(local)
            p = make()
            p.default_ordering = "coloured"
            p.solver  # built now, with the setting, outside the timings
            problems[local] = p
    finally:
        _core._locality_order(old)
    rows = {}
    for _ in range(repeats):
        for t in threads:
            for local, p in problems.items():
                rows.setdefault((local, t), []).append(p.solve("nmg", ordering="coloured", threads=t))
    out = []
    for (local, t), rs in rows.items():
        p = problems[local]
        nu = p.default_cycle.nu1 + p.default_cycle.nu2
        b = cycle_bytes(p, p.solver)
        spc = float(np.median([r.solve_seconds / r.cycles for r in rs]))
        sweep = float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (nu * r.cycles) for r in rs]))
        rate = stream.get(f"core_{t}", stream["numpy_1"]) * 1e9
        phases = {k: round(1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in rs])), 2) for k in PHASES}
        out.append(dict(case=label, dofs=p.mesh.dim * p.mesh.num_points, order="locality" if local else "user", threads=t,
                        cycles=[r.cycles for r in rs], seconds_per_cycle=spc, ms_per_fine_sweep=1e3 * sweep,
                        cycle_mb=b["total"] / 1e6, cycle_gbs=b["total"] / spc / 1e9, cycle_over_stream=spc / (b["total"] / rate),
                        seconds_per_cycle_all=[r.solve_seconds / r.cycles for r in rs], phase_ms=phases, load=load()))
        print(json.dumps(out[-1]), flush=True)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="*", default=[8, 9])
    ap.add_argument("--levels3d", type=int, nargs="*", default=[])
    ap.add_argument("--cell3d", default="tetra")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--json")
    a = ap.parse_args()
    from contactmg.hertz import hertz_problem
    from contactmg.sphere import sphere_problem
    res = {"stream": stream_rates(), "load_before": load(), "rows": []}
    print("stream GB/s:", {k: round(v, 2) for k, v in res["stream"].items()}, "load", load(), flush=True)
    for lev in a.levels:
        res["rows"] += run(lambda: hertz_problem("triangle", lev, 0.4), f"hertz-2d-L{lev}", a.repeats, a.threads, res["stream"])
    for lev in a.levels3d:
        res["rows"] += run(lambda: sphere_problem(levels=lev, friction=0.4, cell=a.cell3d), f"sphere-3d-{a.cell3d}-L{lev}",
                           a.repeats, a.threads, res["stream"])
    res["load_after"] = load()
    print("\n| case | threads | cycles user / locality | s/cycle user | s/cycle locality | speed-up | ms/fine sweep user / locality "
          "| cycle / stream time user / locality | load |\n|---|---|---|---|---|---|---|---|---|")
    by = {(r["case"], r["threads"], r["order"]): r for r in res["rows"]}
    for (case, t, o), r in by.items():
        if o != "user":
            continue
        q = by[(case, t, "locality")]
        print(f"| {case} | {t} | {r['cycles'][0]} / {q['cycles'][0]} | {r['seconds_per_cycle']:.3f} | {q['seconds_per_cycle']:.3f} | "
              f"{r['seconds_per_cycle'] / q['seconds_per_cycle']:.2f}x | {r['ms_per_fine_sweep']:.1f} / {q['ms_per_fine_sweep']:.1f} | "
              f"{r['cycle_over_stream']:.2f} / {q['cycle_over_stream']:.2f} | {q['load']} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
