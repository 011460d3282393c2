"""Engineering models made with gmsh, solved through the Python API, each checked: a block with
rounded corners pressed and sheared in load steps, a plate pressed by a pressure onto a rigid
support, a 3D cylinder with a filleted edge on a tilted plane, two non-matching bodies, a stack of
bodies of several materials held only by contact, and the block in three systems of units.

Per model: dofs, cycles (per step for a load path), the equilibrium of support reactions, contact
forces and load (relative), and the largest violation of the contact conditions (relative; the
independent check of contactmg.results.checks).

Meshes by gmsh (a dependency). Run: python benchmarks/model/engineering_models.py [--quick]"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _common import gmsh_mesh, parser, write_result  # noqa: E402

import contactmg as cm  # noqa: E402
from contactmg.results.checks import contact_conditions  # noqa: E402

BOTTOM, TOP, SIDE, OTHER = 1, 2, 3, 4


def balance(res) -> float:
    """|reactions + spring forces + obstacle forces + load| relative to the largest of them (0: equilibrium; a
    pair's forces on its two bodies cancel)."""
    forces = (list(res.reactions().values()) + list(res.spring_forces().values())
              + [f for k, f in res.contact_forces().items() if k.startswith("obstacle")])
    total = sum(forces, np.zeros(res.mesh.dim)) + res.canonical_load().sum(axis=0)
    scale = max([np.abs(f).max() for f in forces] + [np.abs(res.canonical_load().sum(axis=0)).max(), 1e-300])
    return float(np.abs(total).max() / scale)


def row(name, problem, results, seconds):
    results = results if isinstance(results, list) else [results]
    return {"model": name, "dofs": int(problem.mesh.num_points * problem.mesh.dim),
            "cycles": [r.cycles for r in results], "converged": all(r.converged for r in results),
            "balance": max(balance(r) for r in results),
            "conditions": max(contact_conditions(problem, r)["max"] for r in results),
            "seconds": round(seconds, 2)}


def rounded_block(size, length=1.0, stress=1.0):
    """A 2 x 1 block (lengths times `length`) with rounded corners of radius 0.15."""
    L = 1.0 / length
    mesh = gmsh_mesh(lambda: __import__("gmsh").model.occ.addRectangle(0, 0, 0, 2 * L, L, roundedRadius=0.15 * L),
                     lambda c: BOTTOM if c[1] < 0.3 * L else (TOP if c[1] > 0.99 * L else SIDE), size * L, 2)
    return mesh


def block_path(levels, size, length=1.0, stress=1.0, steps=4):
    mesh = rounded_block(size, length)
    h = cm.MeshHierarchy.build(mesh, levels)
    body = cm.Body(h, cm.Material(210e9 / stress, 0.3), [cm.Dirichlet(TOP, (0.0, 0.0))], contact_tags=BOTTOM)
    p = cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))
    press, shear = -2e-4 / length, 1e-4 / length
    path = cm.LoadPath(p, [k / steps for k in range(1, 2 * steps + 1)],
                       dirichlet=lambda t: [cm.Dirichlet(TOP, (shear * max(t - 1, 0), press * min(t, 1)))])
    return p, path


def plate(levels, size):
    """A 4 x 0.2 plate on elastic supports at its ends, pressed by a pressure onto a rigid cylinder
    of radius 1 that touches its middle."""
    import gmsh
    mesh = gmsh_mesh(lambda: gmsh.model.occ.addRectangle(-2, 0, 0, 4, 0.2),
                     lambda c: TOP if c[1] > 0.19 else (BOTTOM if c[1] < 0.01 else SIDE), size, 2)
    h = cm.MeshHierarchy.build(mesh, levels)
    # the ends rest on springs: stiff vertically, soft horizontally
    body = cm.Body(h, cm.Material(70e3, 0.33), [], contact_tags=BOTTOM, pressure={TOP: 0.5},
                   springs={SIDE: (1e2, 1e5)})
    return cm.Problem(body, obstacle=cm.SphereObstacle((0.0, -1.0), 1.0), friction=cm.Coulomb(0.2))


def fillet_cylinder(levels, size):
    """A cylinder of radius 0.5 and height 1 with a fillet of 0.1 on its lower edge, pressed 0.002
    onto a plane tilted by 10 degrees, Coulomb 0.3."""
    import gmsh

    def build():
        c = gmsh.model.occ.addCylinder(0, 0, 0.0, 0, 0, 1, 0.5)
        gmsh.model.occ.synchronize()
        # the circular edge at z = 0
        curves = [t for _, t in gmsh.model.getEntities(1) if abs(gmsh.model.occ.getCenterOfMass(1, t)[2]) < 1e-9]
        gmsh.model.occ.fillet([c], curves, [0.1])
    mesh = gmsh_mesh(build, lambda c: TOP if c[2] > 0.999 else BOTTOM, size, 3)
    h = cm.MeshHierarchy.build(mesh, levels)
    a = np.deg2rad(10.0)
    normal = (np.sin(a), 0.0, -np.cos(a))
    body = cm.Body(h, cm.Material(210e3, 0.3), [cm.Dirichlet(TOP, (0.0, 0.0, -0.002))], contact_tags=BOTTOM)
    # the plane touches the cylinder's lowest point along its normal
    x = h.finest.points[h.finest.boundary_nodes([BOTTOM])]
    point = x[np.argmax(x @ np.asarray(normal))]
    return cm.Problem(body, obstacle=cm.PlaneObstacle(tuple(point), normal), friction=cm.Coulomb(0.3))


