"""Issue 15: coloured sweeps on 1 and 2 threads against the memory bandwidth, cycle counts of the
two orders, and the memory per dof by owner.

    python benchmarks/parallel_bandwidth.py time   [--levels 8 9] [--levels3d 4] [--repeats 3] [--json out.json]
    python benchmarks/parallel_bandwidth.py counts [--levels 3 4 5 6 7 8 9] [--json out.json]
    python benchmarks/parallel_bandwidth.py memory --level 9 [--dim 2|3] [--cell C] [--json out.json]
    (each with --float-coarse: the switch _core._float_coarse_values on)

time: seconds per cycle for lexicographic (1, 2 threads), coloured in the user's order (1 thread:
issue 15 before renumbering) and coloured stored by colours (1, 2 threads), the runs of one level
interleaved (the machine may be shared: the load average is printed with every row; medians over
--repeats); next to it the bytes one fine sweep must read (matrix blocks, column indices, row
pointers, diagonal positions, iterate read and written, load) over the measured time of
a sweep, the bytes of a whole cycle (cycle_bytes: every sweep, product, restriction and
prolongation on every level) over the time of a cycle, and the core's stream triad a = b + 1.5 c
on 1 and 2 threads (and numpy's) measured in the same run, before and after; and the cycle / stream
time against every reference (stream_rates, references: the triads, and the read rates a cycle that
mostly reads is bound by -- a sum over one array read as 4 pieces or 1, a matrix-like read of 2x2
blocks with int32 columns, numpy's sum). Ends with the whole table in markdown.
memory: peak resident memory of a Hertz solve (--dim 3: the sphere, --cell tetra or hexahedron) in a
fresh process: the CLI itself, then a worker on the CLI's path (the problem releases its Python
hierarchy and vectors once the core solver is built, as the CLI's single solves do) that reports what
each owner holds after the solve (ContactProblem.memory_bytes, the core's counters) and the resident
and peak memory after each stage. benchmarks/memory_timeline.py finds the moment of the peak.
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
    """numpy: bytes moved by a = b + s c in two passes (5 x 8 bytes per entry) over the best time.
    Its second pass (a = a + b in place) stores into lines it has just read, with no write-allocate
    traffic, and ran at 25.5 GB/s here where a pass that allocates (a = 1.5 c) ran at 13.9 (its 16
    counted bytes; 24 moved): numpy's figure mixes the two and is no read rate (docs/history/threads.md)."""
    b, c, a = np.random.rand(n), np.random.rand(n), np.empty(n)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.multiply(c, 1.5, out=a)
        np.add(a, b, out=a)  # two passes: 5 x 8 bytes per entry (a written, read, written)
        best = min(best, time.perf_counter() - t0)
    return 5 * 8 * n / best / 1e9


def numpy_read_gbs(n: int = 40_000_000, repeats: int = 5) -> float:
    """numpy: a sum over n doubles (8 bytes an entry, read only; numpy's own SIMD loops)."""
    a = np.random.rand(n)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        a.sum()
        best = min(best, time.perf_counter() - t0)
    return 8 * n / best / 1e9


def stream_rates() -> dict:
    """The core's triad a = b + 1.5 c (24 bytes an entry, 40M doubles) on 1 and 2 threads, and numpy's;
    the read references (issue 15: a cycle mostly reads): the core's sum over 40M doubles read as 4
    pieces at once (core_read_T) and as one (core_read1_1), its matrix-like read of 2x2 and 3x3 blocks
    with int32 columns (core_blocks_1, core_blocks3_1), numpy's sum (numpy_read_1)."""
    from contactmg import _core
    out = {"numpy_1": triad_gbs(), "numpy_read_1": numpy_read_gbs()}
    if hasattr(_core.testing, "stream_triad"):
        for t in (1, 2):
            out[f"core_{t}"] = _core.testing.stream_triad(40_000_000, 5, t)
    if hasattr(_core.testing, "stream_read"):
        for t in (1, 2):
            out[f"core_read_{t}"] = _core.testing.stream_read(40_000_000, 5, t, 4)
        out["core_read1_1"] = _core.testing.stream_read(40_000_000, 5, 1, 1)
        out["core_blocks_1"] = _core.testing.stream_read_blocks(9_000_000, 5, 1, 2)
        out["core_blocks3_1"] = _core.testing.stream_read_blocks(4_000_000, 5, 1, 3)
    return out


