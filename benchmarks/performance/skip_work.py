"""What the solver skips when a scene does not need it, with timings on the Hertz benchmark:

laws     the friction law picks a compiled sweep (frictionless does no friction work, Tresca no
         Coulomb bound): cycles, milliseconds per cycle and per smoothing, coarse rebuilds (the
         coarse matrices are rebuilt, incrementally, only in cycles whose truncated set changed);
         a scene that cannot touch (obstacle far below) against the same body with no contact
         boundary at all (the linear multigrid).
outputs  stresses, the VTU file and the plot cost nothing unless asked for: their seconds next to
         the solve's.
local    local smoothing on adaptive hierarchies (each coarse level smooths only the rows its
         refinement changed) against full smoothing: seconds per cycle per dof and smoothed rows
         per fine node on the paper's adaptive hierarchy, a strongly graded one (Doerfler
         theta 0.2, about 1.3x more nodes per level) and the same thinned to a growth of 2.5 per
         level, next to uniform hierarchies.

    python benchmarks/performance/skip_work.py [--parts laws outputs local] [--level 8]
        [--graded-levels 26 30] [--paper-levels 9 10] [--uniform-levels 6 7] [--quick] [--json PATH]
"""
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

import contactmg as cm  # noqa: E402
from contactmg.examples import hertz  # noqa: E402
from contactmg.solve.options import options_from, with_cycle


def best_of(problem, n=3, **kw):
    """The fastest of n solves (same problem object: the setup is shared)."""
    best = None
    for _ in range(n):
        r = problem.solve(**kw)
        if best is None or r.solve_seconds < best.solve_seconds:
            best = r
    return best


def part_laws(cell, level, repeat):
    """Per friction law and scene: cycles, ms per cycle and per smoothing, rebuilds."""
    base = hertz.hertz_problem(cell, level, 0.4)
    h, mat = base.hierarchy, cm.Material(hertz.E, hertz.NU)
    top = [cm.Dirichlet([cm.HERTZ_TOP], (0.0, hertz.TOP_DISPLACEMENT))]
    plane = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0))
    scenes = [("frictionless", cm.Frictionless(), plane), ("tresca (bound 20)", cm.Tresca(20.0), plane),
              ("coulomb F=0.4", cm.Coulomb(0.4), plane), ("coulomb F=40", cm.Coulomb(40.0), plane),
              ("cannot touch (gap 1.0)", cm.Coulomb(0.4), cm.PlaneObstacle((0.0, -1.0), (0.0, -1.0))),
              ("no contact boundary", None, None)]
    out = {"cell": cell, "level": level, "dofs": int(2 * base.mesh.num_points), "scenes": {}}
    print(f"{cell}, level {level}, {out['dofs']:,} dofs; best of {repeat} solves each")
    print(f"{'scene':28s} {'cycles':>6s} {'ms/cycle':>9s} {'smooth ms/cyc':>13s} {'rebuilds':>8s} {'rebuild s':>9s}")
    for name, law, obst in scenes:
        # the solve defaults of the recorded results: nmg F(3,3), the absolute stop 1e-11
        p = with_cycle(cm.Problem(cm.Body(h, mat, top, contact_tags=[cm.HERTZ_ARC] if law else []), obstacle=obst,
                                  friction=law))
        r = best_of(p, repeat)
        ph = r.phase_seconds
        smooth = (ph.get("presmooth", 0) + ph.get("postsmooth", 0)) / r.cycles * 1e3
        out["scenes"][name] = {"cycles": r.cycles, "converged": r.converged, "solve_seconds": r.solve_seconds,
                               "ms_per_cycle": r.solve_seconds / r.cycles * 1e3, "smooth_ms_per_cycle": smooth,
                               "rebuilds": r.rebuilds, "phase_seconds": ph}
        print(f"{name:28s} {r.cycles:6d} {1e3 * r.solve_seconds / r.cycles:9.2f} {smooth:13.2f} {r.rebuilds:8d} "
              f"{ph.get('coarse_update', 0):9.4f}", flush=True)
    return out


def part_outputs(cell, level):
    """Seconds of the solve against the outputs derived from it on request."""
    from matplotlib.figure import Figure

    from contactmg.results.plots import plot_boundary_stress

    p = hertz.hertz_problem(cell, level, 0.4)
    r = p.solve()
    t = time.perf_counter()
    _ = (r.normal_stress, r.tangential_stress, r.reaction, r.counts())
    t_stress = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        r.write_vtu(os.path.join(d, "h.vtu"))
        t_vtu = time.perf_counter() - t
        t = time.perf_counter()
        fig = Figure()
        plot_boundary_stress(r, ax=fig.add_subplot(1, 1, 1), friction=0.4, margin=1.5)
        fig.savefig(os.path.join(d, "h.png"))
        t_plot = time.perf_counter() - t
    print(f"outputs (only when asked): solve {r.solve_seconds:.3f} s; stresses/reaction {t_stress * 1e3:.2f} ms, "
          f"VTU {t_vtu:.3f} s, plot {t_plot:.3f} s")
    return {"solve_seconds": r.solve_seconds, "stresses_seconds": t_stress, "vtu_seconds": t_vtu, "plot_seconds": t_plot}


