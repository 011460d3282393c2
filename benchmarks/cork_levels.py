"""Issue-10 table for the cork in the bottle neck: level, dofs, cycles, push force, contact/stick/slip
nodes for F = 0 and 0.4, the linear cycles with the contact state known (F = 0.4), the TNNMG cycles
(F = 0 and 0.4), nmg/linear time ratio (F = 0.4), seconds, peak RSS; one level per fresh process.

    python benchmarks/cork_levels.py --levels 2 4 [--layers 8] [--json out/cork_levels.json]
"""
import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys, time
from contactmg import cork
L, layers = int(sys.argv[1]), int(sys.argv[2])
out = {"level": L}
for F in (0.0, 0.4):
    t0 = time.perf_counter()
    p = cork.cork_problem(L, F, axial_layers=layers)
    p.solver
    out["setup_seconds"] = time.perf_counter() - t0
    res = p.solve(tol=1e-11)
    out["nodes"], out["dofs"] = p.mesh.num_points, 3 * p.mesh.num_points
    out[f"F{F}"] = dict(cycles=res.cycles, converged=res.converged, push_force=cork.push_force(p, res),
                        solve_seconds=res.solve_seconds, **res.counts())
    tn = p.solve("tnnmg", tol=1e-11)
    out[f"F{F}"].update(tnnmg_cycles=tn.cycles, tnnmg_converged=tn.converged, tnnmg_seconds=tn.solve_seconds)
    if F == 0.4:
        lin = p.solve("linear", tol=1e-11, reference=res)
        out["nmg_over_linear"] = res.solve_seconds / lin.solve_seconds
        out["linear_cycles"] = lin.cycles
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 4])
    ap.add_argument("--layers", type=int, default=None, help="axial layers of the coarse mesh (default: the shipped one)")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    print(f"{'lvl':>3} {'dofs':>8} {'cyc F=0':>7} {'cyc .4':>6} {'push F=0':>9} {'push .4':>8} {'stick':>6} {'slip':>5} "
          f"{'lin cyc':>7} {'tnnmg F=0/.4':>12} {'nmg/lin':>7} {'solve s':>8} {'peak MB':>8}")
    for L in range(a.levels[0], a.levels[1] + 1):
        r = subprocess.run([sys.executable, "-c", CHILD, str(L), str(a.layers or 0)], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{L:3d} failed: {r.stderr.strip().splitlines()[-1] if r.stderr else r.returncode}")
            break
        r = json.loads(r.stdout.strip().splitlines()[-1])
        rows.append(r)
        f0, f4 = r["F0.0"], r["F0.4"]
        c = lambda f: f["cycles"] if f["converged"] else "-"  # noqa: E731
        print(f"{L:3d} {r['dofs']:8d} {c(f0):>7} {c(f4):>6} {f0['push_force']:9.3f} {f4['push_force']:8.3f} "
              f"{f4['stick_nodes']:6d} {f4['slip_nodes']:5d} {r['linear_cycles']:7d} "
              f"{str(f0['tnnmg_cycles']) + '/' + str(f4['tnnmg_cycles']):>12} {r['nmg_over_linear']:7.2f} "
              f"{f0['solve_seconds'] + f4['solve_seconds']:8.2f} {r['peak_rss_mb']:8.0f}", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
