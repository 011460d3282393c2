"""Finite-element core: assembly, loads, refinement and transfer."""
import numpy as np
import pytest
import scipy.sparse as sp

from contactmg import _core
from contactmg.mesh.generators import hertz_half_disk, hertz_projector, rectangle
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.mesh.mesh import Mesh
from helpers import to_scipy

MAT = Material(1.0, 0.3)


def stiffness(mesh, mat=MAT):
    return to_scipy(_core.assemble_elasticity(mesh.points, mesh.cells, mesh.cell_type, mat.E, mat.nu))


def rigid_modes(x):
    x = x - x.mean(0)
    t1 = np.tile([1.0, 0.0], (len(x), 1))
    t2 = np.tile([0.0, 1.0], (len(x), 1))
    rot = np.c_[-x[:, 1], x[:, 0]]
    return [m.ravel() for m in (t1, t2, rot)]


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_stiffness_symmetric_rigid_kernel_and_positive_after_elimination(cell):
    mesh = rectangle(5, 4, lx=2.0, ly=1.0, cell=cell, distort=0.2, seed=3)
    K = stiffness(mesh).toarray()
    assert np.abs(K - K.T).max() < 1e-13 * np.abs(K).max()
    for m in rigid_modes(mesh.points):
        assert np.abs(K @ m).max() < 1e-12 * np.abs(K).max() * np.abs(m).max()
    ev = np.linalg.eigvalsh(K)
    assert np.sum(ev < 1e-10 * ev.max()) == 3  # exactly the three rigid modes
    free = np.setdiff1d(np.arange(K.shape[0]), (mesh.boundary_nodes([4])[:, None] * 2 + [0, 1]).ravel())
    assert np.linalg.eigvalsh(K[np.ix_(free, free)]).min() > 1e-8 * ev.max()


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_patch_test_linear_field_on_distorted_mesh(cell):
    """A linear displacement is reproduced to round-off: with it prescribed on the boundary and no
    load, the discrete solution is the linear field itself."""
    mesh = rectangle(6, 5, cell=cell, distort=0.25, seed=1)
    K = stiffness(mesh)
    G = np.array([[0.3, -0.7], [0.2, 0.5]])
    u_exact = (mesh.points @ G.T + [0.1, -0.2]).ravel()
    bnd = (mesh.boundary_nodes()[:, None] * 2 + [0, 1]).ravel()
    free = np.setdiff1d(np.arange(K.shape[0]), bnd)
    rhs = -K[free][:, bnd] @ u_exact[bnd]
    u = u_exact.copy()
    u[free] = sp.linalg.spsolve(K[free][:, free].tocsc(), rhs)
    assert np.abs(u - u_exact).max() < 1e-12


def test_element_stiffness_against_closed_form_p1():
    """Reference right triangle: the P1 stiffness from the B-matrix formula B^T D B * area."""
    x = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    mat = Material(3.0, 0.25)
    K = to_scipy(_core.assemble_elasticity(x, np.array([[0, 1, 2]]), "triangle", mat.E, mat.nu)).toarray()
    area = 1.0
    grads = np.linalg.inv(np.c_[np.ones(3), x])[1:].T  # rows: grad phi_a
    B = np.zeros((3, 6))
    for a, (gx, gy) in enumerate(grads):
        B[:, 2 * a:2 * a + 2] = [[gx, 0], [0, gy], [gy, gx]]
    lam, mu = mat.lam, mat.mu
    D = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
    np.testing.assert_allclose(K, B.T @ D @ B * area, atol=1e-13)


