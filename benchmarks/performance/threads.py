"""Threads and memory bandwidth: seconds per cycle of Algorithm 2 on 1 and 2 threads with the
coloured Gauss-Seidel sweeps (the default) and on one thread with the lexicographic ones, solves
interleaved with medians over --repeats (the machine may be shared: the load average is recorded);
where a cycle's time goes (the step's phases, ms per cycle); and the cycle's time against the
memory bandwidth: the bytes a cycle must move (a model: every sweep, product, restriction and
prolongation on every level as often as the cycle visits it) over the time of a cycle, set against
the core's stream triad and read rates measured in the same run. With --counts also the cycle
counts of both orderings over levels (the orderings give different iterates, not different rates).

    python benchmarks/performance/threads.py [--levels 8 9] [--levels-3d 4] [--repeats 3]
        [--threads 1 2] [--counts 3 9] [--quick] [--json PATH]
"""
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg import _core  # noqa: E402
from contactmg.solve.options import options_from

PHASES = ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check")


def _stream_module():
    """The core's stream measurements (test-only entry points)."""
    return _core.testing


def stream_rates(n=40_000_000, repeats=5):
    """GB/s of the core's triad a = b + 1.5 c (24 counted bytes an entry) on 1 and 2 threads, its
    read of one array in 4 pieces, its matrix-like read of 2x2 blocks with int32 columns, and
    numpy's sum (8 bytes an entry)."""
    s = _stream_module()
    out = {}
    if hasattr(s, "stream_triad"):
        for t in (1, 2):
            out[f"core_triad_{t}"] = s.stream_triad(n, repeats, t)
    if hasattr(s, "stream_read"):
        for t in (1, 2):
            out[f"core_read_{t}"] = s.stream_read(n, repeats, t, 4)
        out["core_blocks_1"] = s.stream_read_blocks(max(n // 4, 1000), repeats, 1, 2)
    a, best = np.random.rand(n), np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        a.sum()
        best = min(best, time.perf_counter() - t0)
    out["numpy_read_1"] = 8 * n / best / 1e9
    return out


def coarse_visits(top, cycle):
    """How often a coarse correction smooths each coarse level 0 .. top (level 0 is solved instead)
    and forms its residual, restricts it and prolongates back (levels 1 .. top). A W- or F-cycle
    visits level top a second time from the fine level, and each visit of a level of a W/F-cycle
    visits the next coarser level twice (F: an F- then a V-cycle)."""
    smooth, resid = [0] * (top + 1), [0] * (top + 1)

    def visit(l, t):
        smooth[l] += 1
        if l == 0:
            return
        for v in range(1 if t == "V" else 2):
            resid[l] += 1
            visit(l - 1, "V" if (t == "F" and v == 1) else t)

    visit(top, cycle)
    if cycle != "V":
        visit(top, "V" if cycle == "F" else "W")
    return smooth, resid


def cycle_bytes(p):
    """Model bytes of one cycle: a sweep reads the matrix, the inverted diagonal blocks (coarse
    levels), the iterate and the right-hand side and writes the iterate; a product reads the matrix
    and x and writes y; a transfer reads the prolongation (scalar weights, 32-bit columns) and both
    vectors."""
    S, d, opt = p.solver.core, p.mesh.dim, p.solver.options
    nu = opt.nu1 + opt.nu2
    vec = lambda n: 8 * d * n  # noqa: E731
    T = p.hierarchy.transfers
    tbytes = lambda t: len(t.parent) * 12 + 8 * (t.n_fine + 1) + vec(t.n_fine) + vec(t.n_coarse)  # noqa: E731
    A, n = _core.testing.fine_matrix(S).memory_bytes(), p.mesh.num_points
    fine = nu * (A + 3 * vec(n)) + 2 * (A + 2 * vec(n)) + 2 * tbytes(T[-1])
    levels = S.num_levels - 1
    smooth, resid = coarse_visits(levels - 1, opt.cycle) if levels >= 1 else ([], [])
    coarse = 0
    for l in range(1, levels):
        m, M = T[l - 1].n_fine, _core.testing.coarse_matrix(S, l).memory_bytes()
        coarse += smooth[l] * nu * (M + 8 * d * d * m + 3 * vec(m)) + resid[l] * (M + 2 * vec(m) + 2 * tbytes(T[l - 1]))
    return {"fine": fine, "coarse": coarse, "total": fine + coarse, "sweep": A + 3 * vec(n)}


def time_case(label, make, repeats, threads, stream):
    """Rows (ordering, threads) of one case: medians of interleaved solves."""
    configs = [("coloured", t) for t in threads] + [("lexicographic", 1)]
    problems = {}
    for ordering in ("coloured", "lexicographic"):
        p = make()
        p.default_options = options_from(p.default_options).replace(ordering=ordering)
        p.solver.core  # noqa: B018 - built outside the timings
        problems[ordering] = p
    runs = {c: [] for c in configs}
    for _ in range(repeats):
        for ordering, t in configs:
            runs[(ordering, t)].append(problems[ordering].solve("nmg", ordering=ordering, threads=t))
    rows = []
    for (ordering, t), rs in runs.items():
        p = problems[ordering]
        nu = p.solver.options.nu1 + p.solver.options.nu2
        b = cycle_bytes(p)
        spc = float(np.median([r.solve_seconds / r.cycles for r in rs]))
        sweep = float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (nu * r.cycles)
                                 for r in rs]))
        phases = {k: 1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in rs])) for k in PHASES}
        phases["other"] = 1e3 * spc - sum(phases.values())
        triad = stream.get(f"core_triad_{t}", stream.get("core_triad_1", stream["numpy_read_1"]))
        rows.append({"case": label, "dofs": p.mesh.dim * p.mesh.num_points, "ordering": ordering, "threads": t,
                     "cycles": rs[0].cycles, "converged": all(r.converged for r in rs), "seconds_per_cycle": spc,
                     "seconds_per_fine_sweep": sweep, "sweep_gbs": b["sweep"] / sweep / 1e9,
                     "cycle_bytes": b["total"], "cycle_gbs": b["total"] / spc / 1e9,
                     "cycle_over_triad_time": spc / (b["total"] / (triad * 1e9)), "phase_ms": phases,
                     "load_average": os.getloadavg()[0]})
    one = next(r["seconds_per_cycle"] for r in rows if r["ordering"] == "coloured" and r["threads"] == 1)
    for r in rows:
        r["speedup_vs_coloured_1"] = one / r["seconds_per_cycle"]
        print(f"{r['case']:>14} {r['dofs']:9,} {r['ordering']:>13} {r['threads']:3d} {r['cycles']:4d} "
              f"{1e3 * r['seconds_per_cycle']:9.2f} {r['speedup_vs_coloured_1']:6.2f}x {r['cycle_gbs']:7.2f} "
              f"{r['cycle_over_triad_time']:6.2f} " + " ".join(f"{r['phase_ms'][k]:6.2f}" for k in PHASES + ("other",)),
              flush=True)
    return rows