def two_bodies(levels, size):
    """A block (mesh size `size`) pressed onto a wider one (size 1.7 `size`: the meshes do not
    match), the lower one clamped, Coulomb 0.2."""
    import gmsh
    lower = gmsh_mesh(lambda: gmsh.model.occ.addRectangle(0, 0, 0, 3, 1),
                      lambda c: TOP if c[1] > 0.99 else (BOTTOM if c[1] < 0.01 else SIDE), 1.7 * size, 2)
    upper = gmsh_mesh(lambda: gmsh.model.occ.addRectangle(0.5, 1, 0, 2, 1, roundedRadius=0.2),
                      lambda c: TOP if c[1] > 1.99 else (BOTTOM if c[1] < 1.3 else SIDE), size, 2)
    bodies = [cm.Body(cm.MeshHierarchy.build(upper, levels), cm.Material(210e3, 0.3),
                      [cm.Dirichlet(TOP, (0.001, -0.003))]),
              cm.Body(cm.MeshHierarchy.build(lower, levels), cm.Material(70e3, 0.33), [cm.Dirichlet(BOTTOM, (0.0, 0.0))])]
    return cm.Problem(bodies, contacts=[cm.ContactPair(0, 1, [BOTTOM], [TOP], search=0.2)], friction=cm.Coulomb(0.2))


def layered_stack(levels, size):
    """A block of two materials (a steel base under a rubber-like layer: two regions of one gmsh
    mesh) on a rigid floor, with a second block pressed onto it by a pressure; no supports at all:
    everything is held by contact."""
    import gmsh

    def build():
        gmsh.model.occ.addRectangle(0, 0, 0, 3, 0.6)
        gmsh.model.occ.addRectangle(0, 0.6, 0, 3, 0.4)
        gmsh.model.occ.fragment([(2, 1)], [(2, 2)])
    lower = gmsh_mesh(build, lambda c: TOP if c[1] > 0.99 else (BOTTOM if c[1] < 0.01 else SIDE), size, 2)
    upper = gmsh_mesh(lambda: gmsh.model.occ.addRectangle(1, 1, 0, 1, 0.5),
                      lambda c: TOP if c[1] > 1.49 else (BOTTOM if c[1] < 1.01 else SIDE), size, 2)
    bodies = [cm.Body(cm.MeshHierarchy.build(upper, levels), cm.Material(210e3, 0.3), [], pressure={TOP: 10.0}),
              cm.Body(cm.MeshHierarchy.build(lower, levels), {1: cm.Material(210e3, 0.3), 2: cm.Material(50.0, 0.45)},
                      [])]
    contacts = [cm.ContactPair(0, 1, [BOTTOM], [TOP], search=0.1),
                cm.ObstacleContact(1, BOTTOM, cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))]
    return cm.Problem(bodies, contacts=contacts, friction=cm.Coulomb(0.4))


def print_table(rows, keys):
    widths = [max(len(k), *(len(str(r[k])) for r in rows)) for k in keys]
    print("  ".join(k.ljust(w) for k, w in zip(keys, widths)))
    for r in rows:
        print("  ".join((f"{r[k]:.1e}" if isinstance(r[k], float) and k != "seconds" else str(r[k])).ljust(w)
                        for k, w in zip(keys, widths)))


def main():
    args = parser(__doc__).parse_args()
    levels, size = (2, 0.25) if args.quick else (4, 0.1)
    rows = []

    def timed(name, make, solve=lambda p: p.solve()):
        t0 = time.perf_counter()
        p = make()
        res = solve(p)
        rows.append(row(name, p, res if not isinstance(res, cm.PathResult) else res.steps, time.perf_counter() - t0))

    p_path = {}

    def path_solve(_):
        return p_path["path"].solve()

    def make_block():
        p, path = block_path(levels, size)
        p_path["path"] = path
        return p

    timed("rounded block, press then shear (8 steps)", make_block, path_solve)
    timed("plate pressed onto a rigid cylinder", lambda: plate(levels, size / 2))
    timed("3D cylinder with a fillet on a tilted plane", lambda: fillet_cylinder(levels if args.quick else 3, 0.25 if args.quick else 0.12))
    timed("two non-matching bodies", lambda: two_bodies(levels, size))
    timed("two materials and a body, held only by contact", lambda: layered_stack(levels, size))
    units = {}
    for name, (length, stress) in {"m, Pa": (1.0, 1.0), "mm, MPa": (1e-3, 1e6), "mm, Pa": (1e-3, 1.0)}.items():
        p = cm.Problem(cm.Body(cm.MeshHierarchy.build(rounded_block(size, length), levels),
                               cm.Material(210e9 / stress, 0.3), [cm.Dirichlet(TOP, (0.0, -2e-4 / length))],
                               contact_tags=BOTTOM),
                       obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))
        t0 = time.perf_counter()
        res = p.solve()
        rows.append(row(f"rounded block in {name}", p, res, time.perf_counter() - t0))
    print_table(rows, ["model", "dofs", "cycles", "converged", "balance", "conditions", "seconds"])
    write_result(__file__, args, rows)


if __name__ == "__main__":
    main()