def test_loads_integrate_exactly():
    """Body-force load sums to force * area; traction load on a side sums to traction * length."""
    mesh = rectangle(4, 3, lx=2.0, ly=1.5, cell="quad", distort=0.2, seed=2)
    f = _core.assemble_mass_load(mesh.points, mesh.cells, "quad", np.tile([1.5, -2.0], (mesh.num_points, 1)))
    np.testing.assert_allclose(f.sum(0), [1.5 * 3.0, -2.0 * 3.0], rtol=1e-13)
    sel = mesh.facet_tags == 2  # right side, length 1.5
    t = _core.assemble_facet_load(mesh.points, mesh.facets[sel], np.tile([0.5, 0.25], (mesh.num_points, 1)))
    np.testing.assert_allclose(t.sum(0), [0.75, 0.375], rtol=1e-13)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_prolongation_reproduces_linear_functions(cell):
    h = MeshHierarchy.build(rectangle(3, 2, cell=cell, distort=0.2, seed=4), 4)
    for coarse, fine, T in zip(h.meshes[:-1], h.meshes[1:], h.transfers):
        P = T.matrix()
        for lin in (coarse.points[:, 0] * 2 - coarse.points[:, 1], np.ones(coarse.num_points)):
            fine_lin = P @ lin
            expect = fine.points[:, 0] * 2 - fine.points[:, 1] if lin[0] != 1 or np.ptp(lin) else np.ones(fine.num_points)
            np.testing.assert_allclose(fine_lin, expect, atol=1e-14)
        np.testing.assert_allclose(P.sum(axis=1).A1, 1.0, atol=1e-15)  # partition of unity


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_galerkin_product_equals_coarse_assembly(cell):
    """On a nested (straight-sided) hierarchy P^T A_fine P is the coarse-mesh stiffness; checked
    against scipy's independent product too. Distorted triangles; for quads an affine (sheared)
    grid, where 2x2 Gauss is exact on both levels (on general quads the quadratures differ)."""
    base = rectangle(3, 3, cell=cell, distort=0.2 if cell == "triangle" else 0.0, seed=5)
    if cell == "quad":
        base = Mesh(base.points @ np.array([[1.0, 0.1], [0.3, 1.0]]), base.cells, "quad", base.facets, base.facet_tags)
    h = MeshHierarchy.build(base, 3)
    for l in (0, 1):
        coarse, fine, T = h.meshes[l], h.meshes[l + 1], h.transfers[l]
        Af = _core.assemble_elasticity(fine.points, fine.cells, cell, MAT.E, MAT.nu)
        C = to_scipy(_core.testing.galerkin_product_2D(Af, T.n_coarse, T.ptr, T.parent, T.weight)).toarray()
        Ac = stiffness(coarse).toarray()
        np.testing.assert_allclose(C, Ac, atol=1e-13 * np.abs(Ac).max())
        P = sp.kron(T.matrix(), sp.eye(2))
        np.testing.assert_allclose(C, (P.T @ to_scipy(Af) @ P).toarray(), atol=1e-13 * np.abs(Ac).max())


def test_refinement_projects_boundary_nodes_onto_the_arc():
    h = MeshHierarchy.build(hertz_half_disk("triangle"), 4, projector=hertz_projector())
    fine = h.finest
    arc = fine.boundary_nodes([1])
    r = np.linalg.norm(fine.points[arc] - [0.0, 0.4], axis=1)
    top = np.isclose(fine.points[arc, 1], 0.4)
    np.testing.assert_allclose(r[~top], 0.4, atol=1e-15)
    # the node count follows the refinement rule n' = n + edges
    c = h.meshes[-2]
    edges = np.unique(np.sort(np.stack([c.cells, np.roll(c.cells, -1, 1)], -1).reshape(-1, 2), 1), axis=0)
    assert fine.num_points == c.num_points + len(edges)


