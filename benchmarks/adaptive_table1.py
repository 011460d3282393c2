"""The paper's adaptive Table 1 and what the adaptive hierarchy buys (issue 11).

    python benchmarks/adaptive_table1.py [--parts table accuracy cost] [--levels 3 5 7 9 11]
        [--frictions ...] [--reference-level 9] [--out out]

table:    the adaptive Hertz hierarchy (hertz_adaptive_hierarchy, F = 0.4, theta = 0.8), per level: dofs
          (beside the paper's), Algorithm 2 cycles for the ten paper coefficients, Algorithm 1
          outer iterations (None: no convergence), every result checked by
          contactmg.checks.contact_conditions (contactmg.table1.table1 does the runs).
accuracy: frictionless Hertz, adaptive against uniform at comparable dofs: the energy error
          against a common reference (the adaptive level R refined uniformly twice; uniform
          solutions are interpolated onto it by point location), the contact half-width and the
          peak pressure against Hertz's formulas for the computed load.
cost:     seconds per cycle and per dof (F = 0.4) on adaptive and uniform levels, and the rows a
          level-local smoother would touch (sum over levels of MeshHierarchy.changed_nodes) against
          the rows every level smooths today (sum of the level sizes).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from contactmg import _core, hertz
from contactmg.hierarchy import MeshHierarchy, _refined
from contactmg.table1 import FIXED_POINT_STALL_WINDOW, failed_runs, format_table, merge_levels, table1


def energy(problem, v):
    return float(np.sqrt(np.sum(v * problem.A.matvec(v))))


def interpolate_p1(mesh, u, points, center=np.array(hertz.CENTER)):
    """u (P1 on mesh) at `points`; points just outside the inscribed polygon of the arc are pulled
    radially inside (the linear extension of the boundary cell, O(h^2) off)."""
    import matplotlib.tri as mtri

    tri = mtri.Triangulation(mesh.points[:, 0], mesh.points[:, 1], mesh.cells)
    finder = tri.get_trifinder()
    q = np.array(points, dtype=float)
    where = finder(q[:, 0], q[:, 1])
    for shrink in (1e-9, 1e-6, 1e-4, 1e-3, 1e-2, 3e-2, 1e-1):
        out = where < 0
        if not np.any(out):
            break
        q[out] = center + (points[out] - center) * (1 - shrink)
        where[out] = finder(q[out, 0], q[out, 1])
    if np.any(where < 0):
        raise RuntimeError(f"{int(np.sum(where < 0))} reference points found in no cell")
    vals = []
    for a in range(2):
        vals.append(mtri.LinearTriInterpolator(tri, u[:, a], trifinder=finder)(q[:, 0], q[:, 1]).data)
    return np.stack(vals, 1)


def contact_quantities(r):
    load = float(r.reaction[1])
    return {"halfwidth": r.contact_halfwidth, "hertz_halfwidth": hertz.halfwidth(load),
            "peak_pressure": float(-r.normal_stress.min()), "hertz_peak_pressure": hertz.peak_pressure(load)}


def part_accuracy(a, out):
    F = a.accuracy_friction
    t0 = time.perf_counter()
    h = hertz.hertz_adaptive_hierarchy(a.reference_level, F)
    proj = hertz.hertz_projector()
    meshes, transfers = list(h.meshes), list(h.transfers)
    for _ in range(2):
        m = meshes[-1]
        fine, t = _refined(m, _core.refine(m.points, m.cells, m.cell_type, m.facets, m.facet_tags), proj)
        meshes.append(fine)
        transfers.append(t)
    ref_p = hertz.hertz_problem_on(MeshHierarchy(meshes, transfers), F)
    ref = ref_p.solve()
    if not ref.converged:
        raise RuntimeError(f"reference solve: {ref.status}")
    u_ref = ref.displacement
    norm = energy(ref_p, u_ref)
    print(f"reference: adaptive level {a.reference_level} + 2 uniform, {2 * ref_p.mesh.num_points:,} dofs, "
          f"{time.perf_counter() - t0:.1f} s", flush=True)
    rows = []
    head = f"{'hier':>8} {'lvl':>3} {'dofs':>9} {'rel energy err':>14} {'estimate':>9} {'a':>8} {'a Hertz':>8} {'p0':>8} {'p0 Hertz':>8}"
    print(head)
    for kind, levels in (("adaptive", range(a.accuracy_adaptive[0], a.accuracy_adaptive[1] + 1)),
                         ("uniform", range(a.accuracy_uniform[0], a.accuracy_uniform[1] + 1))):
        for L in levels:
            hl = h.truncated(L) if kind == "adaptive" else "uniform"
            p = hertz.hertz_problem(levels=L, friction=F, hierarchy=hl)
            r = p.solve()
            if kind == "adaptive":
                u = r.displacement
                for t in transfers[L - 1:]:
                    u = t.matrix() @ u
            else:
                u = interpolate_p1(p.mesh, r.displacement, ref_p.mesh.points)
            row = {"hierarchy": kind, "level": L, "dofs": 2 * p.mesh.num_points, "converged": r.converged,
                   "energy_error": energy(ref_p, u - u_ref) / norm,
                   "estimated_error": (h.estimated_error[L - 1] / norm) if kind == "adaptive" else None}
            row.update(contact_quantities(r))
            rows.append(row)
            est = f"{row['estimated_error']:9.2e}" if row["estimated_error"] is not None else f"{'':9}"
            print(f"{kind:>8} {L:3d} {row['dofs']:9,} {row['energy_error']:14.3e} {est} {row['halfwidth']:8.5f} "
                  f"{row['hertz_halfwidth']:8.5f} {row['peak_pressure']:8.2f} {row['hertz_peak_pressure']:8.2f}", flush=True)
    for kind in ("adaptive", "uniform"):
        d = np.array([r["dofs"] for r in rows if r["hierarchy"] == kind], float)
        e = np.array([r["energy_error"] for r in rows if r["hierarchy"] == kind])
        print(f"{kind}: energy error ~ dofs^{np.polyfit(np.log(d[-3:]), np.log(e[-3:]), 1)[0]:.2f} (last three levels)")
    out["accuracy"] = {"friction": F, "reference_dofs": 2 * ref_p.mesh.num_points, "rows": rows}
    if a.plot:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6, 4.5))
        ax = fig.add_subplot(1, 1, 1)
        for kind, mk in (("adaptive", "o-"), ("uniform", "s-")):
            sel = [r for r in rows if r["hierarchy"] == kind]
            ax.loglog([r["dofs"] for r in sel], [r["energy_error"] for r in sel], mk, label=f"{kind}: energy error")
        sel = [r for r in rows if r["hierarchy"] == "adaptive"]
        ax.loglog([r["dofs"] for r in sel], [r["estimated_error"] for r in sel], "o--", label="adaptive: estimate")
        ax.set_xlabel("dofs")
        ax.set_ylabel("relative energy error")
        ax.set_title(f"Hertz, F = {F:g}: adaptive vs uniform")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "adaptive_error.png"), dpi=130)


def part_cost(a, out):
    rows = []
    print(f"{'hier':>8} {'lvl':>3} {'dofs':>9} {'cycles':>6} {'s/cycle':>9} {'us/cycle/dof':>12} {'rows smoothed':>13} {'rows local':>10}")
    h = hertz.hertz_adaptive_hierarchy(max(a.cost_adaptive), 0.4)
    for kind, levels in (("adaptive", a.cost_adaptive), ("uniform", a.cost_uniform)):
        for L in levels:
            p = hertz.hertz_problem(levels=L, friction=0.4, hierarchy=h.truncated(L) if kind == "adaptive" else "uniform")
            p.solver  # built outside the timing
            best = None
            for _ in range(a.repeat):
                r = p.solve()
                best = r if best is None or r.solve_seconds < best.solve_seconds else best
            hh = p.hierarchy
            smoothed = sum(m.num_points for m in hh.meshes)
            local = sum(len(hh.changed_nodes(k)) for k in range(hh.levels))
            row = {"hierarchy": kind, "level": L, "dofs": 2 * p.mesh.num_points, "cycles": best.cycles,
                   "seconds_per_cycle": best.solve_seconds / best.cycles,
                   "us_per_cycle_per_dof": 1e6 * best.solve_seconds / best.cycles / (2 * p.mesh.num_points),
                   "rows_smoothed": smoothed, "rows_local": local}
            rows.append(row)
            print(f"{kind:>8} {L:3d} {row['dofs']:9,} {row['cycles']:6d} {row['seconds_per_cycle']:9.4f} "
                  f"{row['us_per_cycle_per_dof']:12.3f} {smoothed:13,} {local:10,}", flush=True)
    out["cost"] = rows


def part_table(a, out):
    t0 = time.perf_counter()
    h = hertz.hertz_adaptive_hierarchy(max(a.levels), hertz.ADAPTIVE_FRICTION)
    print(f"adaptive hierarchy to level {max(a.levels)}: {time.perf_counter() - t0:.1f} s; dofs per level "
          f"{[2 * m.num_points for m in h.meshes]}", flush=True)
    for L, d in hertz.PAPER_ADAPTIVE_DOFS.items():
        if L <= h.levels:
            print(f"  level {L}: {2 * h.meshes[L - 1].num_points:,} dofs, paper {d:,} (ratio "
                  f"{2 * h.meshes[L - 1].num_points / d:.2f})")
    tab = None
    for L in a.levels:  # one level at a time, saved after each (level 11 takes minutes per coefficient)
        row = table1([L], a.frictions, hierarchy=h, progress=False, fixed_point_max=a.fixed_point_max, jobs=a.jobs,
                     fixed_point_stall_window=a.fixed_point_stall_window)
        tab = row if tab is None else merge_levels(tab, row)
        tab["estimated_error"] = [float(h.estimated_error[k - 1]) for k in tab["levels"]]
        tab["paper_dofs"] = [hertz.PAPER_ADAPTIVE_DOFS.get(k) for k in tab["levels"]]
        out["table"] = tab
        save(a, out)
        print(format_table(row), flush=True)
    print(format_table(tab))
    print(f"nmg violations <= {max(max(v) for v in tab['nmg_violation']):.1e} (relative); failed: {failed_runs(tab)}")
    out["table"] = tab


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", nargs="+", default=["table", "accuracy", "cost"], choices=["table", "accuracy", "cost"])
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=list(hertz.PAPER_FRICTIONS))
    ap.add_argument("--reference-level", type=int, default=9)
    ap.add_argument("--accuracy-friction", type=float, default=0.0)
    ap.add_argument("--accuracy-adaptive", type=int, nargs=2, default=[3, 8])
    ap.add_argument("--accuracy-uniform", type=int, nargs=2, default=[2, 6])
    ap.add_argument("--cost-adaptive", type=int, nargs="+", default=[7, 8, 9, 10, 11])
    ap.add_argument("--cost-uniform", type=int, nargs="+", default=[5, 6, 7, 8])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--fixed-point-max", type=int, default=100, help="outer iterations of Algorithm 1 before 'no conv.'")
    ap.add_argument("--fixed-point-stall-window", type=int, default=FIXED_POINT_STALL_WINDOW,
                    help="Algorithm 1 stops as not converging when its change of s_n did not fall over this many outer "
                         "iterations (0: off)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes of the table")
    ap.add_argument("--out", default="out")
    ap.add_argument("--tag", default="", help="suffix of the JSON file name (runs split over processes)")
    ap.add_argument("--no-plot", dest="plot", action="store_false")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    out = {"argv": sys.argv[1:]}
    for part in a.parts:
        print(f"== {part}", flush=True)
        {"table": part_table, "accuracy": part_accuracy, "cost": part_cost}[part](a, out)
        save(a, out)


def save(a, out):
    with open(os.path.join(a.out, f"adaptive_table1{a.tag}.json"), "w") as fh:
        json.dump(out, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