def references(stream: dict, t: int) -> dict:
    """The rates (GB/s) a cycle on t threads is set against: the core triad as counted (24 bytes an
    entry) and with its write-allocate bytes (32), numpy's triad, the core's 4- and 1-piece reads,
    its matrix-like read and numpy's sum (one-thread figures where no t-thread one is measured)."""
    ref = {"core triad": stream.get(f"core_{t}"), "numpy triad": stream.get("numpy_1")}
    if ref["core triad"]:
        ref["core triad + write-allocate"] = ref["core triad"] * 32 / 24
    ref["core read, 4 pieces"] = stream.get(f"core_read_{t}")
    ref["core read, 1 piece"] = stream.get("core_read1_1")
    ref["core 2x2 blocks + int32"] = stream.get("core_blocks_1")
    ref["core 3x3 blocks + int32"] = stream.get("core_blocks3_1")
    ref["numpy sum"] = stream.get("numpy_read_1")
    return {k: v for k, v in ref.items() if v}


# The configurations of a level: (label, storage order of the core solver, ordering of the sweeps)
CONFIGS = (("lexicographic", "lexicographic", "lexicographic"),
           ("coloured, user order", "lexicographic", "coloured"),  # issue 15 before renumbering
           ("coloured, by colours", "coloured", "coloured"))


def matrix_bytes(m) -> int:
    return m.memory_bytes()


def transfer_bytes(t, d: int) -> int:
    # the core holds a prolongation as scalar weights with 32-bit columns and 64-bit row pointers
    # (mg/prolongation.hpp; the rotations of the few contact rows left out)
    return len(t.parent) * (8 + 4) + 8 * (t.n_fine + 1)


def coarse_visits(top: int, cycle: str) -> tuple:
    """How often a coarse correction (mg/cycle.hpp, CoarseCycle::correction and ::cycle) smooths
    each coarse level 0 .. top (nu1 + nu2 sweeps a visit; level 0 is solved instead) and forms its
    residual, restricts it and prolongates back (levels 1 .. top). A W- or F-cycle visits level top
    a second time from the fine level (a V- or W-cycle), and each visit of a level of a W/F-cycle
    visits the next coarser level twice (F: an F- then a V-cycle). F-cycle of top 7: level 7
    smoothed 2 times, level l top - l + 2 times."""
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


def cycle_bytes(p, S) -> dict:
    """Bytes a cycle must read once per sweep and product on every level (a model of the passes,
    not a measurement): a sweep reads the matrix, the inverted diagonal blocks, the iterate and the
    right-hand side and writes the iterate; a product reads the matrix and x and writes y; a
    restriction and a prolongation read the prolongation and both vectors. Each coarse level as
    often as coarse_visits counts it. Until stop 23 the model took an F-cycle's level l as smoothed
    top - l + 1 and restricted top - l + 2 times, one visit short on every level (the second visit
    of level top from the fine level, issue 10): "coarse_stop23" / "total_stop23" keep that count."""
    d = p.mesh.dim
    opt = p.default_cycle
    nu = opt.nu1 + opt.nu2
    levels = S.num_levels - 1  # coarse levels 0 .. levels - 1
    top = levels - 1
    fine_n = p.mesh.num_points
    A = matrix_bytes(_core.testing.fine_matrix(S))
    vec = lambda n: 8 * d * n
    # coarse sweeps read stored inverted diagonal blocks; the fine one forms them from the diagonal
    # block (its position is in the matrix's bytes)
    sweep = lambda M, n: M + 8 * d * d * n + 3 * vec(n)
    fine_sweep = lambda M, n: M + 3 * vec(n)
    prod = lambda M, n: M + 2 * vec(n)
    fine = nu * fine_sweep(A, fine_n) + 2 * prod(A, fine_n)
    T = p.hierarchy.transfers
    fine_transfer = transfer_bytes(T[-1], d) + vec(T[-1].n_fine) + vec(T[-1].n_coarse)
    fine += 2 * fine_transfer
    smooth, resid = coarse_visits(top, opt.cycle) if top >= 0 else ([], [])
    coarse = coarse_stop23 = 0
    for l in range(1, levels):
        n = T[l - 1].n_fine  # T[l - 1] prolongs level l - 1 to level l
        M = matrix_bytes(_core.testing.coarse_matrix(S, l))
        tb = transfer_bytes(T[l - 1], d) + vec(T[l - 1].n_fine) + vec(T[l - 1].n_coarse)
        coarse += smooth[l] * nu * sweep(M, n) + resid[l] * (prod(M, n) + 2 * tb)
        smooth23 = (top - l + 1) if opt.cycle == "F" else 1
        restrict23 = (top - l + 2) if opt.cycle == "F" else 1
        coarse_stop23 += smooth23 * nu * sweep(M, n) + restrict23 * (prod(M, n) + 2 * tb)
    return {"fine": fine, "coarse": coarse, "total": fine + coarse, "sweep": fine_sweep(A, fine_n),
            "coarse_stop23": coarse_stop23, "total_stop23": fine + coarse_stop23}