def manufactured(cell, levels):
    """u = (s, s), s = sin(pi x) sin(pi y) on the unit square, clamped all round; returns h, L2 and
    energy errors per level (quadrature of the exact field against the FE solution)."""
    mat = MAT
    lam, mu = mat.lam, mat.mu
    pi = np.pi

    def u_ex(x):
        s = np.sin(pi * x[:, 0]) * np.sin(pi * x[:, 1])
        return np.c_[s, s]

    def f_ex(x):
        s = np.sin(pi * x[:, 0]) * np.sin(pi * x[:, 1])
        c = np.cos(pi * x[:, 0]) * np.cos(pi * x[:, 1])
        v = (lam + mu) * pi ** 2 * (s - c) + 2 * mu * pi ** 2 * s
        return np.c_[v, v]

    from contactmg.model.problem import Body, Dirichlet, Problem

    out = []
    base = rectangle(2, 2, cell=cell)
    hier = MeshHierarchy.build(base, levels)
    for L in range(2, levels + 1):
        sub = MeshHierarchy(hier.meshes[:L], hier.transfers[:L - 1])
        prob = Problem(Body(sub, mat, [Dirichlet([1, 2, 3, 4], (0.0, 0.0))], body_force=f_ex))
        res = prob.solve(tol=1e-13)
        m = sub.finest
        uh = res.displacement
        # L2 error by a 7-point-accurate rule: split every cell into triangles, 6-point rule (degree 4)
        tri = m.cells if cell == "triangle" else np.r_[m.cells[:, [0, 1, 2]], m.cells[:, [0, 2, 3]]]
        X = m.points[tri]
        area = 0.5 * np.abs((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1]) - (X[:, 2, 0] - X[:, 0, 0]) * (X[:, 1, 1] - X[:, 0, 1]))
        a, b = 0.445948490915965, 0.091576213509771
        wa, wb = 0.223381589678011, 0.109951743655322
        bary = np.array([[a, a, 1 - 2 * a], [a, 1 - 2 * a, a], [1 - 2 * a, a, a], [b, b, 1 - 2 * b], [b, 1 - 2 * b, b], [1 - 2 * b, b, b]])
        w = np.array([wa] * 3 + [wb] * 3)
        err2 = 0.0
        for q in range(6):
            xq = np.einsum("k,ckd->cd", bary[q], X)
            if cell == "triangle":
                uq = np.einsum("k,ckd->cd", bary[q], uh[tri])
            else:  # evaluate Q1 at xq by inverting the bilinear map per quad (Newton)
                uq = _eval_q1(m, uh, xq, np.r_[np.arange(m.num_cells), np.arange(m.num_cells)])
            err2 += np.sum(w[q] * area * np.sum((uq - u_ex(xq)) ** 2, 1))
        energy_uh = float(uh.ravel() @ prob.A.matvec(uh).ravel())
        # a(u,u) = int f.u, by the same rule on a fine triangulation of the square
        au = _integrate(lambda x: np.sum(f_ex(x) * u_ex(x), 1), 64)
        out.append((1.0 / (2 * 2 ** (L - 1)), np.sqrt(err2), np.sqrt(abs(au - energy_uh))))
    return np.array(out)


def _integrate(fun, n):
    g = (np.arange(n) + 0.5) / n
    gl, wl = np.polynomial.legendre.leggauss(4)
    x = (np.arange(n)[:, None] + (gl[None, :] + 1) / 2).ravel() / n
    w = np.tile(wl / 2, n) / n
    X, Y = np.meshgrid(x, x)
    W = np.outer(w, w)
    return float(np.sum(W * fun(np.c_[X.ravel(), Y.ravel()]).reshape(X.shape)))


def _eval_q1(m, uh, xq, cell_ids):
    X = m.points[m.cells[cell_ids]]
    U = uh[m.cells[cell_ids]]
    xi = np.full((len(xq), 2), 0.5)
    for _ in range(20):
        s, t = xi[:, 0], xi[:, 1]
        N = np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], 1)
        dNs = np.stack([-(1 - t), 1 - t, t, -t], 1)
        dNt = np.stack([-(1 - s), -s, s, 1 - s], 1)
        r = np.einsum("ck,ckd->cd", N, X) - xq
        J = np.stack([np.einsum("ck,ckd->cd", dNs, X), np.einsum("ck,ckd->cd", dNt, X)], 2)
        xi -= np.linalg.solve(J, r[..., None])[..., 0]
    s, t = xi[:, 0], xi[:, 1]
    N = np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], 1)
    return np.einsum("ck,ckd->cd", N, U)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_manufactured_solution_convergence_rates(cell):
    e = manufactured(cell, 6)
    slope_l2 = np.polyfit(np.log(e[:, 0]), np.log(e[:, 1]), 1)[0]
    slope_en = np.polyfit(np.log(e[:, 0]), np.log(e[:, 2]), 1)[0]
    assert 1.85 < slope_l2 < 2.2, e
    assert 0.9 < slope_en < 1.15, e
