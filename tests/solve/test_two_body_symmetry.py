"""Symmetry planes through the contact zone of two bodies: a half (2D) or quarter (3D) model gives the
full model's answer. The meshes are mirror-symmetric and non-matching across the interface, so the
full model's converged solution is symmetric and the cut model must reproduce it to the solver's
tolerance; nonmortar nodes on a symmetry plane (some components prescribed) keep their contact
condition, nodes held along their normal are taken out by the boundary modification of the dual
basis, and every weighted gap of a rigid translation stays zero."""
from __future__ import annotations

import numpy as np
import pytest

import contactmg as cm
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_TOP, rectangle
from contactmg.mesh.generators_3d import box
from contactmg.results.checks import contact_conditions

E_UP, E_LOW, NU = 1000.0, 300.0, 0.3
PRESS = -0.01


def _two_blocks_2d(half: bool, friction, levels=3):
    x0u, x0l = (0.0, 0.0) if half else (-1.0, -1.5)
    upper = rectangle(4 if half else 8, 4, 1.0 if half else 2.0, 1.0, cell="quad", origin=(x0u, 0.0))
    lower = rectangle(5 if half else 10, 3, 1.5 if half else 3.0, 1.0, cell="quad", origin=(x0l, -1.0))
    sym = [cm.Dirichlet([RECT_LEFT], (0.0, None))] if half else []
    bodies = [cm.Body(cm.MeshHierarchy.build(upper, levels), cm.Material(E_UP, NU),
                      [cm.Dirichlet([RECT_TOP], (0.0, PRESS))] + sym),
              cm.Body(cm.MeshHierarchy.build(lower, levels), cm.Material(E_LOW, NU),
                      [cm.Dirichlet([RECT_BOTTOM], (0.0, 0.0))] + sym)]
    pair = cm.ContactPair(0, 1, [RECT_BOTTOM], [RECT_TOP], search=0.1)
    return cm.Problem(bodies, pairs=[pair], friction=friction)


def _two_blocks_3d(quarter: bool, friction, levels=2):
    if quarter:
        upper = box(2, 2, 2, 1.0, 1.0, 0.5, origin=(0.0, 0.0, 0.0))
        lower = box(5, 5, 2, 1.5, 1.5, 0.5, origin=(0.0, 0.0, -0.5))
        sym = [cm.Dirichlet([1], (0.0, None, None)), cm.Dirichlet([3], (None, 0.0, None))]
    else:
        upper = box(4, 4, 2, 2.0, 2.0, 0.5, origin=(-1.0, -1.0, 0.0))
        lower = box(10, 10, 2, 3.0, 3.0, 0.5, origin=(-1.5, -1.5, -0.5))
        sym = []
    bodies = [cm.Body(cm.MeshHierarchy.build(upper, levels), cm.Material(E_UP, NU),
                      [cm.Dirichlet([6], (0.0, 0.0, PRESS))] + sym),
              cm.Body(cm.MeshHierarchy.build(lower, levels), cm.Material(E_LOW, NU),
                      [cm.Dirichlet([5], (0.0, 0.0, 0.0))] + sym)]
    pair = cm.ContactPair(0, 1, [5], [6], search=0.1)
    return cm.Problem(bodies, pairs=[pair], friction=friction)


def _match(cut, full):
    """Index into the full model's nodes of every node of the cut model (same body, same point)."""
    from scipy.spatial import cKDTree
    idx = np.zeros(cut.mesh.num_points, np.int64)
    for b in np.unique(cut.body_id):
        mine, theirs = np.flatnonzero(cut.body_id == b), np.flatnonzero(full.body_id == b)
        dist, k = cKDTree(full.mesh.points[theirs]).query(cut.mesh.points[mine])
        assert dist.max() < 1e-10
        idx[mine] = theirs[k]
    return idx


