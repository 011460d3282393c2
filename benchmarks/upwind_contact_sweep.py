"""The upwind contact sweep (issue 11, eleventh part) off and on outside the adaptive Hertz levels:
uniform triangles (Hertz), tetrahedra (adaptive sphere) and hexahedra (uniform sphere). Cycles, the
independent check, the two solutions' difference and the time per cycle (one thread).

    python benchmarks/upwind_contact_sweep.py [--cases uniform 3d] [--json benchmarks/results/upwind_contact_sweep.json]

(The adaptive Hertz levels 3-11 are benchmarks/petrov_galerkin_variants.py's variants stop25 and
default.) tol 1e-11 from u = 0, F(3,3); cycle counts do not depend on the machine's load, the
seconds do (run it alone).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from bench_json import write_json  # noqa: E402
from contactmg.checks import contact_conditions  # noqa: E402
from contactmg.hertz import hertz_problem  # noqa: E402
from contactmg.sphere import sphere_adaptive_hierarchy, sphere_problem, sphere_problem_on  # noqa: E402


def cases(which):
    if "uniform" in which:
        for L in (3, 4, 5, 6, 7, 8):
            for F in (0.4, 2.0, 5.0, 8.0):
                yield f"triangles uniform L{L}", F, lambda L=L, F=F: hertz_problem("triangle", L, F)
    if "3d" in which:
        for L in (3, 4):
            h = sphere_adaptive_hierarchy(L, 0.4)
            for F in (0.1, 0.4, 1.0):
                yield f"tetrahedra adaptive L{L}", F, lambda h=h, F=F: sphere_problem_on(h, F)
        for L in (2, 3):
            for F in (0.1, 0.4, 1.0):
                yield f"hexahedra uniform L{L}", F, lambda L=L, F=F: sphere_problem("hexahedron", L, F)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", nargs="+", default=["uniform", "3d"], choices=["uniform", "3d"])
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    print("case, F: cycles off / on, check off / on, |u_on - u_off| / max |u|, ms a cycle off / on")
    for name, F, make in cases(a.cases):
        p = make()
        out = {}
        for on in (False, True):
            r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1, upwind_contact_sweep=on)
            out[on] = r
        u0, u1 = np.asarray(out[False].displacement), np.asarray(out[True].displacement)
        row = {"case": name, "F": F, "dofs": int(u0.size)}
        for on, key in ((False, "off"), (True, "on")):
            r = out[on]
            row[key] = {"cycles": int(r.cycles), "converged": bool(r.converged),
                        "violation": float(contact_conditions(p, r)["max"]) if r.converged else None,
                        "ms_per_cycle": 1e3 * r.solve_seconds / max(r.cycles, 1)}
        row["difference"] = float(np.abs(u1 - u0).max() / np.abs(u0).max())
        rows.append(row)
        f, n = row["off"], row["on"]
        print(f"  {name:24} F={F:<4g} {f['cycles']}{'' if f['converged'] else '!'} / {n['cycles']}{'' if n['converged'] else '!'}"
              f"   {f['violation'] or float('nan'):.1e} / {n['violation'] or float('nan'):.1e}   {row['difference']:.1e}"
              f"   {f['ms_per_cycle']:.1f} / {n['ms_per_cycle']:.1f}", flush=True)
    write_json(a.json, rows)


if __name__ == "__main__":
    main()
