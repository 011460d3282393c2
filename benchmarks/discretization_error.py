"""Discretization error against dofs and seconds (frictionless Hertz): the energy-norm error of
each level's solution against a much finer reference (the level's solution interpolated up the
hierarchy), and the contact half-width and peak pressure against Hertz's formulas for the computed
load.

    python benchmarks/discretization_error.py [--levels 3 7] [--reference 9] [--cell triangle] [--out out]
"""
import argparse
import json
import os

import numpy as np

from contactmg import hertz
from contactmg.hierarchy import MeshHierarchy


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 7])
    ap.add_argument("--reference", type=int, default=9)
    ap.add_argument("--cell", default="triangle")
    ap.add_argument("--friction", type=float, default=0.0)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    ref_p = hertz.hertz_problem(a.cell, a.reference, a.friction)
    ref = ref_p.solve()
    h = ref_p.hierarchy
    u_ref = ref.displacement
    norm = float(np.sqrt(u_ref.ravel() @ ref_p.A.matvec(u_ref).ravel()))
    rows = []
    print(f"{'lvl':>3} {'dofs':>9} {'seconds':>8} {'rel energy err':>14} {'a':>8} {'a Hertz':>8} {'p0':>8} {'p0 Hertz':>8}")
    for L in range(a.levels[0], a.levels[1] + 1):
        p = hertz.hertz_problem(a.cell, L, a.friction)
        r = p.solve()
        u = r.displacement
        for T in h.transfers[L - 1:]:
            u = T.matrix() @ u
        e = u - u_ref
        err = float(np.sqrt(e.ravel() @ ref_p.A.matvec(e).ravel())) / norm
        P = r.reaction[1]
        row = {"level": L, "dofs": 2 * p.mesh.num_points, "seconds": r.setup_seconds + r.solve_seconds,
               "energy_error": err, "halfwidth": r.contact_halfwidth, "hertz_halfwidth": hertz.halfwidth(P),
               "peak_pressure": float(-r.normal_stress.min()), "hertz_peak_pressure": hertz.peak_pressure(P)}
        rows.append(row)
        print(f"{L:3d} {row['dofs']:9d} {row['seconds']:8.3f} {err:14.3e} {row['halfwidth']:8.5f} "
              f"{row['hertz_halfwidth']:8.5f} {row['peak_pressure']:8.2f} {row['hertz_peak_pressure']:8.2f}", flush=True)
    d = np.array([r["dofs"] for r in rows], float)
    e = np.array([r["energy_error"] for r in rows])
    slope = np.polyfit(np.log(d), np.log(e), 1)[0]
    print(f"energy error ~ dofs^{slope:.2f} (h^{-2 * slope:.2f}); reference level {a.reference}: "
          f"{2 * ref_p.mesh.num_points} dofs")
    with open(os.path.join(a.out, "discretization_error.json"), "w") as fh:
        json.dump({"rows": rows, "slope_vs_dofs": slope, "reference_level": a.reference}, fh, indent=1)


if __name__ == "__main__":
    main()
