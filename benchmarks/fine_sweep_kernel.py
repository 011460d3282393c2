"""Issue 15: the fine nonlinear sweep's range kernel against the per-row path it replaced, in one
process, interleaved (the machine may be shared: the load average is printed with every row).

    python benchmarks/fine_sweep_kernel.py [--levels 8 9] [--repeats 3] [--sweeps 6] [--json out.json]

Hertz triangles F = 0.4, stored by colours; the sweeps start from the solution (contact nodes
active, sticking and sliding), omega = 1 (the `smooth` entry point). Per sweep: ms, ns per node
and the model bytes of a fine sweep (benchmarks/parallel_bandwidth.py: matrix, row pointers,
diagonal positions, iterate read and written, load) over the time. The two paths give the same
bits (tests/test_fine_sweep_kernel.py); `_core._fine_sweep_generic(True)` selects the per-row one.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from contactmg import _core
from contactmg.hertz import hertz_problem


def sweep_seconds(S, u0, sweeps, threads):
    # smooth(u0, 0) is the call's own cost (to the frames and back): taken off
    t0 = time.perf_counter()
    _core.testing.smooth(S, u0, 0, "coloured", threads)
    t1 = time.perf_counter()
    _core.testing.smooth(S, u0, sweeps, "coloured", threads)
    t2 = time.perf_counter()
    return ((t2 - t1) - (t1 - t0)) / sweeps


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[8, 9])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sweeps", type=int, default=6)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    old = _core._fine_sweep_generic()
    try:
        for lev in a.levels:
            p = hertz_problem("triangle", lev, 0.4)
            p.default_ordering = "coloured"
            S = p.solver
            n, d = p.mesh.num_points, p.mesh.dim
            sweep_bytes = _core.testing.fine_matrix(S).memory_bytes() + 3 * 8 * d * n
            u0 = p.solve("nmg").displacement
            times = {}
            for _ in range(a.repeats):
                for t in a.threads:
                    for generic in (True, False):
                        _core._fine_sweep_generic(generic)
                        times.setdefault((t, generic), []).append(sweep_seconds(S, u0, a.sweeps, t))
                        _core._fine_sweep_generic(old)
            for (t, generic), v in times.items():
                s = float(np.median(v))
                rows.append(dict(level=lev, nodes=n, threads=t, path="per-row" if generic else "kernel", ms_per_sweep=1e3 * s,
                                 ns_per_node=1e9 * s / n, sweep_gbs=sweep_bytes / s / 1e9, repeats=len(v),
                                 load="%.2f" % os.getloadavg()[0]))
                print(json.dumps(rows[-1]), flush=True)
    finally:
        _core._fine_sweep_generic(old)
    print("\n| level | threads | per-row ms | kernel ms | speed-up | kernel ns/node | kernel GB/s | load |\n|---|---|---|---|---|---|---|---|")
    by = {(r["level"], r["threads"], r["path"]): r for r in rows}
    for lev in a.levels:
        for t in a.threads:
            g, k = by[(lev, t, "per-row")], by[(lev, t, "kernel")]
            print(f"| {lev} | {t} | {g['ms_per_sweep']:.1f} | {k['ms_per_sweep']:.1f} | {g['ms_per_sweep'] / k['ms_per_sweep']:.2f}x | "
                  f"{k['ns_per_node']:.1f} | {k['sweep_gbs']:.2f} | {k['load']} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
