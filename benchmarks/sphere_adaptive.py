"""Adaptive against uniform tetrahedral hierarchies for the Hertz sphere (issue 11, 3D).

    python benchmarks/sphere_adaptive.py [--levels 4] [--uniform-levels 3] [--frictions 0 0.4 2]
        [--theta 0.5] [--out out]

Per level of the adaptive hierarchy (sphere_adaptive_hierarchy: hierarchical estimator, Doerfler
marking, AMP bisection of tetrahedra, refined for F = 0.4) and of the uniform one (Bey's red
refinement): dofs, the estimated error (F = 0.4; the same estimator on the uniform levels up to
--estimate-dofs), Algorithm 2 cycles for each friction coefficient
(tol 1e-11, every result checked by contactmg.checks.contact_conditions), and for the
frictionless solve the accuracy: the contact radius against Hertz's a and the central pressure
against p0 for the computed load P. (P itself is printed but is no error measure across the two
kinds: the energy is P D / 2, but the hierarchies resolve the sphere's surface differently away from
the contact, so their domains differ.)
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from contactmg import sphere
from contactmg.checks import contact_conditions
from contactmg.estimator import estimate
from contactmg.hierarchy import MeshHierarchy
from contactmg.generators_3d import ball_projector, half_ball


def solve_row(kind, level, h, frictions, estimate_dofs=0):
    row = {"kind": kind, "level": level, "dofs": int(3 * h.finest.num_points), "cycles": {}}
    for F in frictions:
        p = sphere.sphere_problem_on(h, friction=F)
        t0 = time.perf_counter()
        r = p.solve(tol=1e-11)
        viol = contact_conditions(p, r)["max"]
        row["cycles"][str(F)] = r.cycles if r.converged else None
        row.setdefault("violation", {})[str(F)] = viol
        row.setdefault("seconds", {})[str(F)] = time.perf_counter() - t0
        if kind == "uniform" and F == 0.4 and row["dofs"] <= estimate_dofs:
            # the same hierarchical estimator on the uniform level: a like-for-like error measure
            est = estimate(h, lambda hh: sphere.sphere_problem_on(hh, friction=F), r,
                           ball_projector(sphere.CENTER, sphere.RADIUS))
            row["estimated_error"] = est.total
        if F == 0:
            load = float(r.reaction[2])
            row.update(load=load, contact_radius=sphere.radius_of(r, (1, 2)), hertz_radius=sphere.hertz_radius(load),
                       central_pressure=sphere.central_pressure(r), hertz_p0=sphere.hertz_p0(load))
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--levels", type=int, default=5, help="adaptive levels")
    ap.add_argument("--uniform-levels", type=int, default=3)
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.0, 0.4, 2.0])
    ap.add_argument("--theta", type=float, default=sphere.ADAPTIVE_THETA)
    ap.add_argument("--estimate-dofs", type=int, default=20000,
                    help="estimate the uniform levels (F = 0.4) up to this many dofs (the estimate refines once more)")
    ap.add_argument("--out", default="out")
    a = ap.parse_args(argv)
    frictions = sorted(set(a.frictions) | {0.0})
    t0 = time.perf_counter()
    full = sphere.sphere_adaptive_hierarchy(a.levels, friction=0.4, theta=a.theta,
                                            progress=lambda l, h, r: print(f"  adaptive level {l}: {3 * h.finest.num_points} dofs, "
                                                                           f"{time.perf_counter() - t0:.0f} s", file=sys.stderr))
    rows = []
    for L in range(1, a.levels + 1):
        rows.append(solve_row("adaptive", L, full.truncated(L), frictions))
        rows[-1]["estimated_error"] = full.estimated_error[L - 1]
    uni = MeshHierarchy.build(half_ball("tetra", sphere.CENTER, sphere.RADIUS, k=sphere.K, inner=sphere.INNER),
                              a.uniform_levels, projector=ball_projector(sphere.CENTER, sphere.RADIUS))
    for L in range(1, a.uniform_levels + 1):
        rows.append(solve_row("uniform", L, uni.truncated(L), frictions, a.estimate_dofs))
    head = f"{'kind':>9} {'lvl':>3} {'dofs':>8} {'est err':>9} " + " ".join(f"{'F=' + str(F):>6}" for F in frictions) + \
        f" {'P':>8} {'a/a_H-1':>8} {'p0/p0_H-1':>9}"
    print(head)
    for r in rows:
        cyc = " ".join(f"{str(r['cycles'][str(F)]):>6}" for F in frictions)
        est = f"{r['estimated_error']:.3e}" if "estimated_error" in r else "-"
        print(f"{r['kind']:>9} {r['level']:>3} {r['dofs']:>8} {est:>9} {cyc} {r['load']:>8.4f} "
              f"{r['contact_radius'] / r['hertz_radius'] - 1:>+8.3f} {r['central_pressure'] / r['hertz_p0'] - 1:>+9.3f}")
    print(f"max violation {max(max(r['violation'].values()) for r in rows):.1e}; {time.perf_counter() - t0:.0f} s in all")
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "sphere_adaptive.json"), "w") as fh:
        json.dump({"rows": rows, "theta": a.theta}, fh, indent=1)


if __name__ == "__main__":
    main()
