"""Contraction per cycle of the linear multigrid (no contact, zero load, random start; geometric
mean of the last five correction ratios) for several cycles, with setup seconds and seconds per
cycle: in 2D on the rectangle and the Hertz half disk (triangles, quadrilaterals; V(1,1) ... F(3,3)),
in 3D on the unit cube, the Hertz half ball and the cork (tetrahedra, hexahedra), there with the
mesh quality per level (tetrahedra: smallest and largest dihedral angle, mean radius ratio;
hexahedra: smallest and mean scaled Jacobian). The contact solver's cycles cannot beat these rates.

    python benchmarks/methods/linear_multigrid.py [--dims 2 3] [--levels 3 8] [--levels-3d 2 4]
        [--cells triangle] [--cycles V11 V22 V33 W33 F33] [--quick] [--json PATH]
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

import contactmg as cm  # noqa: E402
from contactmg.examples import cork  # noqa: E402
from contactmg.mesh.quality import dihedral_angles, radius_ratio, scaled_jacobian  # noqa: E402
from contactmg.solve.options import with_cycle  # noqa: E402
from contactmg.solve.solver import Solver


def contraction(problem, cycles=14, seed=0):
    """Zero load, random start: the correction norms decay like the error; the rate is the
    geometric mean of the last five ratios. Returns (rate, seconds per cycle)."""
    rng = np.random.default_rng(seed)
    u0 = rng.standard_normal(problem.load.shape)
    # a solver of its own, whose core takes the zero load (the problem's kept solver is untouched)
    res = Solver(problem, problem.default_options).solve(
        u0, load=np.zeros_like(problem.load), options=dict(tol=1e-300, rtol=1e-300, max_cycles=cycles))
    c = np.asarray(res.history["correction_norm"])
    ratios = c[1:] / c[:-1]
    return float(np.exp(np.mean(np.log(ratios[-5:])))), res.solve_seconds / res.cycles


def hierarchy(geometry, cell, levels):
    """(hierarchy, material, Dirichlet conditions) of a geometry, clamped where it is held."""
    mat = cm.Material(2000.0, 0.28)
    if geometry == "hertz":
        h = cm.MeshHierarchy.build(cm.hertz_half_disk(cell), levels, projector=cm.hertz_projector())
        return h, mat, [cm.Dirichlet([cm.HERTZ_TOP], (0.0, 0.0))]
    if geometry == "rectangle":
        return cm.MeshHierarchy.build(cm.rectangle(2, 2, cell=cell), levels), mat, [cm.Dirichlet([cm.RECT_LEFT], (0.0, 0.0))]
    zero = (0.0, 0.0, 0.0)
    if geometry == "box":
        return cm.MeshHierarchy.build(cm.box(2, 2, 2, cell=cell), levels), mat, [cm.Dirichlet([5], zero)]
    if geometry == "ball":
        h = cm.MeshHierarchy.build(cm.half_ball(cell), levels, projector=cm.ball_projector())
        return h, mat, [cm.Dirichlet([cm.BALL_TOP], zero)]
    mesh = cm.cylinder(cork.RADIUS, cork.LENGTH, k=cork.K, ring_layers=cork.RING_LAYERS, nz=cork.AXIAL_LAYERS, cell=cell)
    h = cm.MeshHierarchy.build(mesh, levels, projector=cm.CylinderProjector(cork.RADIUS))
    return h, cm.Material(cork.E, cork.NU), [cm.Dirichlet([cm.CORK_TOP], zero)]


def quality(mesh):
    """Shape measures of a 3D mesh's cells."""
    if mesh.cell_type == "tetra":
        a = dihedral_angles(mesh.points, mesh.cells)
        return {"min_dihedral": float(a.min()), "max_dihedral": float(a.max()),
                "mean_radius_ratio": float(radius_ratio(mesh.points, mesh.cells).mean())}
    j = scaled_jacobian(mesh.points, mesh.cells)
    return {"min_scaled_jacobian": float(j.min()), "mean_scaled_jacobian": float(j.mean())}


def rows_of(geometries, cells, levels, cycles, count):
    """One row per (geometry, cell, level): dofs, quality (3D), and per cycle rate and seconds."""
    rows = []
    for geo in geometries:
        for cell in cells:
            t0 = time.perf_counter()
            h, mat, bcs = hierarchy(geo, cell, levels[1])
            build = time.perf_counter() - t0
            dim = h.finest.points.shape[1]
            for L in range(levels[0], levels[1] + 1):
                sub = cm.MeshHierarchy(h.meshes[:L], h.transfers[:L - 1])
                row = {"geometry": geo, "cell": cell, "level": L, "dofs": dim * sub.finest.num_points}
                if dim == 3:
                    row.update(quality(sub.finest))
                for c in cycles:
                    p = with_cycle(cm.Problem(cm.Body(sub, mat, bcs)), c[0], int(c[1]), int(c[2]))
                    t0 = time.perf_counter()
                    p.solver.core  # noqa: B018 - builds the coarse hierarchy
                    row.setdefault("setup_seconds", time.perf_counter() - t0 + (build if L == levels[1] else 0.0))
                    rate, spc = contraction(p, cycles=count)
                    row[c] = {"rate": rate, "seconds_per_cycle": spc}
                rows.append(row)
                print(f"{geo:9} {cell:10} {L:3d} {row['dofs']:9d} {row['setup_seconds']:8.2f} "
                      + " ".join(f"{c}={row[c]['rate']:.3f} ({1e3 * row[c]['seconds_per_cycle']:.1f} ms)" for c in cycles),
                      flush=True)
    return rows


def main():
    ap = parser(__doc__)
    ap.add_argument("--dims", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--levels", type=int, nargs=2, default=[3, 8], help="2D levels (first last)")
    ap.add_argument("--cells", nargs="+", default=["triangle"], help="2D cells")
    ap.add_argument("--geometries", nargs="+", default=["rectangle", "hertz"], help="2D geometries")
    ap.add_argument("--cycles", nargs="+", default=["V11", "V22", "V33", "W33", "F33"], help="2D cycles: type nu1 nu2")
    ap.add_argument("--levels-3d", type=int, nargs=2, default=[2, 4])
    ap.add_argument("--cells-3d", nargs="+", default=["tetra", "hexahedron"])
    ap.add_argument("--geometries-3d", nargs="+", default=["box", "ball", "cork"])
    ap.add_argument("--cycles-3d", nargs="+", default=["V33", "F33"])
    ap.add_argument("--count", type=int, default=20, help="cycles per rate measurement")
    a = ap.parse_args()
    if a.quick:
        a.levels, a.levels_3d, a.cycles, a.cycles_3d, a.count = [2, 4], [1, 2], ["V11", "V33", "F33"], ["V33"], 12
    print(f"{'geometry':9} {'cell':10} {'lvl':>3} {'dofs':>9} {'setup s':>8} rate (time) per cycle")
    out = {}
    if 2 in a.dims:
        out["2d"] = rows_of(a.geometries, a.cells, a.levels, a.cycles, a.count)
    if 3 in a.dims:
        out["3d"] = rows_of(a.geometries_3d, a.cells_3d, a.levels_3d, a.cycles_3d, a.count)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
