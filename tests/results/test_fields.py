"""Strain, stress and von Mises: the patch test (a linear displacement gives its exact uniform
strain and Hooke's stress on every cell type, per cell and recovered at the nodes), von Mises
against the principal-stress formula, and the uniaxial block solved by the core."""
import numpy as np
import pytest

from contactmg import Body, Dirichlet, Material, MeshHierarchy, Problem
from contactmg.examples.cylinders import cylinders_problem
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_TOP, rectangle
from contactmg.mesh.generators_3d import box
from contactmg.mesh.mesh import Mesh
from contactmg.model.material import cell_moduli
from contactmg.results.fields import cell_strain, hooke, nodal_average, problem_cell_moduli, von_mises

MAT = Material(210.0, 0.3)


def _distorted(mesh, seed=0):
    """The mesh with its points moved at random (the cells stay valid): no affine map of a cube."""
    rng = np.random.default_rng(seed)
    h = np.ptp(mesh.points, axis=0).min() / 20
    return Mesh.from_cells(mesh.points + h * rng.uniform(-1, 1, mesh.points.shape), mesh.cells, mesh.cell_type)


MESHES = {"triangle": lambda: _distorted(rectangle(5, 4, cell="triangle")),
          "quad": lambda: _distorted(rectangle(5, 4, cell="quad")),
          "tetra": lambda: _distorted(box(3, 2, 2, cell="tetra")),
          "hexahedron": lambda: _distorted(box(3, 2, 2, cell="hexahedron"))}


def _hooke_by_hand(eps, E, nu):
    """Isotropic Hooke in Voigt form (xx, yy, zz, yz, xz, xy; engineering shears)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[range(3), range(3)] += 2 * mu
    C[range(3, 6), range(3, 6)] = mu
    v = np.array([eps[0, 0], eps[1, 1], eps[2, 2], 2 * eps[1, 2], 2 * eps[0, 2], 2 * eps[0, 1]])
    s = C @ v
    return np.array([[s[0], s[5], s[4]], [s[5], s[1], s[3]], [s[4], s[3], s[2]]])


@pytest.mark.parametrize("cell", sorted(MESHES))
def test_patch_test_linear_displacement(cell):
    m = MESHES[cell]()
    d = m.dim
    G = np.random.default_rng(1).standard_normal((d, d)) * 1e-3
    u = m.points @ G.T + 0.01  # u = G x + a translation
    exact = np.zeros((3, 3))
    exact[:d, :d] = 0.5 * (G + G.T)
    E, nu = cell_moduli(m, MAT)
    eps = cell_strain(m, u)
    sigma = hooke(eps, E, nu)
    want = _hooke_by_hand(exact, MAT.E, MAT.nu)
    np.testing.assert_allclose(eps, np.broadcast_to(exact, eps.shape), rtol=0, atol=1e-14)
    np.testing.assert_allclose(sigma, np.broadcast_to(want, sigma.shape), rtol=0, atol=1e-12 * np.abs(want).max())
    nodal = nodal_average(m, sigma)
    np.testing.assert_allclose(nodal, np.broadcast_to(want, nodal.shape), rtol=0, atol=1e-12 * np.abs(want).max())
    if d == 2:  # plane strain: no zz strain, and the zz stress it takes
        assert np.all(eps[:, 2, :] == 0)
        np.testing.assert_allclose(sigma[:, 2, 2], MAT.nu * (sigma[:, 0, 0] + sigma[:, 1, 1]), rtol=1e-12)


def test_nodal_recovery_weights_cells_by_measure():
    m = rectangle(3, 1, lx=3.0, cell="quad")  # three unit squares in a row
    pts = m.points.copy()
    pts[pts[:, 0] > 2.5, 0] += 1.0  # the last square stretched to width 2
    m = Mesh.from_cells(pts, m.cells, m.cell_type)
    values = np.arange(m.num_cells, dtype=float)
    area = m.cell_measures()
    assert sorted(area) == pytest.approx([1.0, 1.0, 2.0])
    got = nodal_average(m, values)
    for node in range(m.num_points):
        cells = np.nonzero((m.cells == node).any(axis=1))[0]
        assert got[node] == pytest.approx(np.sum(area[cells] * values[cells]) / area[cells].sum())


def test_von_mises_against_principal_stresses_and_known_states():
    rng = np.random.default_rng(2)
    S = rng.standard_normal((50, 3, 3))
    S = S + S.transpose(0, 2, 1)
    p = np.linalg.eigvalsh(S)
    want = np.sqrt(0.5 * ((p[:, 0] - p[:, 1]) ** 2 + (p[:, 1] - p[:, 2]) ** 2 + (p[:, 2] - p[:, 0]) ** 2))
    np.testing.assert_allclose(von_mises(S), want, rtol=1e-12)
    uniaxial, shear, hydrostatic = np.zeros((3, 3)), np.zeros((3, 3)), -4.0 * np.eye(3)
    uniaxial[0, 0] = -7.0
    shear[0, 1] = shear[1, 0] = 2.0
    np.testing.assert_allclose(von_mises(np.array([uniaxial, shear, hydrostatic])), [7.0, 2.0 * np.sqrt(3), 0.0],
                               atol=1e-14)


def test_cell_moduli_broadcasts_a_material_and_refuses_others():
    m = rectangle(2, 2)
    E, nu = cell_moduli(m, MAT)
    assert E.shape == nu.shape == (m.num_cells,) and np.all(E == MAT.E) and np.all(nu == MAT.nu)
    with pytest.raises(TypeError, match="material must be a Material"):
        cell_moduli(m, (210.0, 0.3))


def test_several_bodies_take_each_body_s_material():
    p = cylinders_problem(2, E2=500.0, nu2=0.2)
    E, nu = problem_cell_moduli(p)
    want_E = np.concatenate([np.full(b.hierarchy.finest.num_cells, b.material.E) for b in p.bodies])
    assert np.array_equal(E, want_E) and set(E) == {p.bodies[0].material.E, 500.0} and 0.2 in set(nu)


def test_uniaxial_block_solved_by_the_core():
    """A unit square held by rollers on the bottom (y) and left (x) edges, pressed by -p on top:
    sigma_yy = -p, sigma_xx = 0, sigma_zz = -nu p (plane strain), von Mises
    p sqrt(1 - nu + nu^2); the bottom rollers carry the load p, the left ones nothing."""
    P = 3.0
    body = Body(MeshHierarchy.build(rectangle(4, 4, cell="quad"), 2), MAT,
                [Dirichlet([RECT_BOTTOM], (None, 0.0)), Dirichlet([RECT_LEFT], (0.0, None))],
                traction={RECT_TOP: (0.0, -P)})
    p = Problem(body)
    r = p.solve(tol=1e-13)
    want = np.diag([0.0, -P, -MAT.nu * P])
    for at in ("cells", "nodes"):
        s = r.stress(at)
        np.testing.assert_allclose(s, np.broadcast_to(want, s.shape), rtol=0, atol=1e-9 * P)
        np.testing.assert_allclose(r.von_mises(at), P * np.sqrt(1 - MAT.nu + MAT.nu ** 2), rtol=1e-9)
    R = r.reactions()
    np.testing.assert_allclose(R[RECT_BOTTOM], [0.0, P], rtol=0, atol=1e-9 * P)
    np.testing.assert_allclose(R[RECT_LEFT], [0.0, 0.0], rtol=0, atol=1e-9 * P)
    assert r.contact_forces() == {}  # no contact boundary
    with pytest.raises(ValueError, match="at must be 'cells' or 'nodes'"):
        r.stress("centroids")
