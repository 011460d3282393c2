"""The cork pushed into a bottle neck (3D, a revolution obstacle with rotated contact frames) over
levels: dofs, Algorithm 2 and TNNMG cycles, push force, contact / stick / slip nodes for F = 0 and
0.4, the cycles of the linear solve with the final contact state known and the nmg/linear time
ratio (F = 0.4), solve seconds and peak memory; one level per fresh process.

    python benchmarks/three_d/cork.py [--levels 2 4] [--layers 8] [--quick] [--json PATH]
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, run_child, write_result  # noqa: E402

CHILD = r"""
import json, resource, sys, time
from contactmg.examples import cork
L, layers = int(sys.argv[1]), int(sys.argv[2])
out = {"level": L}
for F in (0.0, 0.4):
    t0 = time.perf_counter()
    p = cork.cork_problem(L, F, axial_layers=layers or None)
    p.solver.core
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
    ap = parser(__doc__)
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 4])
    ap.add_argument("--layers", type=int, default=0, help="axial layers of the coarse mesh (0: the shipped one)")
    a = ap.parse_args()
    if a.quick:
        a.levels = [1, 2]
    rows = []
    print(f"{'lvl':>3} {'dofs':>8} {'cyc F=0':>7} {'cyc .4':>6} {'push F=0':>9} {'push .4':>8} {'stick':>6} {'slip':>5} "
          f"{'lin cyc':>7} {'tnnmg F=0/.4':>12} {'nmg/lin':>7} {'solve s':>8} {'peak MB':>8}")
    for L in range(a.levels[0], a.levels[1] + 1):
        r = run_child(CHILD, L, a.layers)
        if "error" in r:
            print(f"{L:3d} failed: {r['error']}")
            break
        rows.append(r)
        f0, f4 = r["F0.0"], r["F0.4"]
        c = lambda f: f["cycles"] if f["converged"] else "-"  # noqa: E731
        print(f"{L:3d} {r['dofs']:8d} {c(f0):>7} {c(f4):>6} {f0['push_force']:9.3f} {f4['push_force']:8.3f} "
              f"{f4['stick_nodes']:6d} {f4['slip_nodes']:5d} {r['linear_cycles']:7d} "
              f"{str(f0['tnnmg_cycles']) + '/' + str(f4['tnnmg_cycles']):>12} {r['nmg_over_linear']:7.2f} "
              f"{f0['solve_seconds'] + f4['solve_seconds']:8.2f} {r['peak_rss_mb']:8.0f}", flush=True)
    write_result(__file__, a, {"layers": a.layers or None, "rows": rows})


if __name__ == "__main__":
    main()
