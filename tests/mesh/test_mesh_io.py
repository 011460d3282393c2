"""Mesh type, generators and meshio round trips."""
import meshio
import numpy as np
import pytest

from contactmg.examples import hertz
from contactmg.mesh.generators import HERTZ_ARC, HERTZ_TOP, CircleProjector, hertz_half_disk, rectangle
from contactmg.mesh.io import read_mesh, write_mesh
from contactmg.mesh.mesh import Mesh


def min_angle(m):
    X = m.points[m.cells]
    k = X.shape[1]
    ang = []
    for i in range(k):
        a, b = X[:, (i - 1) % k] - X[:, i], X[:, (i + 1) % k] - X[:, i]
        ang.append(np.degrees(np.arccos(np.sum(a * b, 1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1))))
    return np.min(ang), np.max(ang)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_hertz_half_disk_geometry(cell):
    m = hertz_half_disk(cell)
    assert 20 <= m.num_points <= 100
    arc = m.boundary_nodes([HERTZ_ARC])
    top = m.boundary_nodes([HERTZ_TOP])
    np.testing.assert_allclose(np.linalg.norm(m.points[arc] - [0, 0.4], axis=1), 0.4, atol=1e-15)
    np.testing.assert_allclose(m.points[top, 1], 0.4, atol=1e-15)
    assert np.any(np.all(m.points == [0.0, 0.0], axis=1))                # node at the touching point
    mirrored = np.c_[-m.points[:, 0], m.points[:, 1]]
    d = np.linalg.norm(mirrored[:, None] - m.points[None], axis=2).min(1)
    assert d.max() < 1e-14                                                # symmetric about x = 0
    assert np.all(m.cell_measures() > 0)
    lo, hi = min_angle(m)
    assert lo > (35 if cell == "triangle" else 55) and hi < 136
    # area: the polygon inscribed in the half circle, close to pi r^2 / 2
    area = m.cell_measures().sum()
    assert 0.97 * np.pi * 0.16 / 2 < area < np.pi * 0.16 / 2
    # outward normals: the closed boundary integrates n ds to zero; top normals point up
    n, ds = m.facet_normals(), m.facet_measures()
    np.testing.assert_allclose((n * ds[:, None]).sum(0), 0, atol=1e-14)
    np.testing.assert_allclose(n[m.facet_tags == HERTZ_TOP], [[0, 1]] * int(np.sum(m.facet_tags == HERTZ_TOP)), atol=1e-14)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_rectangle_tags_and_area(cell):
    m = rectangle(5, 3, lx=2.0, ly=0.75, cell=cell, distort=0.2, seed=1)
    np.testing.assert_allclose(m.cell_measures().sum(), 1.5, rtol=1e-14)
    L = m.facet_measures()
    for tag, length in ((1, 2.0), (2, 0.75), (3, 2.0), (4, 0.75)):
        np.testing.assert_allclose(L[m.facet_tags == tag].sum(), length, rtol=1e-14)


def test_clockwise_cells_are_reoriented():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    m = Mesh.from_cells(pts, np.array([[0, 2, 1], [0, 3, 2]]), "triangle")
    assert np.all(m.cell_measures() > 0)
    q = Mesh.from_cells(pts, np.array([[0, 3, 2, 1]]), "quad")
    assert q.cell_measures()[0] == pytest.approx(1.0)