def counts(levels, frictions):
    """Cycle counts of the coloured and the lexicographic sweeps over Hertz levels."""
    from contactmg.examples.hertz import hertz_problem
    rows = []
    for L in range(levels[0], levels[1] + 1):
        for F in frictions:
            row = {"level": L, "F": F}
            for o in ("lexicographic", "coloured"):
                p = hertz_problem("triangle", L, F)
                p.default_options = options_from(p.default_options).replace(ordering=o)
                r = p.solve("nmg", ordering=o)
                row[o] = r.cycles if r.converged else None
            rows.append(row)
            print(f"counts L{L} F={F:g}: lexicographic {row['lexicographic']}, coloured {row['coloured']}", flush=True)
    return rows


def main():
    ap = parser(__doc__)
    ap.add_argument("--levels", type=int, nargs="*", default=[8, 9], help="Hertz triangle levels")
    ap.add_argument("--levels-3d", type=int, nargs="*", default=[4], help="hexahedral sphere levels")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--counts", type=int, nargs=2, default=None, help="first and last level of the cycle counts")
    a = ap.parse_args()
    if a.quick:
        a.levels, a.levels_3d, a.repeats, a.counts = [5], [2], 1, [3, 4]
    from contactmg.examples.hertz import hertz_problem
    from contactmg.examples.sphere import sphere_problem
    n = 4_000_000 if a.quick else 40_000_000
    stream = stream_rates(n, 2 if a.quick else 5)
    print("stream GB/s:", {k: round(v, 2) for k, v in stream.items()}, f"load {os.getloadavg()[0]:.2f}", flush=True)
    print(f"{'case':>14} {'dofs':>9} {'ordering':>13} {'thr':>3} {'cyc':>4} {'ms/cycle':>9} {'speedup':>7} {'GB/s':>7} "
          f"{'/triad':>6} " + " ".join(f"{k[:6]:>6}" for k in PHASES + ("other",)))
    rows = []
    for L in a.levels:
        rows += time_case(f"hertz-2d-L{L}", lambda L=L: hertz_problem("triangle", L, 0.4), a.repeats, a.threads, stream)
    for L in a.levels_3d:
        rows += time_case(f"sphere-3d-L{L}", lambda L=L: sphere_problem(levels=L, friction=0.4), a.repeats, a.threads,
                          stream)
    out = {"stream_gbs": stream, "rows": rows}
    if a.counts:
        out["counts"] = counts(a.counts, (0.4, 5.0))
    out["stream_gbs_after"] = stream_rates(n, 2 if a.quick else 5)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