def _compare(cut, full):
    rc, rf = cut.solve(), full.solve()
    assert rc.converged and rf.converged
    # the cut model's nonmortar nodes: every node of the contact facets, the symmetry ones included
    facet_nodes = np.unique(cut.contact.facets)
    assert np.array_equal(np.sort(cut.contact.nodes), facet_nodes)
    idx = _match(cut, full)
    scale = np.abs(rf.displacement).max()
    assert np.abs(rc.displacement - rf.displacement[idx]).max() < 1e-6 * scale
    # the contact pressure per contact node of each model, the cut one's at the same places
    at = np.searchsorted(full.contact.nodes, idx[cut.contact.nodes])
    assert np.array_equal(full.contact.nodes[at], idx[cut.contact.nodes])
    pf = rf.normal_stress
    assert np.abs(rc.normal_stress - pf[at]).max() < 1e-6 * np.abs(pf).max()
    assert contact_conditions(cut, rc)["max"] < 1e-8
    return rc, rf


@pytest.mark.parametrize("friction", [cm.Frictionless(), cm.Coulomb(0.3)])
def test_half_model_of_two_blocks_is_the_full_model(friction):
    _compare(_two_blocks_2d(True, friction), _two_blocks_2d(False, friction))


@pytest.mark.parametrize("friction", [cm.Frictionless(), cm.Coulomb(0.3)])
def test_quarter_model_of_two_boxes_is_the_full_model(friction):
    _compare(_two_blocks_3d(True, friction), _two_blocks_3d(False, friction))


def test_symmetry_plane_nodes_keep_their_condition_with_the_mirror_normal():
    """A nonmortar node on a symmetry plane takes the normal the mirrored model gives it (in the
    plane), even where its one facet is tilted; the transformation leaves its prescribed axis alone,
    so u_x = 0 holds for u = T w as given."""
    p = _two_blocks_2d(True, cm.Frictionless(), levels=2)
    c = p.coupling
    x = p.parts[0].mesh.points[c.nonmortar_nodes]
    on = np.abs(x[:, 0]) < 1e-12
    assert on.sum() == 1 and np.allclose(c.normals[on], [0.0, -1.0])
    assert np.array_equal(c.free[on], [[False, True]])
    r = p.solve()
    assert np.abs(r.displacement[p.contact.nodes][on, 0]).max() == 0.0


def test_a_node_held_along_its_normal_is_taken_out_with_the_modified_basis():
    """The nonmortar edge node held in both axes (the upper block clamped on its side down to the
    contact face) carries no condition; its neighbour's modified dual basis keeps D diagonal, the
    rows of [M, -S] consistent (a rigid translation of both bodies moves no weighted gap) and the
    linear fields reproduced; the problem says so in its notes."""
    upper = rectangle(4, 2, 1.0, 0.5, cell="quad")
    lower = rectangle(5, 2, 1.4, 0.5, cell="quad", origin=(-0.2, -0.5))
    bodies = [cm.Body(cm.MeshHierarchy.build(upper, 2), cm.Material(E_UP, NU),
                      [cm.Dirichlet([RECT_LEFT], (0.0, 0.0)), cm.Dirichlet([RECT_TOP], (0.0, PRESS))]),
              cm.Body(cm.MeshHierarchy.build(lower, 2), cm.Material(E_LOW, NU), [cm.Dirichlet([RECT_BOTTOM], (0.0, 0.0))])]
    p = cm.Problem(bodies, pairs=[cm.ContactPair(0, 1, [RECT_BOTTOM], [RECT_TOP], search=0.1)],
                   friction=cm.Frictionless())
    c = p.coupling
    xs, xm = p.parts[0].mesh.points, p.parts[1].mesh.points
    assert len(c.excluded) == 1 and np.allclose(xs[c.excluded[0]], [0.0, 0.0])
    assert c.S.nnz == 1
    rows = np.asarray(c.M.sum(axis=1)).ravel() - np.asarray(c.S.sum(axis=1)).ravel()
    assert np.allclose(rows, c.D, rtol=1e-12)
    L = np.array([[0.3, -1.2], [0.7, 0.4]])
    field = lambda y: y @ L + [0.2, -0.1]  # noqa: E731
    # sum_q Mhat_pq f(x_q) - sum_a Shat_pa f(x_a) = f(x_p): linear fields pass through the coupling
    assert np.allclose(c.Mhat @ field(xm) - c.Shat @ field(xs), field(xs[c.nonmortar_nodes]), atol=1e-12)
    assert any("Dirichlet" in note for note in p.notes)
    r = p.solve()
    assert r.converged and contact_conditions(p, r)["max"] < 1e-8
