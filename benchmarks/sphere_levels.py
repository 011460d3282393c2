"""Issue-10 table: the Hertz sphere (half ball on a plane, 3D) over levels, for tetrahedra and
hexahedra, one (cell, level) per fresh process so that peak memory is per level: dofs, cycles for
F in {0, 0.4, 2, 40} (tol 1e-11 on ||u^{k+1} - u^k||_A, absolute), the nmg/linear time ratio
(F = 0.4: the linear solve with the final contact state known in advance, same process), seconds,
peak RSS, and the frictionless solve against Hertz (peak pressure at the bottom node against p0,
contact radius against a, for the computed load).

    python benchmarks/sphere_levels.py --levels 2 4 [--cells tetra hexahedron] [--json out/sphere_levels.json]
"""
import argparse
import json
import subprocess
import sys

FRICTIONS = (0.0, 0.4, 2.0, 40.0)

CHILD = r"""
import json, resource, sys, time
from contactmg import sphere
from contactmg.results import STICK, SLIP
L, cell = int(sys.argv[1]), sys.argv[2]
frictions = [float(f) for f in sys.argv[3].split(",")]
out = {"level": L, "cell": cell, "cycles": {}, "solve_seconds": {}, "converged": {}}
for F in frictions:
    t0 = time.perf_counter()
    p = sphere.sphere_problem(cell, L, F)
    p.solver
    setup = time.perf_counter() - t0
    res = p.solve(tol=1e-11, max_cycles=200)
    out["nodes"], out["dofs"] = p.mesh.num_points, 3 * p.mesh.num_points
    out["setup_seconds"] = setup
    out["cycles"][F], out["solve_seconds"][F], out["converged"][F] = res.cycles, res.solve_seconds, res.converged
    if F == 0.0:
        P = float(res.reaction[2])
        out["hertz_p0_error"] = sphere.central_pressure(res) / sphere.hertz_p0(P) - 1
        out["hertz_radius_error"] = sphere.radius_of(res, (STICK, SLIP)) / sphere.hertz_radius(P) - 1
        out["h_over_a"] = sphere.element_width(L) / sphere.hertz_radius(P)
    if F == 0.4:
        lin = p.solve("linear", tol=1e-11, reference=res)
        out["linear_cycles"], out["linear_seconds"] = lin.cycles, lin.solve_seconds
        out["nmg_over_linear"] = res.solve_seconds / lin.solve_seconds
    del p, res
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 4])
    ap.add_argument("--cells", nargs="+", default=["hexahedron", "tetra"])
    ap.add_argument("--max-tetra-level", type=int, default=3, help="tetra levels are twice as large")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    fs = ",".join(str(f) for f in FRICTIONS)
    head = (f"{'cell':>10} {'lvl':>3} {'dofs':>9} " + " ".join(f"{'F=' + str(f):>6}" for f in FRICTIONS)
            + f" {'nmg/lin':>7} {'setup s':>7} {'solve s':>8} {'peak MB':>8} {'p0 err':>7} {'a err':>7} {'h/a':>5}")
    print(head)
    for cell in a.cells:
        for L in range(a.levels[0], (min(a.levels[1], a.max_tetra_level) if cell == "tetra" else a.levels[1]) + 1):
            r = subprocess.run([sys.executable, "-c", CHILD, str(L), cell, fs], capture_output=True, text=True)
            if r.returncode != 0:
                print(f"{cell:>10} {L:3d} failed: {r.stderr.strip().splitlines()[-1] if r.stderr else r.returncode}")
                break
            r = json.loads(r.stdout.strip().splitlines()[-1])
            rows.append(r)
            cyc = " ".join(f"{r['cycles'][str(f)] if r['converged'][str(f)] else '-':>6}" for f in FRICTIONS)
            print(f"{cell:>10} {L:3d} {r['dofs']:9d} {cyc} {r['nmg_over_linear']:7.2f} {r['setup_seconds']:7.2f} "
                  f"{sum(r['solve_seconds'].values()):8.2f} {r['peak_rss_mb']:8.0f} {100 * r['hertz_p0_error']:6.1f}% "
                  f"{100 * r['hertz_radius_error']:6.1f}% {r['h_over_a']:5.2f}", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
