"""Coarse spaces from one fine mesh by nonnegative smoothed aggregation: the prolongations keep the
monotone multigrid's requirements, and the solver on them finds the geometric hierarchy's answer."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz
from contactmg.mesh.aggregation import aggregation_prolongations, pairwise_matching, node_graph
from contactmg.results.checks import contact_conditions


@pytest.fixture(scope="module")
def hertz6():
    return hertz.hertz_problem("triangle", 6, 0.4)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_prolongations_are_nonnegative_partitions_of_unity(cell):
    mesh = hertz.hertz_problem(cell, 5, 0.4).mesh
    Ps = aggregation_prolongations(mesh, coarsest=50)
    assert Ps and Ps[-1].shape[0] == mesh.num_points and Ps[0].shape[1] <= 50
    for coarse, fine in zip(Ps[:-1], Ps[1:]):
        assert fine.shape[1] == coarse.shape[0]            # consecutive levels chain up
    for P in Ps:
        assert P.data.min() >= 0.0
        assert np.allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-14)
        assert P.shape[1] <= P.shape[0] / 2                # every level coarsens
        # every coarse function is used
        assert np.all(np.asarray(P.sum(axis=0)).ravel() > 0)


def test_matching_pairs_neighbours_only():
    mesh = cm.rectangle(5, 4, cell="quad")
    G = node_graph(mesh.cells, mesh.num_points)
    agg, m = pairwise_matching(G)
    for a in range(m):
        members = np.flatnonzero(agg == a)
        assert 1 <= len(members) <= 2
        if len(members) == 2:
            assert G[members[0], members[1]] == 1


def test_the_answer_of_the_geometric_hierarchy_from_the_fine_mesh_alone(hertz6):
    b = hertz6.bodies[0]
    h = cm.MeshHierarchy.aggregated(hertz6.mesh)
    assert h.kind == "aggregation" and h.levels >= 3 and h.finest is hertz6.mesh
    p = cm.Problem(cm.Body(h, b.material, b.dirichlet, contact_tags=b.contact_tags), obstacle=hertz6.obstacle,
                   friction=hertz6.friction)
    res = p.solve(tol=1e-11)
    ref = hertz6.solve()
    assert res.converged and res.cycles <= 30
    assert np.abs(res.displacement - ref.displacement).max() <= 1e-9 * np.abs(ref.displacement).max()
    assert contact_conditions(p, res)["max"] < 1e-8


def test_every_cycle_lowers_the_energy_with_the_new_coarse_spaces(hertz6):
    """Tresca friction: a convex energy that the monotone multigrid minimizes; it must not rise in
    any cycle on the aggregated coarse spaces either."""
    b = hertz6.bodies[0]
    h = cm.MeshHierarchy.aggregated(hertz6.mesh)
    p = cm.Problem(cm.Body(h, b.material, b.dirichlet, contact_tags=b.contact_tags), obstacle=hertz6.obstacle,
                   friction=cm.Tresca(0.05))
    res = p.solve(tol=0.0, rtol=1e-12)
    assert res.converged
    e = np.asarray(res.history["energy"])
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())


def test_a_3d_mesh_alone():
    from contactmg.examples import sphere

    geo = sphere.sphere_problem("tetra", 2, 0.4)
    b = geo.bodies[0]
    h = cm.MeshHierarchy.aggregated(geo.mesh)
    p = cm.Problem(cm.Body(h, b.material, b.dirichlet, contact_tags=b.contact_tags), obstacle=geo.obstacle,
                   friction=geo.friction)
    res = p.solve(tol=1e-11)
    ref = geo.solve()
    assert res.converged and res.cycles <= 30
    assert np.abs(res.displacement - ref.displacement).max() <= 1e-8 * np.abs(ref.displacement).max()


def test_no_coarse_meshes_to_ask_for(hertz6):
    h = cm.MeshHierarchy.aggregated(hertz6.mesh)
    with pytest.raises(ValueError, match=r"made from the fine mesh alone \(aggregation\) has none"):
        h.truncated(2)
    with pytest.raises(ValueError, match=r"omega must lie in \[0, 1\]"):
        aggregation_prolongations(hertz6.mesh, omega=1.5)
