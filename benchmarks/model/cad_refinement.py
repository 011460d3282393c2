"""Refinement that follows the CAD geometry (contactmg.mesh.cad.CadModel): a cylinder with a
filleted edge and a torus, made with gmsh's OpenCASCADE kernel, written as .brep and read back.

Geometry table, per model and level: nodes, the largest distance of the new boundary nodes from
gmsh's closest point on their CAD surface or curve, and the smallest cell quality (normalized radius
ratio) with the relaxation of the interior nodes next to projected ones and without; for the
Netgen-optimized coarse mesh (the default) and gmsh's own (with "caps": tetrahedra with two faces
on the boundary, whose children projection flattens).

Contact table: the fillet cylinder pressed 0.02 onto a plane tilted by 10 degrees that touches the
fillet (Coulomb 0.3), per level: the total contact force with the CAD projector and without it
(faceted: new boundary nodes stay on the coarse mesh's flat facets), and the change from the level
before. The faceted hierarchy converges to the answer of the polyhedral coarse body, the CAD one to
that of the cylinder.

Needs gmsh (pip install gmsh). Run: python benchmarks/model/cad_refinement.py [--quick]"""
from __future__ import annotations

import os
import sys
import tempfile
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _common import parser, write_result  # noqa: E402

import contactmg as cm  # noqa: E402
from contactmg.mesh.cad import CadModel  # noqa: E402

BOTTOM, TOP, SIDE = 1, 2, 3


def write_brep(path, build):
    """Write the OpenCASCADE geometry build() adds to `path`; returns what build() returns."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        out = build()
        gmsh.model.occ.synchronize()
        gmsh.write(path)
        return out
    finally:
        gmsh.finalize()


def fillet_cylinder():
    """A cylinder of radius 0.5 and height 1 with a fillet of radius 0.1 on its lower edge; returns
    the groups {BOTTOM: bottom face and fillet, TOP: top face, SIDE: side} by surface entity."""
    import gmsh

    c = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 1, 0.5)
    gmsh.model.occ.synchronize()
    lower = [t for _, t in gmsh.model.getEntities(1) if abs(gmsh.model.occ.getCenterOfMass(1, t)[2]) < 1e-9]
    gmsh.model.occ.fillet([c], lower, [0.1])
    gmsh.model.occ.synchronize()
    groups = {BOTTOM: [], TOP: [], SIDE: []}
    for _, t in gmsh.model.getEntities(2):
        z = gmsh.model.occ.getCenterOfMass(2, t)[2]
        groups[TOP if z > 0.999 else (BOTTOM if z < 0.1 else SIDE)].append(t)
    return groups


def torus():
    """A torus of radii 1 and 0.3."""
    import gmsh

    gmsh.model.occ.addTorus(0, 0, 0, 1.0, 0.3)


def geometry_rows(name, path, size, levels, groups=None):
    rows = []
    for optimize in ("Netgen", None):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the caps and the degradation are what is measured
            with CadModel(path, size=size, groups=groups, optimize=optimize) as cad:
                t0 = time.perf_counter()
                h = cm.MeshHierarchy.build(cad.mesh, levels, projector=cad.projector())
                seconds = time.perf_counter() - t0
                plain = cm.MeshHierarchy.build(cad.mesh, levels, projector=cad.projector(), relax=False)
                n0 = cad.mesh.num_points
                for k, m in enumerate(h.meshes):
                    rows.append({"model": name, "coarse mesh": optimize or "gmsh", "caps": cad.caps, "level": k + 1,
                                 "nodes": m.num_points,
                                 "distance": float(cad.distance(m, start=n0).max(initial=0.0)),
                                 "min quality": round(h.min_quality[k], 4),
                                 "without relaxation": round(plain.min_quality[k], 4),
                                 "seconds": round(seconds, 2)})
    return rows


def contact_force(mesh, levels, projector):
    """Total contact force (its length), cycles, convergence and dofs of the fillet cylinder pressed
    0.02 onto the tilted plane, on `levels` levels (the contact patch, about 0.06 by 0.13, is a few
    cells wide on level 4)."""
    h = cm.MeshHierarchy.build(mesh, levels, projector=projector)
    a = np.deg2rad(10.0)
    normal = np.array([np.sin(a), 0.0, -np.cos(a)])
    # the plane touches the fillet's torus (centre circle of radius 0.4 at z = 0.1, tube 0.1) at
    # its lowest point along the normal: the same plane for every mesh
    point = np.array([0.4, 0.0, 0.1]) + 0.1 * normal
    body = cm.Body(h, cm.Material(210e3, 0.3), [cm.Dirichlet(TOP, (0.0, 0.0, -0.02))], contact_tags=BOTTOM)
    p = cm.Problem(body, obstacle=cm.PlaneObstacle(tuple(point), tuple(normal)), friction=cm.Coulomb(0.3))
    # one level is no multigrid: its smoother alone needs many more cycles
    res = p.solve(options={"max_cycles": 5000} if levels == 1 else None)
    f = res.contact_forces()["obstacle"]
    return float(np.linalg.norm(f)), res.cycles, res.converged, int(h.finest.num_points * 3)


def contact_rows(path, size, levels, groups):
    rows = []
    with CadModel(path, size=size, groups=groups) as cad:
        for k in range(1, levels + 1):
            t0 = time.perf_counter()
            cad_f, cycles, ok1, dofs = contact_force(cad.mesh, k, cad.projector())
            flat_f, _, ok2, _ = contact_force(cad.mesh, k, None)
            rows.append({"level": k, "dofs": dofs, "force cad": cad_f, "force faceted": flat_f,
                         "change cad": None if not rows else abs(cad_f - rows[-1]["force cad"]),
                         "change faceted": None if not rows else abs(flat_f - rows[-1]["force faceted"]),
                         "cycles": cycles, "converged": ok1 and ok2,
                         "seconds": round(time.perf_counter() - t0, 1)})
            print(rows[-1], flush=True)
    return rows


def print_table(rows, keys):
    def fmt(k, v):
        if isinstance(v, float) and k not in ("seconds", "min quality", "without relaxation"):
            return f"{v:.3e}"
        return str(v)
    widths = [max(len(k), *(len(fmt(k, r[k])) for r in rows)) for k in keys]
    print("  ".join(k.ljust(w) for k, w in zip(keys, widths)))
    for r in rows:
        print("  ".join(fmt(k, r[k]).ljust(w) for k, w in zip(keys, widths)))


def main():
    args = parser(__doc__).parse_args()
    geo_levels, contact_levels = (3, 2) if args.quick else (4, 4)
    with tempfile.TemporaryDirectory() as tmp:
        fillet_path, torus_path = os.path.join(tmp, "fillet.brep"), os.path.join(tmp, "torus.brep")
        groups = write_brep(fillet_path, fillet_cylinder)
        write_brep(torus_path, torus)
        geometry = (geometry_rows("fillet cylinder", fillet_path, 0.2, geo_levels, groups)
                    + geometry_rows("torus", torus_path, 0.3, geo_levels))
        print_table(geometry, ["model", "coarse mesh", "caps", "level", "nodes", "distance", "min quality",
                               "without relaxation", "seconds"])
        print()
        contact = contact_rows(fillet_path, 0.3 if args.quick else 0.2, contact_levels, groups)
        print_table(contact, ["level", "dofs", "force cad", "force faceted", "change cad", "change faceted", "cycles",
                              "converged", "seconds"])
    write_result(__file__, args, {"geometry": geometry, "contact": contact})


if __name__ == "__main__":
    main()
