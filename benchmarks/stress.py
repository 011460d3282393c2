"""Numerical stress tests (issue 5), as a table: each scene's outcome, cycles, asymptotic
contraction, solve seconds and the independent check of the contact conditions. The fast ones are
also tests (tests/test_robustness.py); this prints the figures on a larger level.

    python benchmarks/stress.py [--level 7] [--out out]
"""
import argparse
import json
import os

import numpy as np

from contactmg import hertz
from contactmg.checks import contact_conditions
from contactmg.friction import Coulomb, Frictionless
from contactmg.generators import rectangle
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.obstacle import PlaneObstacle
from contactmg.problem import ContactProblem, Dirichlet


def hertz_scene(h, F=0.4, nu=0.28, push=-0.005, plane_y=0.0):
    return ContactProblem(h, Material(2000.0, nu), [Dirichlet([2], (0.0, push))], contact_tags=[1],
                          obstacle=PlaneObstacle((0.0, plane_y), (0.0, -1.0)),
                          friction=Coulomb(F) if F > 0 else Frictionless())


def layer(aspect, level=5):
    """The layer of tests/test_robustness.py: 4 x 4 quads of aspect ratio `aspect` (long and flat),
    refined, pressed and sheared with friction onto the rigid plane."""
    h = MeshHierarchy.build(rectangle(4, 4, lx=aspect * 1.0, ly=1.0, cell="quad"), level)
    return ContactProblem(h, Material(100.0, 0.3), [Dirichlet([3], (0.01, -0.01))], contact_tags=[1],
                          obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Coulomb(0.3))


def rate(c):
    c = np.asarray(c)
    return float(np.exp(np.mean(np.log(c[-4:] / c[-5:-1])))) if len(c) > 5 and np.all(c[-5:] > 0) else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--level", type=int, default=7)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    h = hertz.hertz_problem("triangle", a.level, 0.4).hierarchy
    scenes = [(f"F = {F:g}", lambda F=F: hertz_scene(h, F=F)) for F in (0.0, 1e-3, 0.4, 5.0, 40.0, 1e3)]
    scenes += [("nu = 0.45", lambda: hertz_scene(h, nu=0.45)), ("nu = 0.49", lambda: hertz_scene(h, nu=0.49)),
               ("gap 1.0: nothing touches", lambda: hertz_scene(h, plane_y=-1.0)),
               ("push 0.2: whole arc touches", lambda: hertz_scene(h, push=-0.2)),
               ("negative gap 0.002 (penetration)", lambda: hertz_scene(h, plane_y=0.002)),
               ("layer, quads aspect 1", lambda: layer(1)), ("layer, quads aspect 8", lambda: layer(8)),
               ("layer, quads aspect 32", lambda: layer(32))]
    rows = []
    print(f"Hertz triangles level {a.level} ({2 * h.finest.num_points:,} dofs) unless stated; tol 1e-11, max 300 cycles")
    print(f"{'scene':34s} {'status':>10s} {'cycles':>6s} {'rate':>6s} {'solve s':>8s} {'violation':>9s} {'contact':>7s}")
    for name, make in scenes:
        p = make()
        r = p.solve(max_cycles=300)
        v = contact_conditions(p, r)["max"]
        row = {"scene": name, "converged": r.converged, "status": r.status, "cycles": r.cycles,
               "rate": rate(r.history["correction_norm"]), "solve_seconds": r.solve_seconds, "violation": v,
               "contact_nodes": r.counts()["contact_nodes"], "finite": bool(np.all(np.isfinite(r.displacement)))}
        rows.append(row)
        print(f"{name:34s} {('ok' if r.converged else r.status[:10]):>10s} {r.cycles:6d} {row['rate']:6.3f} "
              f"{r.solve_seconds:8.3f} {v:9.1e} {row['contact_nodes']:7d}")
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "stress.json"), "w") as fh:
        json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
