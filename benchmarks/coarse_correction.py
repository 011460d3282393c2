"""Issues 10 and 15, the coarse correction: variants of the coarse work interleaved in one process
(the machine may be shared: the load average is printed with every row; medians over --repeats).

    python benchmarks/coarse_correction.py sphere [--levels 3] [--repeats 3] [--json out.json]
    python benchmarks/coarse_correction.py hertz  [--levels 8 9] [--level-rows 8192 0 32768] [--repeats 3] [--json out.json]

sphere (issue 10): Algorithm 2 (nmg) against the linear solve with the contact state known
(`--method linear`) on the tetrahedral sphere at F = 0.4, on 1 and 2 threads, with the coarsest
solve kept current by low-rank corrections (max_rank 96, the default) and by a new factorization
at every coarse update (max_rank 0, the behaviour before); ms per cycle by phase.
hertz (issue 15): Hertz triangles at F = 0.4, levels stored by colours, on 1 and 2 threads, with
coarse levels below --level-rows rows kept on one thread (the default 8192, none: 0, 32768; the
results are the same bit for bit); ms per cycle by phase, the speedup of the cycle and of the
coarse correction from the second thread.
Ends with the table in markdown.
"""
from __future__ import annotations

import argparse
import json
import os

import numpy as np

from contactmg import _core

PHASES = ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm")


def load() -> float:
    return round(os.getloadavg()[0], 2)


def summary(rs, label: str, **kw) -> dict:
    out = dict(case=label, cycles=rs[0].cycles, converged=all(r.converged for r in rs),
               solve_seconds=float(np.median([r.solve_seconds for r in rs])),
               ms_per_cycle=1e3 * float(np.median([r.solve_seconds / r.cycles for r in rs])),
               phase_ms={k: 1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in rs])) for k in PHASES},
               rebuilds=rs[0].rebuilds, load=load(), **kw)
    print(json.dumps(out), flush=True)
    return out


def cmd_sphere(args) -> dict:
    from contactmg.sphere import sphere_problem
    rows = []
    old_rank = _core.coarsest_max_rank()
    for lev in args.levels:
        p = sphere_problem(cell="tetra", levels=lev, friction=0.4)
        p.default_ordering = "coloured"
        ref = p.solve("nmg")
        runs = {}
        for _ in range(args.repeats):
            for t in (1, 2):
                for rank in (old_rank, 0):
                    _core.set_coarsest_max_rank(rank)
                    before = _core.coarsest_factorizations()
                    r = p.solve("nmg", threads=t)
                    r.extra["factorizations"] = _core.coarsest_factorizations() - before
                    runs.setdefault(("nmg", t, rank), []).append(r)
                _core.set_coarsest_max_rank(old_rank)
                runs.setdefault(("linear", t, None), []).append(p.solve("linear", threads=t, reference=ref))
        _core.set_coarsest_max_rank(old_rank)
        for (m, t, rank), rs in runs.items():
            rows.append(summary(rs, f"sphere-tetra-L{lev}", dofs=3 * p.mesh.num_points, method=m, threads=t, max_rank=rank,
                                factorizations=rs[0].extra.get("factorizations")))
    by = {(r["case"], r["method"], r["threads"], r["max_rank"]): r for r in rows}
    for r in rows:
        lin = by.get((r["case"], "linear", r["threads"], None))
        r["over_linear"] = r["solve_seconds"] / lin["solve_seconds"] if lin else None
    return {"rows": rows}


def cmd_hertz(args) -> dict:
    from contactmg.hertz import hertz_problem
    rows = []
    default = _core.parallel_grains()
    variants = {f"level_rows {r}" + (" (default)" if r == default[1] else ""): (default[0], r) for r in args.level_rows}
    for lev in args.levels:
        p = hertz_problem("triangle", lev, 0.4)
        p.default_ordering = "coloured"
        p.solver
        runs = {}
        for _ in range(args.repeats):
            for name, g in variants.items():
                _core.set_parallel_grains(*g)
                for t in (1, 2):
                    runs.setdefault((name, t), []).append(p.solve("nmg", ordering="coloured", threads=t))
        _core.set_parallel_grains(*default)
        for (name, t), rs in runs.items():
            rows.append(summary(rs, f"hertz-2d-L{lev}", dofs=2 * p.mesh.num_points, variant=name, grains=list(variants[name]),
                                threads=t))
    by = {(r["case"], r["variant"], r["threads"]): r for r in rows}
    for r in rows:
        one = by[(r["case"], r["variant"], 1)]
        r["speedup_cycle"] = one["ms_per_cycle"] / r["ms_per_cycle"]
        r["speedup_coarse"] = one["phase_ms"]["coarse_correction"] / r["phase_ms"]["coarse_correction"]
    return {"rows": rows}


def table(res: dict, cmd: str) -> str:
    head = ["case", "dofs"] + (["method", "max_rank", "threads", "cycles", "factorizations", "solve s", "ms/cycle", "/ linear"]
                               if cmd == "sphere" else ["variant", "threads", "cycles", "ms/cycle", "2 thr speedup", "coarse speedup"])
    head += [k for k in PHASES] + ["load"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in res["rows"]:
        if cmd == "sphere":
            cells = [r["case"], f"{r['dofs']:,}", r["method"], str(r["max_rank"]), str(r["threads"]), str(r["cycles"]),
                     str(r["factorizations"]), f"{r['solve_seconds']:.3f}", f"{r['ms_per_cycle']:.1f}",
                     f"{r['over_linear']:.2f}x"]
        else:
            cells = [r["case"], f"{r['dofs']:,}", r["variant"], str(r["threads"]), str(r["cycles"]), f"{r['ms_per_cycle']:.1f}",
                     f"{r['speedup_cycle']:.2f}x", f"{r['speedup_coarse']:.2f}x"]
        cells += [f"{r['phase_ms'][k]:.1f}" for k in PHASES] + [str(r["load"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("sphere")
    s.add_argument("--levels", type=int, nargs="+", default=[3])
    h = sub.add_parser("hertz")
    h.add_argument("--levels", type=int, nargs="+", default=[8, 9])
    h.add_argument("--level-rows", type=int, nargs="+", default=[_core.parallel_grains()[1], 0, 32768],
                   help="coarse levels below this many rows run on one thread (the variants compared)")
    for a in (s, h):
        a.add_argument("--repeats", type=int, default=3)
        a.add_argument("--json")
    args = ap.parse_args()
    res = {"sphere": cmd_sphere, "hertz": cmd_hertz}[args.cmd](args)
    res["load_after"] = load()
    print()
    print(table(res, args.cmd))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
