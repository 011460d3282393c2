"""The Hertz sphere (a half ball pressed onto a plane) over levels, for tetrahedra and hexahedra on
uniform hierarchies and tetrahedra on the adaptive one: dofs, Algorithm 2 cycles for several
friction coefficients (tol 1e-11 on ||u^{k+1} - u^k||_A, absolute), the nmg/linear time ratio
(F = 0.4: the linear solve with the final contact state known in advance), setup and solve
seconds, peak memory and bytes per dof, and the frictionless solve against Hertz (central pressure
against p0, contact radius against a, for the computed load). One (cell, level) per fresh process,
so that the peak memory is that level's; the largest levels that fit show how far the solver scales.

    python benchmarks/three_d/sphere.py [--levels 2 4] [--cells hexahedron tetra] [--max-tetra-level 3]
        [--adaptive-levels 3 5] [--frictions 0 0.4 2 40] [--quick] [--json PATH]
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, run_child, write_result  # noqa: E402

CHILD = r"""
import json, resource, sys, time
from contactmg.examples import sphere
from contactmg.results.result import STICK, SLIP
L, cell, kind = int(sys.argv[1]), sys.argv[2], sys.argv[3]
frictions = [float(f) for f in sys.argv[4].split(",")]
out = {"level": L, "cell": cell, "hierarchy": kind, "cycles": {}, "solve_seconds": {}, "converged": {}}
h = None
if kind == "adaptive":
    h = sphere.sphere_adaptive_hierarchy(L, 0.4, cell=cell)
for F in frictions:
    t0 = time.perf_counter()
    p = sphere.sphere_problem(cell, L, F, hierarchy=h if h is not None else "uniform")
    p.solver.core
    out["setup_seconds"] = time.perf_counter() - t0
    res = p.solve(tol=1e-11, max_cycles=200)
    out["nodes"], out["dofs"] = p.mesh.num_points, 3 * p.mesh.num_points
    out["cycles"][F], out["solve_seconds"][F], out["converged"][F] = res.cycles, res.solve_seconds, res.converged
    if F == 0.0:
        P = float(res.reaction[2])
        out["hertz_p0_error"] = sphere.central_pressure(res) / sphere.hertz_p0(P) - 1
        out["hertz_radius_error"] = sphere.radius_of(res, (STICK, SLIP)) / sphere.hertz_radius(P) - 1
    if F == 0.4:
        lin = p.solve("linear", tol=1e-11, reference=res)
        out["linear_cycles"], out["linear_seconds"] = lin.cycles, lin.solve_seconds
        out["nmg_over_linear"] = res.solve_seconds / lin.solve_seconds
    del p, res
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
out["bytes_per_dof"] = out["peak_rss_mb"] * 2**20 / out["dofs"]
print(json.dumps(out))
"""


def main():
    ap = parser(__doc__)
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 4], help="uniform levels (first last)")
    ap.add_argument("--cells", nargs="+", default=["hexahedron", "tetra"])
    ap.add_argument("--max-tetra-level", type=int, default=3, help="uniform tetra levels are about twice as large")
    ap.add_argument("--adaptive-levels", type=int, nargs=2, default=[3, 5], help="adaptive tetra levels; 0 0: none")
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.0, 0.4, 2.0, 40.0])
    a = ap.parse_args()
    if a.quick:
        a.levels, a.max_tetra_level, a.adaptive_levels, a.frictions = [1, 2], 1, [2, 2], [0.0, 0.4]
    runs = [("uniform", c, L) for c in a.cells
            for L in range(a.levels[0], (min(a.levels[1], a.max_tetra_level) if c == "tetra" else a.levels[1]) + 1)]
    if a.adaptive_levels[1] > 0:
        runs += [("adaptive", "tetra", L) for L in range(a.adaptive_levels[0], a.adaptive_levels[1] + 1)]
    print(f"{'hier':>8} {'cell':>10} {'lvl':>3} {'dofs':>9} " + " ".join(f"{'F=' + format(f, 'g'):>6}" for f in a.frictions)
          + f" {'nmg/lin':>7} {'setup s':>7} {'solve s':>8} {'peak MB':>8} {'p0 err':>7} {'a err':>7}")
    rows, fs = [], ",".join(str(f) for f in a.frictions)
    for kind, cell, L in runs:
        r = run_child(CHILD, L, cell, kind, fs)
        if "error" in r:
            print(f"{kind:>8} {cell:>10} {L:3d} failed: {r['error']}")
            continue
        rows.append(r)
        cyc = " ".join(f"{r['cycles'][str(f)] if r['converged'][str(f)] else '-':>6}" for f in a.frictions)
        ratio = f"{r['nmg_over_linear']:7.2f}" if "nmg_over_linear" in r else f"{'':7}"
        pe = f"{100 * r['hertz_p0_error']:6.1f}% {100 * r['hertz_radius_error']:6.1f}%" if "hertz_p0_error" in r else ""
        print(f"{kind:>8} {cell:>10} {L:3d} {r['dofs']:9d} {cyc} {ratio} {r['setup_seconds']:7.2f} "
              f"{sum(r['solve_seconds'].values()):8.2f} {r['peak_rss_mb']:8.0f} {pe}", flush=True)
    write_result(__file__, a, {"frictions": a.frictions, "rows": rows})


if __name__ == "__main__":
    main()
