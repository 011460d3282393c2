"""Coarse spaces from one fine mesh: geometric coarsening (nested node sets, nonnegative barycentric
interpolation between non-nested levels) and nonnegative smoothed aggregation. The monotone
multigrid's requirements hold on both, and the solver on them finds the geometric hierarchy's answer."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz, sphere
from contactmg.mesh.aggregation import aggregation_prolongations, node_graph, pairwise_matching
from contactmg.mesh.coarsening import (barycentric_prolongation, coarsening_prolongations, independent_set,
                                       node_classes)
from contactmg.results.checks import contact_conditions


@pytest.fixture(scope="module")
def hertz6():
    return hertz.hertz_problem("triangle", 6, 0.4)


SPACES = {"coarsening": cm.MeshHierarchy.coarsened, "aggregation": cm.MeshHierarchy.aggregated}


def _on(problem, space, friction=None):
    """`problem` on the coarse space `space` made from its fine mesh alone."""
    b = problem.bodies[0]
    return cm.Problem(cm.Body(SPACES[space](problem.mesh), b.material, b.dirichlet, contact_tags=b.contact_tags),
                      obstacle=problem.obstacle, friction=friction or problem.friction)


@pytest.mark.parametrize("mesh", [hertz.hertz_problem("triangle", 5, 0.4).mesh, hertz.hertz_problem("quad", 5, 0.4).mesh,
                                  cm.box(6, 5, 4, cell="tetra"), cm.box(6, 5, 4, cell="hexahedron")],
                         ids=["triangle", "quad", "tetra", "hexahedron"])
@pytest.mark.parametrize("space", ["coarsening", "aggregation"])
def test_prolongations_are_nonnegative_partitions_of_unity(mesh, space):
    Ps = (coarsening_prolongations if space == "coarsening" else aggregation_prolongations)(mesh, coarsest=40)
    assert Ps and Ps[-1].shape[0] == mesh.num_points and Ps[0].shape[1] <= 40
    for coarse, fine in zip(Ps[:-1], Ps[1:]):
        assert fine.shape[1] == coarse.shape[0]            # consecutive levels chain up
    for P in Ps:
        assert P.data.min() >= 0.0
        assert np.allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0, rtol=0, atol=1e-13)
        if space == "coarsening":
            assert np.diff(P.indptr).max() <= mesh.dim + 1  # a simplex's corners at most
        assert P.shape[1] <= 0.6 * P.shape[0]               # every level coarsens
        assert np.all(np.asarray(P.sum(axis=0)).ravel() > 0)  # every coarse function is used


def test_interpolation_is_exact_for_linear_functions_inside_the_coarse_simplices():
    rng = np.random.default_rng(0)
    coarse = rng.random((60, 3))
    fine = rng.random((500, 3)) * 0.6 + 0.2               # mostly inside the coarse hull
    P, simplices = barycentric_prolongation(fine, coarse)
    from scipy.spatial import Delaunay

    inside = Delaunay(coarse).find_simplex(fine) >= 0
    assert inside.sum() > 400
    f = lambda x: 2.0 * x[:, 0] - 3.0 * x[:, 1] + 0.5 * x[:, 2] + 1.0  # noqa: E731
    assert np.abs(P[inside] @ f(coarse) - f(fine[inside])).max() < 1e-12
    # a point outside every simplex is interpolated from the nearest one's corners, clipped
    assert P.data.min() >= 0 and np.allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0)


def test_the_coarse_nodes_are_an_independent_set_that_leaves_no_node_alone():
    mesh = cm.box(5, 5, 5, cell="tetra")
    G = node_graph(mesh.cells, mesh.num_points)
    rng = np.random.default_rng(1)
    keep = independent_set(G, rng.permutation(mesh.num_points).astype(float))
    rows = np.repeat(np.arange(mesh.num_points), np.diff(G.indptr))
    assert not np.any(keep[rows] & keep[G.indices])       # no two chosen nodes are neighbours
    touched = np.zeros(mesh.num_points, bool)
    touched[rows[keep[G.indices]]] = True
    assert np.all(keep | touched)                          # every other node is next to a chosen one


def test_the_outline_is_kept_first():
    mesh = cm.box(4, 4, 4, cell="hexahedron")
    cls = node_classes(mesh)
    x = mesh.points
    corner = np.all((np.abs(x - x.min(axis=0)) < 1e-12) | (np.abs(x - x.max(axis=0)) < 1e-12), axis=1)
    assert np.all(cls[corner] == 3)                        # the box's corners
    on_faces = (np.abs(x - x.min(axis=0)) < 1e-12) | (np.abs(x - x.max(axis=0)) < 1e-12)
    assert np.all(cls[on_faces.sum(axis=1) == 2] == 2)     # its edges
    assert np.all(cls[on_faces.sum(axis=1) == 1] == 1)     # its faces
    interior = np.all((x > x.min(axis=0) + 1e-12) & (x < x.max(axis=0) - 1e-12), axis=1)
    assert np.all(cls[interior] == 0)
    P = coarsening_prolongations(mesh, coarsest=20)[-1]
    kept = np.flatnonzero(np.isclose(P.max(axis=1).toarray().ravel(), 1.0) & (np.diff(P.indptr) == 1))
    assert set(np.flatnonzero(corner)) <= set(kept)        # corners stay coarse nodes


@pytest.mark.parametrize("space", ["coarsening", "aggregation"])
def test_the_answer_of_the_geometric_hierarchy_from_the_fine_mesh_alone(hertz6, space):
    p = _on(hertz6, space)
    h = p.hierarchy
    assert h.kind == space and h.from_fine_mesh and h.levels >= 3 and h.finest is hertz6.mesh
    res = p.solve(tol=1e-11)
    ref = hertz6.solve()
    assert res.converged and res.cycles <= (ref.cycles + 3 if space == "coarsening" else 30)
    assert np.abs(res.displacement - ref.displacement).max() <= 1e-9 * np.abs(ref.displacement).max()
    assert contact_conditions(p, res)["max"] < 1e-8


@pytest.mark.parametrize("space", ["coarsening", "aggregation"])
def test_every_cycle_lowers_the_energy_with_the_new_coarse_spaces(hertz6, space):
    """Tresca friction: a convex energy that the monotone multigrid minimizes; it must not rise in
    any cycle on these coarse spaces either (nonnegative weights keep the coarse obstacles below the
    fine ones)."""
    res = _on(hertz6, space, cm.Tresca(0.05)).solve(tol=0.0, rtol=1e-12, method="nmg")
    assert res.converged
    e = np.asarray(res.history["energy"])
    # once converged the energy changes by its own evaluation's round-off (a sum over all dofs)
    assert np.all(np.diff(e) <= 1e-11 * np.abs(e).max())
    assert e[-1] < e[0]


@pytest.mark.parametrize("space", ["coarsening", "aggregation"])
def test_a_3d_mesh_alone(space):
    geo = sphere.sphere_problem("tetra", 2, 0.4)
    res = _on(geo, space).solve(tol=1e-11)
    ref = geo.solve()
    assert res.converged and res.cycles <= (ref.cycles + 3 if space == "coarsening" else 30)
    assert np.abs(res.displacement - ref.displacement).max() <= 1e-8 * np.abs(ref.displacement).max()


def test_matching_pairs_neighbours_only():
    mesh = cm.rectangle(5, 4, cell="quad")
    G = node_graph(mesh.cells, mesh.num_points)
    agg, m = pairwise_matching(G)
    for a in range(m):
        members = np.flatnonzero(agg == a)
        assert 1 <= len(members) <= 2
        if len(members) == 2:
            assert G[members[0], members[1]] == 1


def test_no_coarse_meshes_to_ask_for_and_bad_sizes(hertz6):
    h = cm.MeshHierarchy.coarsened(hertz6.mesh)
    with pytest.raises(ValueError, match=r"made from the fine mesh alone \(coarsening\) has none"):
        h.truncated(2)
    with pytest.raises(ValueError, match="coarsest must be a number of nodes of at least 4"):
        coarsening_prolongations(hertz6.mesh, coarsest=2)
    with pytest.raises(TypeError, match="mesh must be a Mesh"):
        cm.MeshHierarchy.coarsened(hertz6.mesh.points)
    with pytest.raises(ValueError, match=r"made from the fine mesh alone \(aggregation\) has none"):
        cm.MeshHierarchy.aggregated(hertz6.mesh).truncated(2)
    with pytest.raises(ValueError, match=r"omega must lie in \[0, 1\]"):
        aggregation_prolongations(hertz6.mesh, omega=1.5)


@pytest.mark.parametrize("space", ["coarsening", "aggregation"])
def test_monotone_restriction_stays_a_bound(space):
    """Any coarse correction within the restricted bounds keeps every fine dof within its own: checked
    at the corners of the coarse box (the extreme corrections) through each level's prolongation."""
    from contactmg import _core

    mesh = hertz.hertz_problem("triangle", 4, 0.4).mesh
    Ps = (coarsening_prolongations if space == "coarsening" else aggregation_prolongations)(mesh, 30)
    rng = np.random.default_rng(2)
    for P in Ps:
        nf, nc = P.shape
        lo = -rng.random((nf, 2)) * (rng.random((nf, 2)) < 0.5)
        hi = rng.random((nf, 2))
        lo[rng.random((nf, 2)) < 0.3] = -np.inf
        hi[rng.random((nf, 2)) < 0.3] = np.inf
        lc, hc = _core.testing.restrict_bounds_2D(nf, nc, P.indptr.astype(np.int64), P.indices.astype(np.int64),
                                                  P.data, None, lo, hi)
        assert np.all(lc <= 0) and np.all(hc >= 0)
        for _ in range(20):  # random corners of the coarse box (a finite side where there is one)
            pick = rng.random((nc, 2)) < 0.5
            c = np.where(pick, np.where(np.isfinite(hc), hc, 0.0), np.where(np.isfinite(lc), lc, 0.0))
            v = P @ c
            assert np.all(v <= hi + 1e-14) and np.all(v >= lo - 1e-14)


@pytest.mark.parametrize("make", [cm.MeshHierarchy.coarsened, cm.MeshHierarchy.aggregated])
def test_a_small_mesh_coarsened_from_itself_gets_coarse_levels(make):
    """A mesh of at most 200 nodes (the default coarsest size) still gets coarse levels, down to an
    eighth of its nodes, as a lone mesh given to a Problem does: a block of 153 nodes that falls onto
    its floor, held by nothing else, converges in a multigrid's cycles."""
    mesh = cm.rectangle(16, 8, 2.0, 1.0, origin=(0.0, 0.5))
    assert mesh.num_points <= 200
    h = make(mesh)
    assert h.levels >= 2 and len(h.transfers) == h.levels - 1
    assert h.transfers[0].matrix().shape[1] <= mesh.num_points // 8
    body = cm.Body(h, cm.Material(1000.0, 0.3), [], contact_tags=[cm.RECT_BOTTOM], pressure={cm.RECT_TOP: 1.0})
    p = cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.converged and res.cycles <= 30, (res.cycles, res.status)
    assert res.contact_forces()["obstacle"][1] == pytest.approx(2.0, rel=1e-8)
