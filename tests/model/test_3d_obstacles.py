"""Curved rigid obstacles: closest-point gaps and normals against closed forms, in frames
not aligned with the axes."""
import numpy as np
import pytest

from contactmg.model.obstacle import PlaneObstacle, RevolutionObstacle, SphereObstacle


def rotation(seed=3):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q if np.linalg.det(q) > 0 else -q


def test_sphere_outside_and_inside():
    c, R = np.array([0.3, -0.1, 0.2]), 0.5
    rng = np.random.default_rng(0)
    d = rng.normal(size=(20, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    dist = rng.uniform(0.6, 1.5, 20)
    x = c + dist[:, None] * d
    g, n = SphereObstacle(tuple(c), R).gaps_and_normals(x)       # a rigid ball, body outside
    np.testing.assert_allclose(g, dist - R, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(n, -d, atol=1e-14)
    # the node moved by g along n lands on the sphere
    np.testing.assert_allclose(np.linalg.norm(x + g[:, None] * n - c, axis=1), R, rtol=1e-14)
    x_in = c + 0.5 * dist[:, None] * d
    g, n = SphereObstacle(tuple(c), R, inside=True).gaps_and_normals(x_in)  # a cavity, body inside
    np.testing.assert_allclose(g, R - 0.5 * dist, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(n, d, atol=1e-14)
    with pytest.raises(ValueError, match="centre"):
        SphereObstacle(tuple(c), R).gaps_and_normals(c[None])


def test_revolution_cylinder_and_cone_against_closed_forms_in_a_rotated_frame():
    Q, p = rotation(), np.array([1.0, 2.0, -0.5])
    # profile: cylinder radius 1 for zeta >= 0, cone down to radius 0.5 at zeta = -1 (half-angle atan 0.5)
    wall = RevolutionObstacle(z=(-1.0, 0.0, 5.0), r=(0.5, 1.0, 1.0), point=tuple(p), axis=tuple(Q[:, 2]))
    rho = np.array([0.2, 0.7, 0.9, 0.8, 0.6])
    zeta = np.array([2.0, 3.0, -0.5, -0.2, -0.6])
    phi = np.linspace(0.1, 5.0, len(rho))
    local = np.c_[rho * np.cos(phi), rho * np.sin(phi), zeta]
    x = p + local @ Q.T
    g, n = wall.gaps_and_normals(x)
    e_rho = np.c_[np.cos(phi), np.sin(phi), np.zeros(len(phi))] @ Q.T
    # cylinder part: radial gap
    np.testing.assert_allclose(g[:2], 1.0 - rho[:2], rtol=1e-13)
    np.testing.assert_allclose(n[:2], e_rho[:2], atol=1e-13)
    # cone part: distance to the line r = 1 + 0.5 zeta in the meridian plane, normal (1, -0.5)/|.|
    m = np.array([1.0, -0.5]) / np.hypot(1.0, 0.5)
    cone_r = 1.0 + 0.5 * zeta[2:]
    dist = (cone_r - rho[2:]) * m[0]
    np.testing.assert_allclose(g[2:], dist, rtol=1e-12)
    np.testing.assert_allclose(n[2:], m[0] * e_rho[2:] + m[1] * Q[:, 2], atol=1e-12)
    # a node outside the wall (penetrating) has a negative gap and a normal back to the wall
    out = p + np.array([0.9, 0.0, -0.5]) @ Q.T
    g, n = wall.gaps_and_normals(out[None])
    assert g[0] == pytest.approx(-(0.9 - 0.75) * m[0], rel=1e-12)
    np.testing.assert_allclose(n[0], m[0] * Q[:, 0] + m[1] * Q[:, 2], atol=1e-12)


def test_revolution_corner_uses_the_direction_to_the_corner():
    # the profile's corner where a widening cone meets the cylinder above: a node pressed into the
    # wall beyond the corner has the corner as its closest point
    wall = RevolutionObstacle(z=(0.0, 1.0), r=(1.0, 2.0))  # r = 1 + z on [0, 1], 2 above
    x = np.array([[0.0, 2.1, 0.95]])
    g, n = wall.gaps_and_normals(x)
    d = np.hypot(0.1, 0.05)
    assert g[0] == pytest.approx(-d, rel=1e-12)
    np.testing.assert_allclose(n[0], np.array([0.0, 0.1, -0.05]) / d, atol=1e-12)
    # inside, next to the corner, the nearer wall segment wins: the cone for (1.8, 1.05), the
    # cylinder for (1.9, 1.3)
    g, n = wall.gaps_and_normals(np.array([[1.8, 0.0, 1.05], [1.9, 0.0, 1.3]]))
    np.testing.assert_allclose(g, [0.25 / np.sqrt(2), 0.1], rtol=1e-12)
    np.testing.assert_allclose(n, [[1 / np.sqrt(2), 0.0, -1 / np.sqrt(2)], [1.0, 0.0, 0.0]], atol=1e-12)


def test_plane_in_3d_and_bad_obstacle_input():
    g, n = PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -2.0)).gaps_and_normals(np.array([[1.0, 2.0, 0.3]]))
    assert g[0] == pytest.approx(0.3)
    np.testing.assert_allclose(n[0], [0, 0, -1])
    with pytest.raises(ValueError, match="increase"):
        RevolutionObstacle(z=(1.0, 0.0), r=(1.0, 1.0)).gaps_and_normals(np.ones((1, 3)))
    with pytest.raises(ValueError, match="axis"):
        RevolutionObstacle(z=(0.0,), r=(1.0,)).gaps_and_normals(np.array([[0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match="3D"):
        RevolutionObstacle(z=(0.0,), r=(1.0,)).gaps_and_normals(np.ones((2, 2)))