def time_level(make, label, repeats, threads, stream):
    problems = {}
    for name, storage, ordering in CONFIGS:
        p = make()
        p.default_ordering = storage
        p.solver  # built now, outside the timings
        problems[name] = (p, ordering)
    rows = {}
    for rep in range(repeats):  # interleaved: the machine is shared
        for name, (p, ordering) in problems.items():
            for t in threads:
                if name == "coloured, user order" and t != 1:
                    continue
                r = p.solve("nmg", ordering=ordering, threads=t)
                rows.setdefault((name, t), []).append(r)
    out = []
    for (name, t), rs in rows.items():
        p, _ = problems[name]
        S = p.solver
        d, n = p.mesh.dim, p.mesh.num_points
        nu = p.default_cycle.nu1 + p.default_cycle.nu2
        b = cycle_bytes(p, S)
        spc = float(np.median([r.solve_seconds / r.cycles for r in rs]))
        sweeps = float(np.median([(r.phase_seconds["presmooth"] + r.phase_seconds["postsmooth"]) / (nu * r.cycles) for r in rs]))
        rate = stream.get(f"core_{t}", stream["numpy_1"]) * 1e9
        # where a cycle's time goes: the step's phases (norm: the Anderson mixing and the fused
        # A (u - u_old) pass; linearize: the contact linearization with the contact rows' residual -- the
        # fine residual's other rows are formed in the coarse correction's restriction since perf6) and the
        # rest of the loop (the energy record, the step's setup), ms per cycle, medians
        phases = {k: 1e3 * float(np.median([r.phase_seconds.get(k, 0.0) / r.cycles for r in rs]))
                  for k in ("presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check")}
        phases["other"] = 1e3 * spc - sum(phases.values())
        out.append(dict(case=label, dofs=d * n, config=name, renumbered=bool(getattr(S, "renumbered", False)), threads=t,
                        cycles=rs[0].cycles, seconds_per_cycle=spc, seconds_per_fine_sweep=sweeps,
                        sweep_bytes=b["sweep"], sweep_gbs=b["sweep"] / sweeps / 1e9, cycle_bytes=b["total"],
                        cycle_gbs=b["total"] / spc / 1e9, stream_gbs=rate / 1e9, cycle_over_stream=spc / (b["total"] / rate),
                        cycle_bytes_stop23=b["total_stop23"], cycle_over_stream_stop23=spc / (b["total_stop23"] / rate),
                        coarse_bytes=b["coarse"], fine_bytes=b["fine"],
                        cycle_over_reference={k: spc / (b["total"] / (v * 1e9)) for k, v in references(stream, t).items()},
                        converged=all(r.converged for r in rs), load=load(), phase_ms=phases))
        print(json.dumps(out[-1]), flush=True)
    base = {(r["config"], r["threads"]): r["seconds_per_cycle"] for r in out}
    for r in out:
        r["speedup_vs_lex_1"] = base[("lexicographic", 1)] / r["seconds_per_cycle"]
    return out


