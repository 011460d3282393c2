"""3D uniform refinement: node counts, volume, boundary facets and tags, the projection
onto curved surfaces, interpolation, shape stability of Bey's red refinement."""
import itertools

import numpy as np
import pytest

from contactmg import _core
from contactmg.mesh.generators_3d import (BALL_SURFACE, BALL_TOP, CORK_SIDE, CORK_TOP, CylinderProjector, ball_projector,
                                     box, cylinder, half_ball)
from contactmg.mesh.hierarchy import MeshHierarchy, estimate_nodes
from contactmg.mesh.mesh import Mesh, boundary_facets


@pytest.mark.parametrize("cell", ["tetra", "hexahedron"])
def test_box_refinement_counts_volume_facets_and_interpolation(cell):
    m = box(2, 1, 2, lx=1.0, ly=0.5, lz=2.0, cell=cell, origin=(0.3, -0.2, 0.1))
    h = MeshHierarchy.build(m, 3)
    f = h.finest
    # a box refined twice is the structured box with 4x the cells per side: its nodes are the grid's
    assert f.num_points == (8 + 1) * (4 + 1) * (8 + 1)
    assert f.num_cells == m.num_cells * 64
    assert [estimate_nodes(m, L) for L in (1, 2, 3)] == [x.num_points for x in h.meshes]
    assert f.cell_measures().min() > 0
    assert f.cell_measures().sum() == pytest.approx(1.0 * 0.5 * 2.0, rel=1e-13)
    # refined facets are exactly the boundary of the refined cells, with the same orientation
    assert _cyclic_set(f.facets) == _cyclic_set(boundary_facets(f.cells, cell))
    for tag in range(1, 7):  # each side keeps its area and tag
        a0 = m.facet_measures()[m.facet_tags == tag].sum()
        assert f.facet_measures()[f.facet_tags == tag].sum() == pytest.approx(a0, rel=1e-13)
    # interpolation reproduces linear fields
    lin = lambda x: x @ np.array([[1.0, 2.0, -1.0], [0.5, 0.0, 3.0], [0.0, -2.0, 1.0]]).T + 0.7  # noqa: E731
    for t, coarse, fine in zip(h.transfers, h.meshes[:-1], h.meshes[1:]):
        np.testing.assert_allclose(t.matrix() @ lin(coarse.points), lin(fine.points), atol=1e-12)
        np.testing.assert_allclose(t.matrix().sum(axis=1), 1.0, rtol=1e-15)


def _cyclic_set(facets):
    """Facets as a set, each rotated to start at its smallest node (orientation kept)."""
    return {tuple(np.roll(f, -int(np.argmin(f))).tolist()) for f in facets}


def test_interpolation_weights_are_those_of_the_brief():
    hx = box(1, 1, 1, cell="hexahedron")
    r = _core.refine(hx.points, hx.cells, "hexahedron", hx.facets, hx.facet_tags)
    counts = np.diff(r["ptr"])
    # 8 corners (1), 12 edge midpoints (1/2 x 2), 6 face centres (1/4 x 4), 1 cell centre (1/8 x 8)
    assert sorted(np.bincount(counts).tolist()) == sorted([0, 8, 12, 0, 6, 0, 0, 0, 1])
    for k, w in ((1, 1.0), (2, 0.5), (4, 0.25), (8, 0.125)):
        rows = np.flatnonzero(counts == k)
        for i in rows:
            np.testing.assert_array_equal(r["weight"][r["ptr"][i]:r["ptr"][i + 1]], w)
    # every new node on a facet (12 edges, 6 face centres) is listed for the projector, once
    assert len(r["boundary_nodes"]) == 18 == len(np.unique(r["boundary_nodes"]))
    assert r["facets"].shape == (24, 4)


def _similarity_classes(points, cells):
    keys = set()
    for c in cells:
        X = points[c]
        e = np.sort([np.linalg.norm(X[i] - X[j]) for i, j in itertools.combinations(range(4), 2)])
        keys.add(tuple(np.round(e / e[-1], 8)))
    return len(keys)