@pytest.mark.parametrize("points,cells,cell_type,match", [
    (np.array([[0, 0], [1, 0], [2, 0.0]]), np.array([[0, 1, 2]]), "triangle", "degenerate"),
    (np.array([[0, 0], [1, 0], [0.2, 0.2], [0, 1.0]]), np.array([[0, 1, 2, 3]]), "quad", "not convex"),
    # the second triangle is inverted: folded back over the first across their shared edge 1-2
    (np.array([[0, 0], [1, 0], [0, 1], [0.2, 0.2]]), np.array([[0, 1, 2], [1, 2, 3]]), "triangle", "inverted"),
    # a convex trapezoid folded into the unit square across their shared edge 0-1
    (np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.2, 0.5], [0.8, 0.5]]),
     np.array([[0, 1, 2, 3], [1, 0, 4, 5]]), "quad", "inverted"),
    (np.array([[0, 0], [1, np.nan], [0, 1.0]]), np.array([[0, 1, 2]]), "triangle", "non-finite"),
    (np.array([[0, 0], [1, 0], [0, 1.0]]), np.array([[0, 1, 3]]), "triangle", "outside"),
    (np.array([[0, 0], [1, 0], [0, 1.0]]), np.array([[0, 1, 1]]), "triangle", "repeats"),
    (np.array([[0, 0], [1, 0], [0, 1.0]]), np.array([[0, 1, 2]]), "hexagon", "unknown cell type"),
    (np.array([[0, 0], [1, 0], [0, 1.0]]), np.array([[0, 1]]), "triangle", "shape"),
    (np.array([0.0, 1.0, 2.0]), np.array([[0, 1, 2]]), "triangle", "shape"),
])
def test_bad_meshes_raise_clear_errors(points, cells, cell_type, match):
    with pytest.raises(ValueError, match=match):
        Mesh.from_cells(points, cells, cell_type)


def test_circle_projector_moves_only_tagged_points():
    proj = CircleProjector((0.0, 0.4), 0.4, tags=(1,))
    chord_mid = np.array([[0.5 * (0.4 * np.cos(4.0) + 0.4 * np.cos(4.2)), 0.4 + 0.5 * (0.4 * np.sin(4.0) + 0.4 * np.sin(4.2))]] * 2)
    out = proj(chord_mid, np.array([1, 2]))
    assert np.linalg.norm(out[0] - [0, 0.4]) == pytest.approx(0.4, abs=1e-15)
    np.testing.assert_array_equal(out[1], chord_mid[1])


@pytest.mark.parametrize("ext", [".vtu", ".msh"])
@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_mesh_round_trip(tmp_path, ext, cell):
    m = hertz_half_disk(cell)
    path = tmp_path / f"m{ext}"
    kw = {"file_format": "gmsh22", "binary": False} if ext == ".msh" else {}
    write_mesh(path, m, **kw)
    r = read_mesh(path)
    np.testing.assert_array_equal(r.points, m.points)
    np.testing.assert_array_equal(r.cells, m.cells)
    key = lambda mesh: sorted(zip(map(tuple, np.sort(mesh.facets, 1).tolist()), mesh.facet_tags.tolist()))  # noqa: E731
    assert key(r) == key(m)


def test_result_round_trip(tmp_path):
    p = hertz.hertz_problem("triangle", 4, 0.4)
    res = p.solve()
    path = tmp_path / "r.vtu"
    res.write_vtu(path)
    back = meshio.read(path)
    np.testing.assert_allclose(back.point_data["displacement"][:, :2], res.displacement, rtol=0, atol=0)
    assert np.all(back.point_data["displacement"][:, 2] == 0)
    sn = back.point_data["normal_stress"]
    np.testing.assert_allclose(sn[res.contact_nodes], res.normal_stress)
    np.testing.assert_array_equal(back.point_data["node_state"], res.node_state)
    np.testing.assert_allclose(back.point_data["tangential_stress"][res.contact_nodes], res.tangential_stress[:, 0])


def test_read_errors(tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        read_mesh(tmp_path / "missing.msh")
    bad = tmp_path / "bad.vtu"
    bad.write_bytes(b"\x00\x01garbage")
    with pytest.raises(ValueError, match="cannot read"):
        read_mesh(bad)
    mixed = meshio.Mesh(np.array([[0, 0], [1, 0], [1, 1], [0, 1.0], [2, 0]]),
                        [("triangle", np.array([[1, 4, 2]])), ("quad", np.array([[0, 1, 2, 3]]))])
    with pytest.raises(ValueError, match="mixed cell types"):
        read_mesh(mixed)
    with pytest.raises(ValueError, match="does not exist"):
        write_mesh(tmp_path / "nodir" / "x.vtu", hertz_half_disk())