def table(res) -> str:
    s = res["stream"]
    lines = [f"stream triad GB/s: core 1 thread {s.get('core_1', float('nan')):.1f}, 2 threads {s.get('core_2', float('nan')):.1f}, "
             f"numpy 1 thread {s['numpy_1']:.1f}; after: {res['stream_after'].get('core_1', float('nan')):.1f} / "
             f"{res['stream_after'].get('core_2', float('nan')):.1f}; load average {res['load_before']} -> {res['load_after']}", "",
             "| case | dofs | config | threads | cycles | s/cycle | vs lex 1 thr | s/fine sweep | sweep GB/s | cycle MB | cycle GB/s | cycle / stream time | load |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in res["rows"]:
        lines.append(f"| {r['case']} | {r['dofs']:,} | {r['config']} | {r['threads']} | {r['cycles']} | {r['seconds_per_cycle']:.3f} | "
                     f"{r['speedup_vs_lex_1']:.2f}x | {r['seconds_per_fine_sweep']:.4f} | {r['sweep_gbs']:.2f} | "
                     f"{r['cycle_bytes'] / 1e6:.0f} | {r['cycle_gbs']:.2f} | {r['cycle_over_stream']:.2f} | {r['load']} |")
    # issue 15's figures: the default storage (by colours) on 1 and 2 threads
    lines += ["", "Issue 15 targets, coloured stored by colours (2 thr / 1 thr >= 1.6x; cycle / stream time <= 1.5 on 1 thread):", "",
              "| case | dofs | cycles | s/cycle 1 thr | s/cycle 2 thr | 2 thr / 1 thr | cycle / stream time 1 thr | 2 thr |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    by = {(r["case"], r["threads"]): r for r in res["rows"] if r["config"] == "coloured, by colours"}
    for case in dict.fromkeys(r["case"] for r in res["rows"]):
        a, b = by.get((case, 1)), by.get((case, 2))
        if a and b:
            lines.append(f"| {case} | {a['dofs']:,} | {a['cycles']} | {a['seconds_per_cycle']:.3f} | {b['seconds_per_cycle']:.3f} | "
                         f"{a['seconds_per_cycle'] / b['seconds_per_cycle']:.2f}x | {a['cycle_over_stream']:.2f} | {b['cycle_over_stream']:.2f} |")
    # the same cycles against every reference (issue 15: the cycle mostly reads; no one figure is "the" bandwidth)
    refs = list(dict.fromkeys(k for r in res["rows"] for k in r.get("cycle_over_reference", {})))
    rates = references(s, 1)
    lines += ["", "Cycle / stream time, coloured by colours, 1 thread, against each reference (GB/s of the run in the header; "
              "model bytes: every visit of coarse_visits; the stop-23 model in the last column, at the core triad):", "",
              "| case | model GB / cycle | " + " | ".join(f"{k} ({rates.get(k, float('nan')):.1f})" for k in refs) +
              " | stop-23 model, core triad |",
              "| --- | --- | " + " | ".join("---" for _ in refs) + " | --- |"]
    for case in dict.fromkeys(r["case"] for r in res["rows"]):
        a = by.get((case, 1))
        if a and "cycle_over_reference" in a:
            lines.append(f"| {case} | {a['cycle_bytes'] / 1e9:.2f} (stop 23: {a['cycle_bytes_stop23'] / 1e9:.2f}) | " +
                         " | ".join(f"{a['cycle_over_reference'].get(k, float('nan')):.2f}" for k in refs) +
                         f" | {a['cycle_over_stream_stop23']:.2f} |")
    lines += ["", "Where a cycle's time goes (ms per cycle; fine sweeps = presmooth + postsmooth; norm = Anderson mixing + the fused "
              "A (u - u_old) pass; linearize: the contact rows' residual and linearization, the fine residual's other rows in the coarse "
              "correction (before perf6: in linearize); other = the loop's energy record and the step's setup):", "",
              "| case | config | threads | presmooth | postsmooth | linearize | coarse update | coarse correction | norm | check | other |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in res["rows"]:
        ph = r.get("phase_ms", {})
        lines.append(f"| {r['case']} | {r['config']} | {r['threads']} | " +
                     " | ".join(f"{ph.get(k, float('nan')):.1f}" for k in
                                ("presmooth", "postsmooth", "linearize", "coarse_update", "coarse_correction", "norm", "check", "other")) + " |")
    return "\n".join(lines)


def cmd_time(args):
    from contactmg.hertz import hertz_problem
    from contactmg.sphere import sphere_problem
    res = {"stream": stream_rates(), "load_before": load(), "rows": []}
    print("stream GB/s:", {k: round(v, 2) for k, v in res["stream"].items()}, "load", load(), flush=True)
    threads = (1, 2)
    for lev in args.levels:
        res["rows"] += time_level(lambda: hertz_problem("triangle", lev, 0.4), f"hertz-2d-L{lev}", args.repeats, threads, res["stream"])
    for lev in args.levels3d:
        res["rows"] += time_level(lambda: sphere_problem(levels=lev, friction=0.4), f"sphere-3d-L{lev}", args.repeats, threads,
                                  res["stream"])
    res["stream_after"] = stream_rates()
    res["load_after"] = load()
    print()
    print(table(res))
    return res


def cmd_counts(args):
    from contactmg.hertz import hertz_problem
    rows = []
    for lev in args.levels:
        for F in (0.4, 5.0) if not args.f else args.f:
            row = {"level": lev, "F": F}
            for o in ("lexicographic", "coloured"):
                p = hertz_problem("triangle", lev, F)
                p.default_ordering = o
                r = p.solve("nmg", ordering=o)
                row[o] = r.cycles if r.converged else f"not converged: {r.status}"
            print(json.dumps(row), flush=True)
            rows.append(row)
    return {"rows": rows}


MEMORY_WORKER = r'''
import json, resource, sys, gc
import numpy as np
def status(key):  # VmRSS (now) or VmHWM (peak so far) in bytes
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
stages = {}
def stage(name):
    stages[name] = {"rss": status("VmRSS"), "peak": status("VmHWM")}
dim, level, cell = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
if len(sys.argv) > 4 and sys.argv[4] == "float-coarse":
    from contactmg import _core
    _core._float_coarse_values(True)
stage("imports")
if dim == 2:
    from contactmg.hertz import hertz_problem
    p = hertz_problem(cell, level, 0.4)
else:
    from contactmg.sphere import sphere_problem
    p = sphere_problem(cell, levels=level, friction=0.4)
p.release_hierarchy = True  # as the command line's single solves (cli.release_after_build)
stage("problem")
p.solver
stage("core solver")
r = p.solve("nmg")
stage("solve")
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
d, n = p.mesh.dim, p.mesh.num_points
S = p.solver
nb = lambda *arrs: int(sum(a.nbytes for a in arrs if isinstance(a, np.ndarray)))
own = p.memory_bytes()  # by owner, nothing made again (a released hierarchy stays released)
fine = _core.testing.fine_matrix(S).memory_bytes()
coarse = sum(_core.testing.coarse_matrix(S, l).memory_bytes() for l in range(S.num_levels - 1))
core = S.memory_bytes()
results = nb(r.displacement, r.contact_force, r.friction_bound, r.node_state) + sum(v.nbytes for v in r.history.values())
print(json.dumps(dict(dim=dim, level=level, cell=cell, dofs=d * n, cycles=r.cycles, converged=r.converged, peak_rss_bytes=peak,
                      peak_bytes_per_dof=peak / (d * n), fine_matrix=fine, coarse_matrices=coarse,
                      core_total=core, core_transfers_vectors_dinv=core - fine - coarse, python_matrix_copy=own["python_matrix"],
                      mesh_hierarchy_python=own["mesh_hierarchy"], transfers_python=own["transfers"],
                      problem_vectors_python=own["problem_vectors"], hierarchy_released=p.hierarchy.released,
                      results=results, stages=stages)))
'''


# the CLI with the process-wide switch _core._float_coarse_values on (memory --float-coarse)
CLI_FLOAT_COARSE = ("from contactmg import _core; _core._float_coarse_values(True); import runpy; "
                    "runpy.run_module('contactmg', run_name='__main__')")


def cli_peak_rss(dim: int, level: int, cell: str, float_coarse: bool = False) -> int:
    """Peak resident bytes of the CLI solve itself (`contactmg hertz --levels L` / `sphere --cell C`)
    in a fresh process."""
    cmd = ([sys.executable, "-c", CLI_FLOAT_COARSE] if float_coarse else [sys.executable, "-m", "contactmg"]) + (["hertz", "--cell", cell, "--levels", str(level), "--friction", "0.4"] if dim == 2 else
                                                 ["sphere", "--cell", cell, "--levels", str(level)]) + ["--json", "-", "-q"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # ru_maxrss of children is the largest of any child so far: run this first
    return max(peak, before) * 1024


def cmd_memory(args):
    cell = args.cell or ("triangle" if args.dim == 2 else "hexahedron")
    cli = cli_peak_rss(args.dim, args.level, cell, args.float_coarse)
    out = subprocess.run([sys.executable, "-c", MEMORY_WORKER, str(args.dim), str(args.level), cell] +
                         (["float-coarse"] if args.float_coarse else []), capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["cli_peak_rss_bytes"] = cli
    res["cli_peak_bytes_per_dof"] = cli / res["dofs"]
    dofs = res["dofs"]
    for k, v in res.items():
        if isinstance(v, int) and not isinstance(v, bool) and k not in ("dim", "level", "dofs", "cycles"):
            print(f"{k:32s} {v / 2**20:9.1f} MiB {v / dofs:7.1f} B/dof")
    for name, st in res["stages"].items():
        print(f"after {name:24s} rss {st['rss'] / 2**20:9.1f} MiB  peak so far {st['peak'] / 2**20:9.1f} MiB "
              f"({st['peak'] / dofs:6.1f} B/dof)")
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
    m.add_argument("--cell", default=None, help="triangle (2D default), quad; hexahedron (3D default), tetra")
    for s in (t, c, m):
        s.add_argument("--json")
        s.add_argument("--float-coarse", action="store_true",
                       help="with the switch _core._float_coarse_values on (coarse values read as float; CLI and worker too)")
    args = ap.parse_args()
    if args.float_coarse and args.cmd != "memory":
        from contactmg import _core
        _core._float_coarse_values(True)
    res = {"time": cmd_time, "counts": cmd_counts, "memory": cmd_memory}[args.cmd](args)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
