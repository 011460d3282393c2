"""A coarse mesh too large for the coarsest level's direct solve gets levels of aggregates below it,
and says so; the answer is the same."""
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
    with pytest.warns(UserWarning, match=r"the coarse mesh has 6,591 dofs.*levels of aggregates were added below it"):
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
