"""A coarse mesh too large for the coarsest level's direct solve, or a mesh that is the only level,
gets coarser levels made from it below it, and says so; the answer is the same."""
import warnings

import numpy as np
import pytest

import contactmg as cm
from contactmg.model.problem import MAX_COARSEST_DOFS


def _box_on_floor(n, levels):
    h = cm.MeshHierarchy.build(cm.box(n, n, n, cell="hexahedron"), levels)
    body = cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet(6, (0.0, 0.0, -0.01))], contact_tags=5)
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)), friction=cm.Coulomb(0.3))


def test_a_large_coarse_mesh_is_coarsened_below_and_says_so():
    assert 3 * 12 ** 3 > MAX_COARSEST_DOFS
    with pytest.warns(UserWarning, match=r"the coarse mesh has 6,591 dofs.*coarser levels were made from it by geometric coarsening"):
        p = _box_on_floor(12, 2)
    assert len(p.transfers) > 1 and p.notes and not p.coarse_levels_match_meshes()
    res = p.solve(tol=0.0, rtol=1e-12)
    assert res.converged and res.cycles <= 30
    # the same problem on its own two levels (the coarse mesh solved directly)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        q = _box_on_floor(12, 2)
    q.transfers = q.transfers[-1:]
    direct = q.solve(tol=0.0, rtol=1e-12)
    assert np.abs(res.displacement - direct.displacement).max() <= 1e-8 * np.abs(direct.displacement).max()


def test_a_small_coarse_mesh_is_left_alone():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = _box_on_floor(4, 2)
    assert len(p.transfers) == 1 and p.notes == () and p.coarse_levels_match_meshes()


def test_a_mesh_alone_gets_coarse_levels():
    """A hierarchy of one level (a user's mesh as it comes) is not left to the sweeps alone: coarser
    levels are made from it, the problem notes it, and the answer is the mesh's own."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: nothing the user gave was changed
        p = _box_on_floor(8, 1)
    assert len(p.transfers) >= 1 and "only level" in p.notes[0]
    res = p.solve(tol=0.0, rtol=1e-12)
    assert res.converged and res.cycles <= 30
    # the same mesh as the fine level of two: the geometric coarse correction gives the same answer
    q = _box_on_floor(4, 2)
    order_p, order_q = np.lexsort(p.mesh.points.T), np.lexsort(q.mesh.points.T)  # the same nodes, numbered otherwise
    assert np.allclose(q.mesh.points[order_q], p.mesh.points[order_p], rtol=0, atol=1e-14)
    ref = q.solve(tol=0.0, rtol=1e-12)
    diff = np.abs(res.displacement[order_p] - ref.displacement[order_q]).max()
    assert diff <= 1e-8 * np.abs(ref.displacement).max()
