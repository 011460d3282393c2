"""3D finite elements: element stiffness against closed forms, the patch test, and a
manufactured solution's convergence rates under 3D refinement."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.mesh.generators_3d import box
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.mesh.mesh import Mesh
from contactmg.model.problem import Body, Dirichlet, Problem

MAT = Material(210.0, 0.3)
ALL_SIDES = [1, 2, 3, 4, 5, 6]


def dense(A):
    """The block matrix as a dense scalar matrix (dof 3 i + a)."""
    d = A.block_size
    rows = np.repeat(np.arange(len(A.indptr) - 1), np.diff(A.indptr))
    M = np.zeros(A.shape)
    for r, c, B in zip(rows, A.indices, A.data):
        M[d * r:d * r + d, d * c:d * c + d] += B
    return M


def elasticity_tensor(mat):
    C = np.zeros((6, 6))
    C[:3, :3] = mat.lam
    C[np.arange(3), np.arange(3)] += 2 * mat.mu
    C[np.arange(3, 6), np.arange(3, 6)] = mat.mu
    return C


def test_p1_tetrahedron_stiffness_is_BtCBV():
    X = np.array([[0.1, 0.0, 0.2], [1.3, 0.1, 0.0], [0.2, 0.9, 0.1], [0.3, 0.2, 1.1]])
    A = dense(_core.assemble_elasticity(X, np.array([[0, 1, 2, 3]]), "tetra", MAT.E, MAT.nu))
    # gradients of the barycentric coordinates: rows of inv([1 x])
    G = np.linalg.inv(np.c_[np.ones(4), X])[1:].T  # (4 nodes, 3)
    V = abs(np.linalg.det(np.c_[np.ones(4), X])) / 6
    B = np.zeros((6, 12))  # Voigt strain (xx, yy, zz, yz, xz, xy), engineering shear
    for a in range(4):
        gx, gy, gz = G[a]
        B[:, 3 * a:3 * a + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz], [0, gz, gy], [gz, 0, gx], [gy, gx, 0]]
    np.testing.assert_allclose(A, B.T @ elasticity_tensor(MAT) @ B * V, rtol=1e-12, atol=1e-12 * np.abs(A).max())


@pytest.mark.parametrize("cell", ["tetra", "hexahedron"])
def test_rigid_motions_are_the_kernel_and_linear_fields_have_their_exact_energy(cell):
    # a parallelepiped (affine: Q1 integrates the energy of a linear field exactly)
    m = box(2, 2, 2, cell=cell)
    J = np.array([[1.0, 0.3, 0.1], [0.0, 0.8, 0.2], [0.1, 0.0, 1.2]])
    X = m.points @ J.T
    A = _core.assemble_elasticity(X, m.cells, cell, MAT.E, MAT.nu)
    x = X - X.mean(0)
    for w in np.eye(3):
        np.testing.assert_allclose(A.matvec(np.tile(w, (len(X), 1))), 0, atol=1e-10)
        np.testing.assert_allclose(A.matvec(np.cross(w, x)), 0, atol=1e-10)
    Gu = np.array([[0.01, 0.02, -0.01], [0.00, -0.02, 0.03], [0.015, 0.0, 0.005]])
    u = X @ Gu.T
    eps = 0.5 * (Gu + Gu.T)
    energy = 0.5 * (MAT.lam * np.trace(eps) ** 2 + 2 * MAT.mu * np.sum(eps * eps)) * np.linalg.det(J)
    assert 0.5 * np.sum(u * A.matvec(u)) == pytest.approx(energy, rel=1e-12)


def distorted_box(cell, n=3, amount=0.2, seed=1):
    m = box(n, n, n, cell=cell)
    rng = np.random.default_rng(seed)
    P = m.points.copy()
    interior = np.all((P > 1e-9) & (P < 1 - 1e-9), axis=1)
    P[interior] += rng.uniform(-amount / n, amount / n, (int(interior.sum()), 3))
    return Mesh(P, m.cells, cell, m.facets, m.facet_tags)


@pytest.mark.parametrize("cell", ["tetra", "hexahedron"])
def test_patch_test_reproduces_a_linear_displacement(cell):
    Gu = np.array([[0.01, 0.02, -0.01], [0.0, -0.02, 0.03], [0.015, 0.0, 0.005]])
    c = np.array([0.001, -0.002, 0.003])
    exact = lambda x: x @ Gu.T + c  # noqa: E731
    h = MeshHierarchy.build(distorted_box(cell), 2)
    prob = Problem(Body(h, MAT, [Dirichlet(ALL_SIDES, exact)]))
    res = prob.solve(tol=1e-14)
    assert res.converged
    np.testing.assert_allclose(res.displacement, exact(prob.mesh.points), atol=1e-12)


def _manufactured(mat):
    """u = (x^2 y, y^2 z, z^2 x) and the body force f = -div sigma(u) (linear: P1 interpolates it)."""
    lam, mu = mat.lam, mat.mu

    def u(x):
        X, Y, Z = x.T
        return np.c_[X * X * Y, Y * Y * Z, Z * Z * X]

    def grad(x):  # G[i, a, b] = d u_a / d x_b
        X, Y, Z = x.T
        G = np.zeros((len(x), 3, 3))
        G[:, 0, 0], G[:, 0, 1] = 2 * X * Y, X * X
        G[:, 1, 1], G[:, 1, 2] = 2 * Y * Z, Y * Y
        G[:, 2, 2], G[:, 2, 0] = 2 * Z * X, Z * Z
        return G

    def f(x):
        X, Y, Z = x.T
        grad_div = np.c_[2 * Y + 2 * Z, 2 * X + 2 * Z, 2 * X + 2 * Y]
        lap = np.c_[2 * Y, 2 * Z, 2 * X]
        return -((lam + mu) * grad_div + mu * lap)

    return u, grad, f


def _tet_errors(mesh, uh, u, grad, mat):
    """Energy-norm and L2 errors of the P1 field uh, by the degree-2 4-point rule on every tet."""
    X = mesh.points[mesh.cells]                       # (m, 4, 3)
    M = np.concatenate([np.ones((len(X), 4, 1)), X], axis=2)
    inv = np.linalg.inv(M)                            # barycentric coordinate gradients in rows 1..3
    vol = np.abs(np.linalg.det(M)) / 6
    Gh = np.einsum("cka,cbk->cab", uh[mesh.cells], inv[:, 1:, :])
    a, b = 0.1381966011250105, 0.5854101966249685
    lams = np.array([[b, a, a, a], [a, b, a, a], [a, a, b, a], [a, a, a, b]])
    e_energy = e_l2 = 0.0
    for l in lams:
        xq = np.einsum("k,ckd->cd", l, X)
        uq = np.einsum("k,ckd->cd", l, uh[mesh.cells])
        E = grad(xq) - Gh
        eps = 0.5 * (E + E.transpose(0, 2, 1))
        dens = mat.lam * np.trace(eps, axis1=1, axis2=2) ** 2 + 2 * mat.mu * np.sum(eps * eps, axis=(1, 2))
        e_energy += np.sum(0.25 * vol * dens)
        e_l2 += np.sum(0.25 * vol * np.sum((u(xq) - uq) ** 2, axis=1))
    return np.sqrt(e_energy), np.sqrt(e_l2)


def test_manufactured_solution_converges_at_order_h_in_energy_and_h2_in_L2():
    u, grad, f = _manufactured(MAT)
    h = MeshHierarchy.build(box(2, 2, 2, cell="tetra"), 4)
    errors = []
    for levels in (2, 3, 4):
        sub = MeshHierarchy(h.meshes[:levels], h.transfers[:levels - 1])
        prob = Problem(Body(sub, MAT, [Dirichlet(ALL_SIDES, u)], body_force=f))
        res = prob.solve(tol=1e-12)
        assert res.converged
        errors.append(_tet_errors(prob.mesh, res.displacement, u, grad, MAT))
    errors = np.array(errors)
    rates = np.log2(errors[:-1] / errors[1:])
    assert np.all(rates[:, 0] > 0.85), rates   # energy: O(h)
    assert np.all(rates[:, 1] > 1.7), rates    # L2: O(h^2)