def test_bey_red_refinement_is_shape_stable():
    X = np.array([[0.0, 0.0, 0.0], [1.0, 0.1, 0.0], [0.3, 0.9, 0.2], [0.2, 0.3, 1.1]])
    m = Mesh.from_cells(X, np.array([[0, 1, 2, 3]]), "tetra")
    h = MeshHierarchy.build(m, 4)
    for k, mesh in enumerate(h.meshes[1:], start=1):
        assert mesh.num_cells == 8 ** k
        assert _similarity_classes(mesh.points, mesh.cells) <= 3
        assert mesh.cell_measures().min() > 0
        assert mesh.cell_measures().sum() == pytest.approx(m.cell_measures()[0], rel=1e-12)


@pytest.mark.parametrize("cell", ["tetra", "hexahedron"])
def test_half_ball_boundary_nodes_are_projected_onto_the_sphere(cell):
    c, R = np.array([0.0, 0.0, 0.4]), 0.4
    h = MeshHierarchy.build(half_ball(cell, k=2), 3, projector=ball_projector())
    vol_err = []
    for mesh in h.meshes:
        s = mesh.boundary_nodes([BALL_SURFACE])
        np.testing.assert_allclose(np.linalg.norm(mesh.points[s] - c, axis=1), R, rtol=1e-14)
        top = mesh.boundary_nodes([BALL_TOP])
        np.testing.assert_allclose(mesh.points[top, 2], 0.4, atol=1e-15)  # the rim stays in the top plane
        assert mesh.cell_measures().min() > 0
        vol_err.append(2 / 3 * np.pi * R ** 3 - mesh.cell_measures().sum())
    # the polyhedral volume converges to the ball's at O(h^2), from below
    assert np.all(np.array(vol_err) > 0)
    assert vol_err[0] / vol_err[1] > 3.5 and vol_err[1] / vol_err[2] > 3.5


def test_cylinder_rims_land_on_the_circle_and_the_top_stays_flat():
    h = MeshHierarchy.build(cylinder(1.0, 2.0), 3, projector=CylinderProjector(1.0))
    f = h.finest
    s = f.boundary_nodes([CORK_SIDE])
    np.testing.assert_allclose(np.hypot(f.points[s, 0], f.points[s, 1]), 1.0, rtol=1e-14)
    np.testing.assert_allclose(f.points[f.boundary_nodes([CORK_TOP]), 2], 2.0, rtol=1e-15)


def test_refinement_rejects_a_facet_that_is_not_a_face():
    # three tetrahedra around the edge x-y: the triangle a-b-c has all its edges in the mesh but is
    # no face of any cell
    P = np.array([[1.0, 0, 0], [-0.5, 0.9, 0], [-0.5, -0.9, 0], [0, 0, 1], [0, 0, -1]])
    a, b, c, x, y = range(5)
    m = Mesh.from_cells(P, np.array([[a, b, x, y], [b, c, x, y], [c, a, x, y]]), "tetra")
    with pytest.raises(ValueError, match="not a face"):
        _core.refine(m.points, m.cells, "tetra", np.array([[a, b, c]]), np.array([1]))
    with pytest.raises(ValueError, match="shape"):
        _core.refine(m.points, m.cells, "tetra", np.zeros((1, 4), np.int64), np.array([1]))
    hx = box(1, 1, 1, cell="hexahedron")
    with pytest.raises(ValueError, match="not a face"):
        _core.refine(hx.points, hx.cells, "hexahedron", np.array([[0, 1, 6, 7]]), np.array([1]))


def test_refined_kuhn_box_is_the_finer_kuhn_box():
    """Bey's ordering is consistent: refining the Kuhn split of a cube gives the Kuhn split of the
    8 half-size cubes, tetrahedron for tetrahedron."""
    f = MeshHierarchy.build(box(1, 1, 1, cell="tetra"), 3).finest
    s = box(4, 4, 4, cell="tetra")
    index = {tuple(np.round(p * 4).astype(int)): i for i, p in enumerate(s.points)}
    to_s = np.array([index[tuple(np.round(p * 4).astype(int))] for p in f.points])
    assert {frozenset(c) for c in to_s[f.cells].tolist()} == {frozenset(c) for c in s.cells.tolist()}
