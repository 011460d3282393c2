"""Skip what a scene does not need (issue 5), shown with timings on one Hertz mesh:

- the friction law picks a compiled sweep: frictionless does no friction work, Tresca no Coulomb
  bound; seconds per cycle and per phase for each law;
- a scene that cannot touch (obstacle far below) against the same body with no contact boundary at
  all (the linear multigrid): cycles and seconds;
- coarse matrices: rebuilt (incrementally) only in cycles whose truncated set changed;
- outputs: stresses, VTU and the plot are computed only when asked for (their cost next to the solve).

    python benchmarks/skip_work.py [--cell triangle] [--level 8] [--out out]
"""
import argparse
import json
import os
import tempfile
import time

import numpy as np

from contactmg import hertz
from contactmg.friction import Coulomb, Frictionless, Tresca
from contactmg.generators import HERTZ_ARC, HERTZ_TOP
from contactmg.material import Material
from contactmg.obstacle import PlaneObstacle
from contactmg.problem import ContactProblem, Dirichlet


def best_of(problem, n=3, **kw):
    """The fastest of n solves (same problem object: the setup is shared)."""
    best = None
    for _ in range(n):
        r = problem.solve(**kw)
        if best is None or r.solve_seconds < best.solve_seconds:
            best = r
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cell", default="triangle")
    ap.add_argument("--level", type=int, default=8)
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    base = hertz.hertz_problem(a.cell, a.level, 0.4)
    h, mat = base.hierarchy, Material(hertz.E, hertz.NU)
    top = [Dirichlet([HERTZ_TOP], (0.0, hertz.TOP_DISPLACEMENT))]
    plane = PlaneObstacle((0.0, 0.0), (0.0, -1.0))
    out = {"cell": a.cell, "level": a.level, "dofs": int(2 * base.mesh.num_points), "laws": {}}

    print(f"{a.cell}, level {a.level}, {out['dofs']:,} dofs; best of 3 solves each")
    print(f"{'scene':28s} {'cycles':>6s} {'solve s':>8s} {'ms/cycle':>9s} {'smooth ms/cyc':>13s} {'rebuilds':>8s} {'rebuild s':>9s}")
    scenes = [("frictionless", Frictionless(), plane), ("tresca (bound 20)", Tresca(20.0), plane),
              ("coulomb F=0.4", Coulomb(0.4), plane), ("coulomb F=40", Coulomb(40.0), plane),
              ("cannot touch (gap 1.0)", Coulomb(0.4), PlaneObstacle((0.0, -1.0), (0.0, -1.0))),
              ("no contact boundary", None, None)]
    for name, law, obst in scenes:
        p = ContactProblem(h, mat, top, contact_tags=[HERTZ_ARC] if law else [], obstacle=obst, friction=law)
        r = best_of(p)
        ph = r.phase_seconds
        smooth = (ph.get("presmooth", 0) + ph.get("postsmooth", 0)) / r.cycles * 1e3
        row = {"cycles": r.cycles, "solve_seconds": r.solve_seconds, "ms_per_cycle": r.solve_seconds / r.cycles * 1e3,
               "smooth_ms_per_cycle": smooth, "rebuilds": r.rebuilds, "phase_seconds": ph, "converged": r.converged,
               "rebuild_cycles": int(np.sum(r.history["rebuilt"])) if "rebuilt" in r.history else None}
        out["laws"][name] = row
        print(f"{name:28s} {r.cycles:6d} {r.solve_seconds:8.3f} {row['ms_per_cycle']:9.1f} {smooth:13.1f} "
              f"{r.rebuilds:8d} {ph.get('coarse_update', 0):9.4f}")

    # outputs only on demand: the solve returns arrays; stresses are derived on access, files on request
    p = hertz.hertz_problem(a.cell, a.level, 0.4)
    r = p.solve()
    t = time.perf_counter(); _ = (r.normal_stress, r.tangential_stress, r.reaction, r.counts()); t_stress = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter(); r.write_vtu(os.path.join(d, "h.vtu")); t_vtu = time.perf_counter() - t
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from contactmg.plots import plot_boundary_stress
        t = time.perf_counter()
        fig, ax = plt.subplots()
        plot_boundary_stress(r, ax=ax, friction=0.4, margin=1.5)
        fig.savefig(os.path.join(d, "h.png"))
        plt.close(fig)
        t_plot = time.perf_counter() - t
    out["outputs"] = {"solve_seconds": r.solve_seconds, "stresses_seconds": t_stress, "vtu_seconds": t_vtu,
                      "plot_seconds": t_plot}
    print(f"outputs (only when asked): solve {r.solve_seconds:.3f} s; stresses/reaction {t_stress * 1e3:.2f} ms, "
          f"VTU {t_vtu:.3f} s, plot {t_plot:.3f} s")
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, f"skip_work_{a.cell}.json"), "w") as fh:
        json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
