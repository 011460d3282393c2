"""Obstacles given by a surface mesh (closest-point projection) and the rigid cylinder, against the
analytic obstacles they discretize."""
import meshio
import numpy as np
import pytest

import contactmg as cm

B, T = cm.RECT_BOTTOM, cm.RECT_TOP


def _floor_polyline(x0=-1.0, x1=3.0, n=7):
    x = np.linspace(x0, x1, n)
    return np.c_[x, np.zeros(n)], np.c_[np.arange(n - 1), np.arange(1, n)]


def test_a_polyline_floor_is_the_plane():
    pts, segs = _floor_polyline()
    x = np.random.default_rng(0).uniform([0, 0.0], [2, 0.5], (50, 2))
    g, n = cm.MeshObstacle(pts, segs).gaps_and_normals(x)
    g0, n0 = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)).gaps_and_normals(x)
    assert np.allclose(g, g0, atol=1e-15) and np.allclose(n, n0)
    # the segments' orientation does not matter: the body's side is taken from the nodes
    g2, n2 = cm.MeshObstacle(pts, segs[:, ::-1]).gaps_and_normals(x)
    assert np.allclose(g2, g0, atol=1e-15) and np.allclose(n2, n0)


def test_a_block_on_a_mesh_floor_solves_as_on_the_plane():
    h = cm.MeshHierarchy.build(cm.rectangle(4, 2, 2.0, 1.0, cell="quad"), 4)
    body = cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet(T, (0.01, -0.02))], contact_tags=B)
    pts, segs = _floor_polyline()
    a = cm.Problem(body, obstacle=cm.MeshObstacle(pts, segs), friction=cm.Coulomb(0.3)).solve()
    b = cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3)).solve()
    assert a.cycles == b.cycles
    np.testing.assert_allclose(a.displacement, b.displacement, rtol=0, atol=1e-14)


def _icosphere(refine=3):
    t = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
                  [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
                  [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11],
                  [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    v /= np.linalg.norm(v, axis=1)[:, None]
    for _ in range(refine):
        edges = {}
        pts = list(v)

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in edges:
                m = (v[a] + v[b]) / 2
                pts.append(m / np.linalg.norm(m))
                edges[key] = len(pts) - 1
            return edges[key]
        nf = []
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        v, f = np.array(pts), np.array(nf)
    return v, f


def test_a_triangulated_ball_is_the_sphere_to_its_chord_error(tmp_path):
    v, f = _icosphere(4)
    path = tmp_path / "ball.msh"
    meshio.write(path, meshio.Mesh(v, [("triangle", f)]), file_format="gmsh22")
    ball = cm.MeshObstacle.read(path)
    x = np.random.default_rng(1).normal(size=(40, 3))
    x = x / np.linalg.norm(x, axis=1)[:, None] * np.random.default_rng(2).uniform(1.05, 1.5, (40, 1))
    g, n = ball.gaps_and_normals(x)
    g0, n0 = cm.SphereObstacle((0.0, 0.0, 0.0), 1.0).gaps_and_normals(x)
    edge = np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1).max()
    assert np.abs(g - g0).max() <= edge ** 2           # the sagitta of the facets
    assert np.all(np.einsum("ij,ij->i", n, n0) > np.cos(edge))


def test_a_rigid_rod_and_a_bore():
    x = np.array([[2.0, 0.0, 5.0], [0.0, -3.0, -1.0]])
    g, n = cm.CylinderObstacle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0).gaps_and_normals(x)
    assert np.allclose(g, [1.0, 2.0]) and np.allclose(n, [[-1, 0, 0], [0, 1, 0]])
    g, n = cm.CylinderObstacle((0.0, 0.0, 0.0), (0.0, 0.0, 2.0), 4.0, inside=True).gaps_and_normals(x)
    assert np.allclose(g, [2.0, 1.0]) and np.allclose(n, [[1, 0, 0], [0, -1, 0]])
    with pytest.raises(ValueError, match="3D obstacle"):
        cm.CylinderObstacle((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0).gaps_and_normals(np.zeros((1, 2)))


def test_bad_surface_meshes_are_named():
    with pytest.raises(ValueError, match="segments"):
        cm.MeshObstacle(np.zeros((3, 2)), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="degenerate"):
        cm.MeshObstacle(np.zeros((2, 2)), np.array([[0, 1]]))
