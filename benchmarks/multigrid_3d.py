"""Issue 10: why 3D cycle counts grow. Per level: the mesh quality (tetrahedra: smallest and largest
dihedral angle, mean radius ratio; hexahedra: smallest scaled Jacobian) and the contraction of the
linear multigrid (no contact, zero load, random start; geometric mean of the last five correction
ratios) on the unit cube (Kuhn tetrahedra or hexahedra, clamped at z = 0), the Hertz half ball
(clamped top) and the cork (clamped top, the cork's material).

    python benchmarks/multigrid_3d.py [--geometries box ball cork] [--cells tetra hexahedron]
                                      [--levels 2 4] [--cycles V33 V66] [--count 30] [--json PATH]
"""
import argparse
import json
import time

from linear_multigrid import contraction

from contactmg import cork
from contactmg.generators_3d import (BALL_TOP, CORK_TOP, CylinderProjector, ball_projector, box, cylinder,
                                     half_ball)
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.problem import ContactProblem, Dirichlet
from contactmg.quality_3d import dihedral_angles, radius_ratio, scaled_jacobian


def hierarchy(geometry, cell, levels):
    if geometry == "box":
        return MeshHierarchy.build(box(2, 2, 2, cell=cell), levels), [5], Material(2000.0, 0.28)
    if geometry == "ball":
        return (MeshHierarchy.build(half_ball(cell), levels, projector=ball_projector()), [BALL_TOP],
                Material(2000.0, 0.28))
    mesh = cylinder(cork.RADIUS, cork.LENGTH, k=cork.K, ring_layers=cork.RING_LAYERS, nz=cork.AXIAL_LAYERS, cell=cell)
    return (MeshHierarchy.build(mesh, levels, projector=CylinderProjector(cork.RADIUS)), [CORK_TOP],
            Material(cork.E, cork.NU))


def quality(mesh):
    if mesh.cell_type == "tetra":
        a = dihedral_angles(mesh.points, mesh.cells)
        return {"min_dihedral": float(a.min()), "max_dihedral": float(a.max()),
                "mean_radius_ratio": float(radius_ratio(mesh.points, mesh.cells).mean())}
    j = scaled_jacobian(mesh.points, mesh.cells)
    return {"min_scaled_jacobian": float(j.min()), "mean_scaled_jacobian": float(j.mean())}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--geometries", nargs="+", default=["box", "ball", "cork"])
    ap.add_argument("--cells", nargs="+", default=["tetra", "hexahedron"])
    ap.add_argument("--levels", type=int, nargs=2, default=[2, 4])
    ap.add_argument("--cycles", nargs="+", default=["V33", "F33"], help="type and nu1 nu2, e.g. V33 F55")
    ap.add_argument("--count", type=int, default=30, help="cycles per rate measurement")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    for geo in a.geometries:
        for cell in a.cells:
            h, tags, material = hierarchy(geo, cell, a.levels[1])
            for L in range(a.levels[0], a.levels[1] + 1):
                sub = MeshHierarchy(h.meshes[:L], h.transfers[:L - 1])
                row = {"geometry": geo, "cell": cell, "level": L, "dofs": 3 * sub.finest.num_points,
                       **quality(sub.finest)}
                for c in a.cycles:
                    p = ContactProblem(sub, material, [Dirichlet(tags, (0.0, 0.0, 0.0))], cycle=c[0],
                                       nu1=int(c[1]), nu2=int(c[2]))
                    t0 = time.perf_counter()
                    row[c] = contraction(p, cycles=a.count)[0]
                    row[c + "_seconds"] = time.perf_counter() - t0
                rows.append(row)
                q = " ".join(f"{k}={v:.3f}" for k, v in row.items() if k in ("min_dihedral", "max_dihedral",
                             "mean_radius_ratio", "min_scaled_jacobian", "mean_scaled_jacobian"))
                r = " ".join(f"{c}={row[c]:.3f}" for c in a.cycles)
                print(f"{geo:5} {cell:10} L{L} dofs {row['dofs']:8d}  {q}  {r}", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