def visits(levels, cycle):
    """How often one cycle smooths each level (index 0 = coarsest, solved instead; last = fine)."""
    def go(l, kind, out):
        out[l] += 1
        if l == 0:
            return
        for _ in range(1 if kind == "V" else 2):
            go(l - 1, "V" if (kind == "F" and _ == 1) else kind, out)
    out = [0] * levels
    go(levels - 1, cycle, out)
    return out


def measure_local(name, h, local, repeat, cycle="F"):
    """One hierarchy with local or full smoothing: seconds per cycle and smoothed rows per fine node."""
    p = hertz.hertz_problem_on(h, 0.4, cycle=cycle)
    p.default_options = options_from(p.default_options).replace(local_smoothing=local)
    p.solver.core  # noqa: B018 - built outside the timing
    best = best_of(p, repeat, threads=1)
    n = p.mesh.num_points
    rows = [0] + [len(h.changed_nodes(l)) if local else h.meshes[l].num_points for l in range(1, h.levels - 1)] + [n]
    smoothed = sum(v * r for v, r in zip(visits(h.levels, cycle), rows))
    return {"hierarchy": name, "local": bool(local), "levels": h.levels, "dofs": 2 * n, "cycles": best.cycles,
            "converged": best.converged, "seconds_per_cycle": best.solve_seconds / best.cycles,
            "us_per_cycle_per_dof": 1e6 * best.solve_seconds / best.cycles / (2 * n),
            "smoothed_rows_per_fine_node": smoothed / n}


def part_local(graded_levels, theta, paper_levels, uniform_levels, min_growth, repeat):
    """Local against full smoothing on graded, thinned, paper and uniform hierarchies."""
    graded = hertz.hertz_adaptive_hierarchy(max(graded_levels), 0.4, theta=theta)
    paper = hertz.hertz_adaptive_hierarchy(max(paper_levels), 0.4)
    cases = []
    for L in graded_levels:
        g = graded.truncated(L)
        cases += [(f"graded L{L}", g), (f"thinned L{L}", g.thinned(min_growth))]
    cases += [(f"paper L{L}", paper.truncated(L)) for L in paper_levels]
    cases += [(f"uniform L{L}", hertz.hertz_problem("triangle", L, 0.4).hierarchy) for L in uniform_levels]
    rows = []
    print(f"{'hierarchy':>12} {'smoothing':>9} {'levels':>6} {'dofs':>8} {'cycles':>6} {'s/cycle':>8} "
          f"{'us/cyc/dof':>10} {'rows/dof':>8}")
    for name, h in cases:
        for local in ((False, True) if h.kind == "adaptive" else (False,)):
            r = measure_local(name, h, local, repeat)
            rows.append(r)
            print(f"{name:>12} {'local' if local else 'full':>9} {r['levels']:6d} {r['dofs']:8,} {r['cycles']:6d} "
                  f"{r['seconds_per_cycle']:8.4f} {r['us_per_cycle_per_dof']:10.3f} {r['smoothed_rows_per_fine_node']:8.2f}",
                  flush=True)
    return rows


def main():
    ap = parser(__doc__)
    ap.add_argument("--parts", nargs="+", choices=["laws", "outputs", "local"], default=["laws", "outputs", "local"])
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"])
    ap.add_argument("--level", type=int, default=8)
    ap.add_argument("--graded-levels", type=int, nargs="+", default=[26, 30])
    ap.add_argument("--graded-theta", type=float, default=0.2)
    ap.add_argument("--paper-levels", type=int, nargs="+", default=[9, 10])
    ap.add_argument("--uniform-levels", type=int, nargs="+", default=[6, 7])
    ap.add_argument("--min-growth", type=float, default=2.5)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    if a.quick:
        a.level, a.graded_levels, a.paper_levels, a.uniform_levels, a.repeat = 4, [8], [5], [4], 1
    out = {"load_average": os.getloadavg()[0]}
    if "laws" in a.parts:
        out["laws"] = part_laws(a.cell, a.level, a.repeat)
    if "outputs" in a.parts:
        out["outputs"] = part_outputs(a.cell, a.level)
    if "local" in a.parts:
        out["local"] = part_local(a.graded_levels, a.graded_theta, a.paper_levels, a.uniform_levels, a.min_growth, a.repeat)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
