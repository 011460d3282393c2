"""Issue-13 tables for `contactmg cylinders` (two half-disks, dual mortar, non-matching meshes).

cycles: nmg (Algorithm 2 with the tied coarse correction, the default), nmg without it and tnnmg
cycles per level and F, equal (E2 = 2000, nu2 = 0.28) and unequal (E2 = 4000, nu2 = 0.2) materials,
with the cycles of the linear problem whose contact state is known ("lin", the coarse space's own
rate).
hertz: per level, the half-width and peak pressure against the two-body Hertz formulas, by three
evaluations: the last contact node / the largest nodal multiplier (the contract's keys), the
ellipse fitted to all contact nodes (hertz_fit.py), the second moment of the nodal forces
(a = 2 sqrt(sum f x^2 / sum f), exact for the Hertz profile); time against the one-body Hertz
problem of the same level.
bounds: the diagnosis of nmg's growth without the tied correction: the mortar body's coarse
unknowns scaled by alpha in the finest prolongation (the same coarse space, another split of each
slack between the two bodies in the monotone bound restriction).

    python benchmarks/two_body_levels.py cycles --levels 3 4 5 6 [--json out.json]
    python benchmarks/two_body_levels.py hertz --levels 5 6 7 8 [--json out.json]
    python benchmarks/two_body_levels.py bounds --levels 4 5 6
"""
import argparse
import json
import time

import numpy as np
import scipy.sparse as sp

from contactmg import hertz as one_body_hertz
from contactmg.cylinders import RADIUS, cylinders_problem, two_body_halfwidth, two_body_peak_pressure
from contactmg.hertz import hertz_problem
from contactmg.hertz_fit import elliptic_fit
from contactmg.two_body import _scalar_transfer

MATERIALS = {"equal": (2000.0, 0.28), "unequal": (4000.0, 0.2)}


def cycles(levels, out):
    for name, (E2, nu2) in MATERIALS.items():
        for F in (0.0, 0.4, 2.0):
            row = {"materials": name, "E2": E2, "nu2": nu2, "F": F, "nmg": [], "nmg_untied": [], "tnnmg": [], "lin": [],
                   "nmg_seconds_per_cycle": [], "nmg_untied_seconds_per_cycle": []}
            for method, tied in (("nmg", True), ("nmg_untied", False), ("tnnmg", True)):
                for L in levels:
                    p = cylinders_problem(levels=L, friction=F, E2=E2, nu2=nu2, tied_correction=tied)
                    r = p.solve(method.split("_")[0])
                    row[method].append(r.cycles if r.converged else None)
                    if method.startswith("nmg"):
                        row[method + "_seconds_per_cycle"].append(r.solve_seconds / r.cycles)
                    if method == "nmg":
                        row["lin"].append(p.solve("linear", reference=r).cycles)
            out.append(row)
            print(f"{name:8s} F={F:<4} nmg {row['nmg']} (without the tied correction {row['nmg_untied']}) tnnmg "
                  f"{row['tnnmg']} lin {row['lin']}", flush=True)


def _evaluate(x, f, lam, active, a, p0):
    a_fit, p0_fit, _ = elliptic_fit(x[active], lam[active])
    a_mom = 2 * np.sqrt((f * x ** 2).sum() / f.sum())
    return {"halfwidth_node": 100 * (np.abs(x[active]).max() / a - 1), "halfwidth_fit": 100 * (a_fit / a - 1),
            "halfwidth_moment": 100 * (a_mom / a - 1), "p0_max": 100 * (lam.max() / p0 - 1),
            "p0_fit": 100 * (p0_fit / p0 - 1)}


def hertz(levels, out, method):
    for L in levels:
        t = time.perf_counter()
        one = hertz_problem("triangle", L, 0.0)
        one_setup = time.perf_counter() - t
        r1 = one.solve(method)
        P1 = r1.reaction[1]
        x1 = one.mesh.points[one.contact.nodes, 0]
        ev1 = _evaluate(x1, -r1.contact_force[:, 0], -r1.normal_stress, r1.contact_state > 0,
                        one_body_hertz.halfwidth(P1), one_body_hertz.peak_pressure(P1))
        print(f"L{L} one-body dofs {2 * one.mesh.num_points} {r1.cycles} cycles {r1.solve_seconds / r1.cycles:.4f} s/cycle "
              + " ".join(f"{k} {v:+.2f}%" for k, v in ev1.items()), flush=True)
        for name, (E2, nu2) in MATERIALS.items():
            t = time.perf_counter()
            p = cylinders_problem(levels=L, friction=0.0, E2=E2, nu2=nu2)
            setup = time.perf_counter() - t
            r = p.solve(method)
            P = r.reaction[1]
            m1, m2 = p.bodies[0].material, p.bodies[1].material
            x = p.mesh.points[p.contact.nodes, 0]
            ev = _evaluate(x, -r.contact_force[:, 0], -r.normal_stress, r.contact_state > 0,
                           two_body_halfwidth(P, RADIUS, RADIUS, m1, m2), two_body_peak_pressure(P, RADIUS, RADIUS, m1, m2))
            h = np.pi * RADIUS / (12 * 2 ** (L - 1))
            row = {"level": L, "materials": name, "dofs": 2 * p.mesh.num_points, "method": method, "cycles": r.cycles,
                   "setup_seconds": setup, "solve_seconds": r.solve_seconds,
                   "seconds_per_cycle_per_mdof": r.solve_seconds / r.cycles / (2e-6 * p.mesh.num_points),
                   "one_body_dofs": 2 * one.mesh.num_points, "one_body_setup_seconds": one_setup,
                   "one_body_seconds_per_cycle_per_mdof": r1.solve_seconds / r1.cycles / (2e-6 * one.mesh.num_points),
                   "h_over_a_percent": 100 * h / two_body_halfwidth(P, RADIUS, RADIUS, m1, m2),
                   "one_body": ev1, **ev}
            out.append(row)
            print(f"L{L} {name:8s} dofs {row['dofs']} {r.cycles} cycles, per cycle and Mdof {row['seconds_per_cycle_per_mdof']:.3f} s "
                  f"(one body {row['one_body_seconds_per_cycle_per_mdof']:.3f}), h/a {row['h_over_a_percent']:.1f}% "
                  + " ".join(f"{k} {v:+.2f}%" for k, v in ev.items()), flush=True)


def bounds(levels, out, alphas=(0.5, 1.0, 2.0, 4.0, 10.0)):
    E2, nu2 = MATERIALS["unequal"]
    for L in levels:
        row = {"level": L}
        for a in alphas:
            p = cylinders_problem(levels=L, friction=0.0, E2=E2, nu2=nu2, tied_correction=False)
            P = p.transfers[-1].matrix().tocsr()
            scale = np.ones(P.shape[1])
            scale[p.bodies[0].hierarchy.meshes[-2].num_points:] = a  # the mortar body's coarse unknowns
            p.transfers[-1] = _scalar_transfer(P @ sp.diags(scale))
            r = p.solve()
            row[str(a)] = r.cycles if r.converged else None
        out.append(row)
        print(f"L{L} nmg cycles by alpha: {row}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("table", choices=["cycles", "hertz", "bounds"])
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 4, 5, 6])
    ap.add_argument("--method", default="tnnmg", help="hertz: the solver (the discretization is the same)")
    ap.add_argument("--json")
    args = ap.parse_args()
    out = []
    if args.table == "cycles":
        cycles(args.levels, out)
    elif args.table == "hertz":
        hertz(args.levels, out, args.method)
    else:
        bounds(args.levels, out)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
