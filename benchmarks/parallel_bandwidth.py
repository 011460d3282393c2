"""Issue 15: coloured sweeps on 1 and 2 threads against the memory bandwidth, cycle counts of the
two orders, and the memory per dof by owner.

    python benchmarks/parallel_bandwidth.py time   [--levels 8 9] [--levels3d 4] [--repeats 3] [--json out.json]
    python benchmarks/parallel_bandwidth.py counts [--levels 3 4 5 6 7 8 9] [--json out.json]
    python benchmarks/parallel_bandwidth.py memory --level 9 [--dim 2|3] [--json out.json]

time: seconds per cycle for (ordering x threads), the runs of one level interleaved (the machine
is shared: the load average is printed with every row; medians over --repeats); next to it the
bytes one fine sweep must read (matrix blocks, column indices, row pointers, diagonal positions,
inverted diagonal blocks, iterate and load) over the measured time of a sweep, and a stream-like
numpy triad a = b + s c on arrays far larger than the caches, 1 thread, in the same process.
memory: peak resident memory of a Hertz solve (the CLI's path) in a fresh process and what each
owner holds after the solve.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np


def load() -> str:
    return "%.2f" % os.getloadavg()[0]


def triad_gbs(n: int = 20_000_000, repeats: int = 5) -> float:
    """Bytes moved by a = b + s c (read b, c; write a: 3 x 8 bytes per entry) over the best time."""
    b, c, a = np.random.rand(n), np.random.rand(n), np.empty(n)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.multiply(c, 1.5, out=a)
        np.add(a, b, out=a)  # two passes: 5 x 8 bytes per entry (a written, read, written)
        best = min(best, time.perf_counter() - t0)
    return 5 * 8 * n / best / 1e9


def time_level(make, label, repeats, orders, threads):
    p = make()
    S = p.solver
    rows = {}
    for rep in range(repeats):
        for o in orders:
            for t in threads:
                r = p.solve("nmg", ordering=o, threads=t)
                rows.setdefault((o, t), []).append(r)
    out = []
    d = p.mesh.dim
    n = p.mesh.num_points
    mat = S.fine_matrix().memory_bytes()
    vec = 8 * d * n * (3 + d)  # iterate read + written, load, inverted diagonal blocks (d x d)
    for (o, t), rs in rows.items():
        spc = float(np.median([r.solve_seconds / r.cycles for r in rs]))
        sweeps = float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (6 * r.cycles) for r in rs]))
        out.append(dict(case=label, dofs=d * n, ordering=o, threads=t, cycles=rs[0].cycles,
                        seconds_per_cycle=spc, seconds_per_fine_sweep=sweeps,
                        sweep_bytes=mat + vec, sweep_gbs=(mat + vec) / sweeps / 1e9,
                        converged=all(r.converged for r in rs), load=load()))
        print(json.dumps(out[-1]), flush=True)
    return out


def cmd_time(args):
    from contactmg.hertz import hertz_problem
    from contactmg.sphere import sphere_problem
    res = {"triad_gbs_1thread": triad_gbs(), "load_before": load(), "rows": []}
    print("triad GB/s (1 thread):", round(res["triad_gbs_1thread"], 2), "load", load(), flush=True)
    orders, threads = ("lexicographic", "coloured"), (1, 2)
    for lev in args.levels:
        res["rows"] += time_level(lambda: hertz_problem("triangle", lev, 0.4), f"hertz-2d-L{lev}", args.repeats, orders, threads)
    for lev in args.levels3d:
        res["rows"] += time_level(lambda: sphere_problem(levels=lev, friction=0.4), f"sphere-3d-L{lev}", args.repeats, orders, threads)
    res["triad_gbs_1thread_after"] = triad_gbs()
    res["load_after"] = load()
    print("triad GB/s after:", round(res["triad_gbs_1thread_after"], 2), "load", load())
    return res


def cmd_counts(args):
    from contactmg.hertz import hertz_problem
    rows = []
    for lev in args.levels:
        for F in (0.4, 5.0) if not args.f else args.f:
            row = {"level": lev, "F": F}
            for o in ("lexicographic", "coloured"):
                r = hertz_problem("triangle", lev, F).solve("nmg", ordering=o)
                row[o] = r.cycles if r.converged else f"not converged: {r.status}"
            print(json.dumps(row), flush=True)
            rows.append(row)
    return {"rows": rows}


MEMORY_WORKER = r'''
import json, resource, sys, gc
import numpy as np
dim, level = int(sys.argv[1]), int(sys.argv[2])
if dim == 2:
    from contactmg.hertz import hertz_problem
    p = hertz_problem("triangle", level, 0.4)
else:
    from contactmg.sphere import sphere_problem
    p = sphere_problem(levels=level, friction=0.4)
r = p.solve("nmg")
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
d, n = p.mesh.dim, p.mesh.num_points
S = p.solver
nb = lambda *arrs: int(sum(a.nbytes for a in arrs if isinstance(a, np.ndarray)))
meshes = sum(nb(m.points, m.cells, m.facets, m.facet_tags) for m in p.hierarchy.meshes)
transfers = sum(nb(*t.as_tuple()[2:]) for t in p.hierarchy.transfers)
fine = S.fine_matrix().memory_bytes()
coarse = sum(S.coarse_matrix(l).memory_bytes() for l in range(S.num_levels - 1))
core = S.memory_bytes()
results = nb(r.displacement, r.contact_force, r.friction_bound, r.node_state) + sum(v.nbytes for v in r.history.values())
python_A = p._A.memory_bytes() if getattr(p, "_A", None) is not None else 0
problem_vectors = nb(p.load, p.fixed, p.fixed_values, p.contact.nodes, p.contact.normals, p.contact.gaps, p.coefficients)
print(json.dumps(dict(dim=dim, level=level, dofs=d * n, cycles=r.cycles, converged=r.converged, peak_rss_bytes=peak,
                      peak_bytes_per_dof=peak / (d * n), fine_matrix=fine, coarse_matrices=coarse,
                      core_total=core, core_transfers_vectors_dinv=core - fine - coarse, python_matrix_copy=python_A,
                      mesh_hierarchy_python=meshes, transfers_python=transfers, problem_vectors_python=problem_vectors,
                      results=results)))
'''


def cmd_memory(args):
    out = subprocess.run([sys.executable, "-c", MEMORY_WORKER, str(args.dim), str(args.level)], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    dofs = res["dofs"]
    for k, v in res.items():
        if isinstance(v, int) and k not in ("dim", "level", "dofs", "cycles"):
            print(f"{k:32s} {v / 2**20:9.1f} MiB {v / dofs:7.1f} B/dof")
    return res


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("time")
    t.add_argument("--levels", type=int, nargs="*", default=[8, 9])
    t.add_argument("--levels3d", type=int, nargs="*", default=[4])
    t.add_argument("--repeats", type=int, default=3)
    c = sub.add_parser("counts")
    c.add_argument("--levels", type=int, nargs="+", default=[3, 4, 5, 6, 7, 8, 9])
    c.add_argument("--f", type=float, nargs="*", default=None)
    m = sub.add_parser("memory")
    m.add_argument("--level", type=int, default=9)
    m.add_argument("--dim", type=int, default=2)
    for s in (t, c, m):
        s.add_argument("--json")
    args = ap.parse_args()
    res = {"time": cmd_time, "counts": cmd_counts, "memory": cmd_memory}[args.cmd](args)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
