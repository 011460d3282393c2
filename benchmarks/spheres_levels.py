"""Issue-13 (3D) table: two elastic hemispheres pressed together through the 3D dual mortar
(`contactmg spheres`), over levels, one level per fresh process (peak memory per level): dofs,
nonmortar nodes, nmg cycles for F in {0, 0.4, 2} (tol 1e-11 on ||w^{k+1} - w^k||_A, absolute), the
asymptotic contraction of the last cycles, the cycles of the linear solve with the final contact state
known (F = 0.4), the largest violation of the independent check, setup and solve seconds (one
thread), and the frictionless solve against the two-body Hertz formulas (central pressure against
p0, contact radius against a). Equal materials (E2 = E1) and unequal ones (E2 = 2 E1, nu2 = 0.2).

    python benchmarks/spheres_levels.py --levels 2 3 [--json out/spheres_levels.json]
"""
import argparse
import json
import subprocess
import sys

FRICTIONS = (0.0, 0.4, 2.0)
MATERIALS = ((2000.0, 0.28), (4000.0, 0.2))

CHILD = r"""
import json, resource, sys, time
import numpy as np
from contactmg import spheres
from contactmg.sphere import central_pressure, radius_of
from contactmg.results import STICK, SLIP
L, E2, nu2 = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
frictions = [float(f) for f in sys.argv[4].split(",")]
out = {"level": L, "E2": E2, "nu2": nu2, "cycles": {}, "rate": {}, "solve_seconds": {}, "converged": {}, "violation": {}}
for F in frictions:
    t0 = time.perf_counter()
    p = spheres.spheres_problem(levels=L, friction=F, E2=E2, nu2=nu2)
    p.solver
    setup = time.perf_counter() - t0
    res = p.solve(tol=1e-11, max_cycles=200, threads=1)
    out["nodes"], out["dofs"], out["nonmortar_nodes"] = p.mesh.num_points, 3 * p.mesh.num_points, len(p.contact.nodes)
    out["setup_seconds"] = setup
    c = np.asarray(res.history["correction_norm"], float)
    c = c[c > 0]
    q = c[1:] / c[:-1]
    out["rate"][F] = float(np.exp(np.mean(np.log(q[-5:])))) if len(q) else None
    out["cycles"][F], out["solve_seconds"][F], out["converged"][F] = res.cycles, res.solve_seconds, res.converged
    out["violation"][F] = spheres.check_conditions(p, res)["max"]
    if F == 0.0:
        P = float(res.reaction[2])
        m1, m2 = p.bodies[0].material, p.bodies[1].material
        out["load"] = P
        out["hertz_p0_error"] = central_pressure(res) / spheres.two_body_p0(P, spheres.RADIUS, spheres.RADIUS, m1, m2) - 1
        out["hertz_radius_error"] = radius_of(res, (STICK, SLIP)) / spheres.two_body_radius(P, spheres.RADIUS, spheres.RADIUS, m1, m2) - 1
    if F == 0.4:
        lin = p.solve("linear", tol=1e-11, reference=res, threads=1)
        out["linear_cycles"], out["linear_seconds"] = lin.cycles, lin.solve_seconds
        out["stick_slip"] = [res.counts()["stick_nodes"], res.counts()["slip_nodes"]]
    del p, res
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 3])
    ap.add_argument("--materials", nargs="+", default=[f"{E:g},{nu:g}" for E, nu in MATERIALS],
                    help="E2,nu2 pairs of the lower body (default: equal and unequal)")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    fs = ",".join(str(f) for f in FRICTIONS)
    print(f"{'E2,nu2':>10} {'lvl':>3} {'dofs':>9} {'nm':>4} " + " ".join(f"{'F=' + str(f):>6}" for f in FRICTIONS)
          + f" {'rates':>15} {'lin':>4} {'viol':>8} {'setup s':>7} {'solve s':>8} {'MB':>6} {'p0 err':>7} {'a err':>7}")
    for E2, nu2 in (tuple(float(v) for v in m.split(",")) for m in a.materials):
        for L in range(a.levels[0], a.levels[1] + 1):
            run = subprocess.run([sys.executable, "-c", CHILD, str(L), str(E2), str(nu2), fs], capture_output=True, text=True)
            if run.returncode != 0:
                print(f"{E2:g},{nu2:g} level {L}: failed: {run.stderr.strip().splitlines()[-1:]}")
                continue
            r = json.loads(run.stdout.strip().splitlines()[-1])
            rows.append(r)
            cyc = " ".join(f"{r['cycles'][str(f)] if r['converged'][str(f)] else 'x':>6}" for f in FRICTIONS)
            rates = "/".join(f"{r['rate'][str(f)]:.2f}" for f in FRICTIONS)
            print(f"{E2:g},{nu2:g}".rjust(10) + f" {L:>3} {r['dofs']:>9,} {r['nonmortar_nodes']:>4} {cyc} {rates:>15} "
                  f"{r['linear_cycles']:>4} {max(r['violation'].values()):>8.1e} {r['setup_seconds']:>7.1f} "
                  f"{sum(r['solve_seconds'].values()):>8.1f} {r['peak_rss_mb']:>6.0f} {100 * r['hertz_p0_error']:>6.1f}% "
                  f"{100 * r['hertz_radius_error']:>6.1f}%", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
