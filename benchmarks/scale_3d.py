"""Issue-10 scale run: the largest 3D Hertz sphere levels that fit in memory (24 GB, 2 cores). One
(cell, level) per fresh process so that the peak RSS is that level's: dofs, hierarchy + assembly +
core-solver setup seconds, nmg solve seconds and cycles for F = 0.4 (tol 1e-11 absolute on
||u^{k+1} - u^k||_A), the linear solve with that contact state known in advance (the cost
reference), the frictionless solve against Hertz (optional), peak RSS and bytes per dof. The child
writes what it has measured after each stage (setup, nmg, linear, done) to <json>.<cell><level>.partial.

    python benchmarks/scale_3d.py --runs hexahedron:5 tetra:4 [--frictionless] [--threads 0]
                                  [--json benchmarks/results/scale_3d.json]
"""
import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys, time
from contactmg import sphere
from contactmg.results import STICK, SLIP
cell, L, threads, frictionless, partial = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "1", sys.argv[5]
rss = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # noqa: E731
out = {"cell": cell, "level": L, "threads": threads}
def stage(name):  # what is measured so far, for a run that is stopped before its end
    out["stage"] = name
    out["peak_rss_mb"] = rss()
    if "dofs" in out:
        out["bytes_per_dof"] = out["peak_rss_mb"] * 2**20 / out["dofs"]
    with open(partial, "w") as fh:
        json.dump(out, fh)
t0 = time.perf_counter()
p = sphere.sphere_problem(cell, L, 0.4, memory_fraction=2.0)  # the estimate (14 kB a node) is 1.6x the hexahedra's measured need: this run measures it
out["hierarchy_assembly_seconds"] = time.perf_counter() - t0
p.solver
out["setup_seconds"] = time.perf_counter() - t0
out["nodes"], out["dofs"] = p.mesh.num_points, 3 * p.mesh.num_points
out["rss_after_setup_mb"] = rss()
stage("setup")
res = p.solve(tol=1e-11, max_cycles=200, threads=threads)
out.update(cycles=res.cycles, converged=res.converged, solve_seconds=res.solve_seconds, **res.counts())
out["rss_after_nmg_mb"] = rss()
stage("nmg")
lin = p.solve("linear", tol=1e-11, reference=res, threads=threads)
out.update(linear_cycles=lin.cycles, linear_seconds=lin.solve_seconds, nmg_over_linear=res.solve_seconds / lin.solve_seconds)
stage("linear")
del lin, res
if frictionless:
    del p
    q = sphere.sphere_problem(cell, L, 0.0, memory_fraction=2.0)
    r0 = q.solve(tol=1e-11, max_cycles=200, threads=threads)
    P = float(r0.reaction[2])
    out.update(frictionless_cycles=r0.cycles, frictionless_converged=r0.converged, load=P,
               hertz_p0_error=sphere.central_pressure(r0) / sphere.hertz_p0(P) - 1,
               hertz_radius_error=sphere.radius_of(r0, (STICK, SLIP)) / sphere.hertz_radius(P) - 1,
               h_over_a=sphere.element_width(L) / sphere.hertz_radius(P))
stage("done")
print(json.dumps(out))
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", nargs="+", default=["hexahedron:5", "tetra:4"], help="cell:level")
    ap.add_argument("--threads", type=int, default=0, help="0: all cores")
    ap.add_argument("--frictionless", action="store_true", help="also the F = 0 solve against Hertz")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    print(f"{'cell':>10} {'lvl':>3} {'dofs':>9} {'setup s':>8} {'cycles':>6} {'solve s':>8} {'lin cyc':>7} "
          f"{'lin s':>7} {'nmg/lin':>7} {'peak MB':>8} {'B/dof':>6} {'p0 err':>7} {'a err':>7}")
    for run in a.runs:
        cell, L = run.split(":")
        partial = f"{a.json or 'scale_3d.json'}.{cell}{L}.partial"
        r = subprocess.run([sys.executable, "-c", CHILD, cell, L, str(a.threads), "1" if a.frictionless else "0", partial],
                           capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{cell:>10} {L:>3} failed: {r.stderr.strip().splitlines()[-1] if r.stderr else r.returncode} "
                  f"(what it measured before: {partial})", flush=True)
            rows.append({"cell": cell, "level": int(L), "failed": r.stderr.strip()[-2000:]})
            continue
        r = json.loads(r.stdout.strip().splitlines()[-1])
        rows.append(r)
        hz = (f"{100 * r['hertz_p0_error']:6.1f}% {100 * r['hertz_radius_error']:6.1f}%" if "hertz_p0_error" in r
              else f"{'-':>7} {'-':>7}")
        print(f"{cell:>10} {r['level']:3d} {r['dofs']:9d} {r['setup_seconds']:8.1f} "
              f"{r['cycles'] if r['converged'] else '-':>6} {r['solve_seconds']:8.1f} {r['linear_cycles']:7d} "
              f"{r['linear_seconds']:7.1f} {r['nmg_over_linear']:7.2f} {r['peak_rss_mb']:8.0f} "
              f"{r['bytes_per_dof']:6.0f} {hz}", flush=True)
        if a.json:  # after every run: a long run that is stopped keeps what it measured
            with open(a.json, "w") as fh:
                json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
