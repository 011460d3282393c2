"""A contact node with some Dirichlet components keeps its contact condition in the free
directions: symmetry half models, rollers, and the errors for prescriptions
that penetrate or that are not aligned with the contact frame."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.model.friction import Coulomb, Frictionless
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_TOP, rectangle
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.model.problem import Body, Dirichlet, Problem

MAT = Material(1000.0, 0.3)
PLANE = PlaneObstacle((0.0, 0.0), (0.0, -1.0))
PUSH = (0.0, -0.01)


def corner(mesh, x=0.0, y=0.0):
    return int(np.argmin(np.linalg.norm(mesh.points - np.array([x, y]), axis=1)))


def test_issue_reproduction_corner_does_not_penetrate():
    """rectangle(4, 4, 1, 1), 5 levels, top pushed down, left a roller u_x = 0, contact below on
    y = 0: the corner (0, 0) used to end at u_y = -2.3e-4 (gap 0) because it was dropped from the
    contact set; it is a contact node now and stays on the obstacle."""
    h = MeshHierarchy.build(rectangle(4, 4, 1, 1), 5)
    p = Problem(Body(h, MAT, [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (0.0, None))],
                     contact_tags=[RECT_BOTTOM]), obstacle=PLANE)
    r = p.solve()
    assert r.converged, r.status
    k = corner(p.mesh)
    assert k in set(p.contact.nodes.tolist())
    assert r.displacement[k, 0] == 0.0  # the roller holds exactly
    assert r.displacement[k, 1] >= -1e-15  # u_n = -u_y <= g = 0
    assert np.all(r.displacement[p.contact.nodes, 1] >= -1e-15)
    c = contact_conditions(p, r)
    assert c["max"] <= VIOLATION_TOL, c
    assert r.node_state[k] > 0  # pressed onto the obstacle: in contact (2D roller: counts as sticking)


def _mirror_full(cell, n):
    """The full symmetric body [-1, 1] x [0, 1] (its right half is rectangle(n, n, 1, 1))."""
    return rectangle(2 * n, n, 2.0, 1.0, cell, origin=(-1.0, 0.0))


@pytest.mark.parametrize("cell", ["triangle", "quad"])
@pytest.mark.parametrize("friction", [Frictionless(), Coulomb(0.3)], ids=["frictionless", "coulomb"])
def test_half_model_equals_full_model(cell, friction):
    levels = 4
    full_mesh, half_mesh = _mirror_full(cell, 4), rectangle(4, 4, 1.0, 1.0, cell)
    full = Problem(Body(MeshHierarchy.build(full_mesh, levels), MAT, [Dirichlet([RECT_TOP], PUSH)],
                        contact_tags=[RECT_BOTTOM]), obstacle=PLANE, friction=friction)
    half = Problem(Body(MeshHierarchy.build(half_mesh, levels), MAT,
                        [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (0.0, None))],
                        contact_tags=[RECT_BOTTOM]), obstacle=PLANE, friction=friction)
    rf, rh = full.solve(tol=1e-12), half.solve(tol=1e-12)
    assert rf.converged and rh.converged, (rf.status, rh.status)
    for p, r in ((full, rf), (half, rh)):
        c = contact_conditions(p, r)
        assert c["max"] <= VIOLATION_TOL, c
    # match the half's nodes with the full model's by coordinates
    xf, xh = full.mesh.points, half.mesh.points
    order = np.lexsort((xf[:, 1], xf[:, 0]))
    keyf = {tuple(np.round(xf[i], 12)): i for i in order}
    idx = np.array([keyf[tuple(np.round(x, 12))] for x in xh])
    uf, uh = rf.displacement[idx], rh.displacement
    scale = np.abs(uf).max()
    assert np.abs(uf - uh).max() <= 1e-8 * scale, np.abs(uf - uh).max() / scale
    # the full model's symmetry-line node is in contact, as the half's corner is (whose tangential
    # component is prescribed: it counts as sticking; the full model's has u_x = 0 up to round-off)
    k = corner(half.mesh)
    assert rh.node_state[k] == 1 and rf.node_state[idx[k]] > 0
    # and the contact zones agree node by node
    sh = rh.node_state[half.contact.nodes]
    assert np.array_equal(sh > 0, rf.node_state[idx[half.contact.nodes]] > 0)


def test_prescribed_tangential_value_stays_exact_under_coulomb_friction():
    """A roller with a nonzero value u_x = 0.002 at a contact node in contact with friction: the
    value holds exactly (friction acts on the free tangential components only, none here), the node
    does not penetrate, and the independent check passes."""
    h = MeshHierarchy.build(rectangle(4, 4, 1, 1), 4)
    p = Problem(Body(h, MAT, [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (0.002, None))],
                     contact_tags=[RECT_BOTTOM]), obstacle=PLANE, friction=Coulomb(0.5))
    r = p.solve()
    assert r.converged, r.status
    k = corner(p.mesh)
    assert abs(r.displacement[k, 0] - 0.002) <= 1e-15
    assert r.displacement[k, 1] >= -1e-15
    assert contact_conditions(p, r)["max"] <= VIOLATION_TOL


def test_prescribed_normal_lift_is_not_a_contact_node():
    """The normal component prescribed (u_y = +0.001 on the left edge: the corner lifts off): the
    node is no contact node and takes its value; the rest of the bottom is in contact."""
    h = MeshHierarchy.build(rectangle(4, 4, 1, 1), 3)
    p = Problem(Body(h, MAT, [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (None, 0.001))],
                     contact_tags=[RECT_BOTTOM]), obstacle=PLANE)
    k = corner(p.mesh)
    assert k not in set(p.contact.nodes.tolist())
    r = p.solve()
    assert r.converged
    assert r.displacement[k, 1] == 0.001
    assert contact_conditions(p, r)["max"] <= VIOLATION_TOL


def test_prescribed_penetration_is_an_error():
    h = MeshHierarchy.build(rectangle(4, 4, 1, 1), 2)
    with pytest.raises(ValueError, match="prescribes penetration"):
        Problem(Body(h, MAT, [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (None, -0.001))],
                     contact_tags=[RECT_BOTTOM]), obstacle=PLANE)


def test_misaligned_roller_is_refused_naming_the_node():
    h = MeshHierarchy.build(rectangle(4, 4, 1, 1), 2)
    tilted = PlaneObstacle((0.0, 0.0), (0.3, -1.0))
    with pytest.raises(ValueError, match=r"contact node 0 .*neither normal nor tangential"):
        Problem(Body(h, MAT, [Dirichlet([RECT_TOP], PUSH), Dirichlet([RECT_LEFT], (0.0, None))],
                     contact_tags=[RECT_BOTTOM]), obstacle=tilted)


def test_core_classification():
    n = np.array([[0.0, -1.0]] * 4)
    fixed = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], np.uint8)
    vals = np.array([[0, 0], [0.1, 0], [0, 0.5], [0, 0]], float)
    kind = _core.classify_contact_dirichlet_2D(np.arange(4), fixed, vals, n, np.ones(4))
    assert kind.tolist() == [0, 1, 2, 3]
    with pytest.raises(ValueError, match="contact node 7 .*prescribes penetration"):
        _core.classify_contact_dirichlet_2D(np.array([7]), np.array([[0, 1]], np.uint8), np.array([[0, -2.0]]),
                                            n[:1], np.ones(1))


def _brute_force_3d(B, b, fixed_axis, value, s):
    """min 1/2 x^T B x - b^T x + s |x_free_tangential| over x with x[fixed_axis] = value and the
    normal free (gap far away), by a fine grid search refined twice around the best point."""
    from scipy.optimize import minimize
    free = [a for a in range(3) if a != fixed_axis]
    tang = [a for a in (1, 2) if a != fixed_axis]

    def J(z):
        x = np.zeros(3)
        x[fixed_axis] = value
        x[free] = z
        return 0.5 * x @ B @ x - b @ x + s * np.linalg.norm(x[tang])

    best = None
    for z0 in ([0, 0], [1, 1], [-1, 1], [1, -1]):
        res = minimize(J, np.array(z0, float), method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-15, "maxiter": 20000})
        if best is None or res.fun < best.fun:
            best = res
    x = np.zeros(3)
    x[fixed_axis] = value
    x[free] = best.x
    return x, J(best.x)


@pytest.mark.parametrize("fixed_axis", [1, 2])
def test_nodal_solver_with_a_fixed_tangential_component_3d(fixed_axis):
    """After elimination the fixed tangential component is decoupled (identity row and column, its
    value on the right); friction acts on the other tangential component only, and the value stays exact."""
    rng = np.random.default_rng(fixed_axis)
    for _ in range(5):
        M = rng.normal(size=(3, 3))
        B = M @ M.T + 3 * np.eye(3)
        B[fixed_axis, :] = B[:, fixed_axis] = 0.0
        B[fixed_axis, fixed_axis] = 1.0
        b = rng.normal(size=3)
        value = rng.normal()
        b[fixed_axis] = value
        s = abs(rng.normal())
        free = 0b11 & ~(1 << (fixed_axis - 1))
        x = _core.solve_node_tresca_3D(B, b, 1e3, s, free)
        assert x[fixed_axis] == value
        xb, Jb = _brute_force_3d(B, b, fixed_axis, value, s)
        tang = [a for a in (1, 2) if a != fixed_axis]
        Jx = 0.5 * x @ B @ x - b @ x + s * np.linalg.norm(x[tang])
        assert Jx <= Jb + 1e-9 * max(1.0, abs(Jb))
        np.testing.assert_allclose(x, xb, atol=1e-5)
