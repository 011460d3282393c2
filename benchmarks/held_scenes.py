"""Scenes whose answer lies far from u = 0 or whose body only its contacts hold, built as a user
builds them (the public contactmg API, gmsh meshes through the gmsh Python API). Each builder is a
pure function of its size parameters returning a `contactmg.Problem`.

- sideways_block: a 2 x 1 block with no supports on a rigid floor, traction (0.2, -1) on its top,
  Coulomb 0.3: only friction holds it sideways.
- falling_block: the block 0.5 above the floor (half its height), pressed down by a pressure of 1.
- plate_on_cylinder: a 2 x 0.2 half plate (E 1000: its free end would deflect by about 3) pressed by a
  pressure of 1 onto a rigid cylinder of radius 1 under its symmetry plane x = 0; nothing but the
  cylinder holds it vertically.
- whole_plate_on_cylinder: the whole 4 x 0.2 plate, no supports, Coulomb 0.3 on the cylinder.
- thin_plate: a 4 x 0.2 plate clamped at both ends, pressed by a pressure of 1 across a gap of 0.005
  onto a rigid plane, Coulomb 0.3 (structured triangles or a gmsh mesh of size h).
- lone_block: a block given as a lone mesh (its only level), pressed 0.01 into a floor at its top,
  Coulomb 0.3 (2D triangles, 3D tetrahedra).
- falling_lone_block: the falling block given as a lone mesh of 2n x n cells (its coarse levels made
  from it).

balance(result) is the largest component of the sum of the load, the reactions, the elastic
supports' forces and the contact forces, relative to the load's.
"""
from __future__ import annotations

import numpy as np

import _common
import contactmg as cm
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_RIGHT, RECT_TOP

FLOOR = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0))


def _block(levels, origin=(0.0, 0.0)):
    return cm.MeshHierarchy.build(cm.rectangle(4, 2, 2.0, 1.0, origin=origin), levels)


def sideways_block(levels):
    body = cm.Body(_block(levels), cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM],
                   traction={RECT_TOP: (0.2, -1.0)})
    return cm.Problem(body, obstacle=FLOOR, friction=cm.Coulomb(0.3))


def falling_block(levels):
    body = cm.Body(_block(levels, origin=(0.0, 0.5)), cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM],
                   pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=FLOOR, friction=cm.Coulomb(0.3))


def falling_lone_block(n):
    mesh = cm.rectangle(2 * n, n, 2.0, 1.0, origin=(0.0, 0.5))
    body = cm.Body(cm.MeshHierarchy.build(mesh, 1), cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM],
                   pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=FLOOR, friction=cm.Coulomb(0.3))


def plate_on_cylinder(levels, friction=None):
    h = cm.MeshHierarchy.build(cm.rectangle(8, 2, 2.0, 0.2), levels)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [cm.Dirichlet(RECT_LEFT, (0.0, None))], contact_tags=[RECT_BOTTOM],
                   pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=cm.SphereObstacle((0.0, -1.0), 1.0), friction=friction)


def whole_plate_on_cylinder(levels):
    """The whole 4 x 0.2 plate (no symmetry plane) balanced on the cylinder, Coulomb 0.3: nothing but
    the friction of the nodes it stands on holds its rocking."""
    h = cm.MeshHierarchy.build(cm.rectangle(16, 2, 4.0, 0.2, origin=(-2.0, 0.0)), levels)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM], pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=cm.SphereObstacle((0.0, -1.0), 1.0), friction=cm.Coulomb(0.3))


def thin_plate_mesh(h=None):
    """The 4 x 0.2 plate: 20 x 1 structured cells (h None) or a gmsh mesh of size h."""
    if h is None:
        return cm.rectangle(20, 1, 4.0, 0.2)
    import gmsh

    def classify(c):
        if c[1] > 0.199:
            return RECT_TOP
        if c[1] < 0.001:
            return RECT_BOTTOM
        return RECT_LEFT if c[0] < 0.001 else RECT_RIGHT
    return _common.gmsh_mesh(lambda: gmsh.model.occ.addRectangle(0, 0, 0, 4, 0.2), classify, h, 2, one_region=True)


def thin_plate(mesh, levels):
    hier = cm.MeshHierarchy.build(mesh, levels)
    body = cm.Body(hier, cm.Material(1000.0, 0.3), [cm.Dirichlet(RECT_LEFT, (0.0, 0.0)),
                                                    cm.Dirichlet(RECT_RIGHT, (0.0, 0.0))],
                   contact_tags=[RECT_BOTTOM], pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, -0.005), (0.0, -1.0)), friction=cm.Coulomb(0.3))


def lone_block(n, dim):
    """A 2 x 1 block of 2n x n cells (2D triangles) or a unit cube of n^3 cells (3D tetrahedra) as
    its only level, its top pushed 0.01 down onto the floor."""
    if dim == 2:
        mesh, top, bottom, push = cm.rectangle(2 * n, n, 2.0, 1.0), RECT_TOP, RECT_BOTTOM, (0.0, -0.01)
    else:
        mesh, top, bottom, push = cm.box(n, n, n, cell="tetra"), 6, 5, (0.0, 0.0, -0.01)
    floor = cm.PlaneObstacle((0.0,) * dim, (0.0,) * (dim - 1) + (-1.0,))
    body = cm.Body(cm.MeshHierarchy.build(mesh, 1), cm.Material(1000.0, 0.3), [cm.Dirichlet(top, push)],
                   contact_tags=[bottom])
    return cm.Problem(body, obstacle=floor, friction=cm.Coulomb(0.3))


def balance(result) -> float:
    """max |load + reactions + spring forces + contact forces| / max |load| (components summed over
    the body)."""
    load = result.canonical_load().sum(axis=0)
    total = load + sum(result.contact_forces().values()) + sum(result.reactions().values(), np.zeros_like(load))
    total = total + sum(result.spring_forces().values(), np.zeros_like(load))
    scale = np.abs(load).max()
    if scale == 0:  # pushed by a prescribed displacement: the reactions are the scale
        scale = max(float(np.abs(v).max()) for v in result.reactions().values())
    return float(np.abs(total).max() / scale)
