"""Adaptive hierarchies: newest-vertex bisection, the hierarchical estimator, bulk
marking, MeshHierarchy.adaptive and the adaptive Hertz hierarchy."""
import numpy as np
import pytest

import contactmg as cm
from contactmg import _core
from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.solve.adaptivity import adaptive_hierarchy, doerfler_mark, estimate
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_RIGHT, RECT_TOP
from contactmg.examples.hertz import (PAPER_ADAPTIVE_DOFS, halfwidth, hertz_adaptive_hierarchy, hertz_problem, peak_pressure,
                             hertz_problem_on)
from contactmg.mesh.hierarchy import MeshHierarchy, _refined, longest_edge_first
from contactmg.mesh.mesh import Mesh


def bisect(mesh, marked, projector=None):
    r = _core.bisect(mesh.points, mesh.cells, mesh.facets, mesh.facet_tags, np.asarray(marked, dtype=np.int64))
    return _refined(mesh, r, projector)


def edge_counts(cells):
    e = np.sort(np.stack([cells, np.roll(cells, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    return np.unique(e, axis=0, return_counts=True)


def assert_conforming(mesh):
    """Every edge belongs to one or two cells, and the edges of one cell are exactly the boundary
    facets (a hanging node would leave an interior edge with one cell)."""
    edges, count = edge_counts(mesh.cells)
    assert count.max() <= 2
    single = {tuple(e) for e in edges[count == 1]}
    facets = {tuple(sorted(f)) for f in mesh.facets}
    assert single == facets
    assert np.all(mesh.cell_measures() > 0)


def angles(mesh):
    X = mesh.points[mesh.cells]
    out = []
    for a in range(3):
        u, v = X[:, (a + 1) % 3] - X[:, a], X[:, (a + 2) % 3] - X[:, a]
        out.append(np.arccos(np.clip(np.einsum("ij,ij->i", u, v) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1), -1, 1)))
    return np.sort(np.stack(out, 1), axis=1)


def refine_towards(mesh, point, rounds, projector=None):
    """Repeatedly mark the cells whose centroid is nearest to `point` (a strongly graded mesh)."""
    meshes, transfers = [mesh], []
    for _ in range(rounds):
        m = meshes[-1]
        dist = np.linalg.norm(m.points[m.cells].mean(1) - point, axis=1)
        fine, t = bisect(m, np.flatnonzero(dist <= np.sort(dist)[min(2, len(dist) - 1)]), projector)
        meshes.append(fine)
        transfers.append(t)
    return meshes, transfers


def scalene():
    pts = np.array([[0.0, 0.0], [1.0, 0.1], [0.3, 0.8], [1.2, 0.9]])
    cells = np.array([[0, 1, 2], [1, 3, 2]])
    m = Mesh.from_cells(pts, cells, "triangle", lambda mid: np.arange(len(mid)))
    return Mesh(m.points, longest_edge_first(m.points, m.cells), "triangle", m.facets, m.facet_tags)


# -- newest-vertex bisection ------------------------------------------------------------------------
def test_bisection_is_conforming_nested_and_keeps_area_under_random_marking():
    rng = np.random.default_rng(7)
    m = cm.rectangle(4, 3, lx=2.0, ly=1.0, distort=0.2, seed=2)
    m = Mesh(m.points, longest_edge_first(m.points, m.cells), "triangle", m.facets, m.facet_tags)
    G = np.array([[0.3, -1.1], [0.7, 0.4]])
    for _ in range(8):
        marked = np.flatnonzero(rng.random(m.num_cells) < 0.2)
        fine, t = bisect(m, marked)
        assert_conforming(fine)
        # nested: the coarse nodes keep their numbers and places; a linear field is interpolated exactly
        assert np.array_equal(fine.points[:m.num_points], m.points)
        f = m.points @ G.T + [0.5, -2.0]
        assert np.allclose(t.matrix() @ f, fine.points @ G.T + [0.5, -2.0], atol=1e-14)
        assert np.isclose(fine.cell_measures().sum(), m.cell_measures().sum(), rtol=1e-13)
        # every edge of a marked cell was bisected: its midpoint is a new node
        pairs = {tuple(sorted(p)) for p in t.parent[m.num_points:].reshape(-1, 2)}
        for c in marked:
            v = m.cells[c]
            assert {tuple(sorted((v[a], v[(a + 1) % 3]))) for a in range(3)} <= pairs
        # boundary facets are split with their tags: the tagged length is kept
        for tag in (RECT_BOTTOM, RECT_RIGHT, RECT_TOP, RECT_LEFT):
            assert np.isclose(fine.facet_measures()[fine.facet_tags == tag].sum(),
                              m.facet_measures()[m.facet_tags == tag].sum(), rtol=1e-13)
        m = fine
    assert m.num_cells > 4 * 24


def test_bisection_keeps_similarity_classes_and_angles_under_strong_grading():
    """NVB: all descendants of a triangle fall into at most 4 similarity classes (Mitchell), so
    the smallest angle cannot decay however strongly the mesh is graded."""
    m0 = scalene()
    meshes, _ = refine_towards(m0, np.array([0.3, 0.8]), rounds=12)
    fine = meshes[-1]
    assert_conforming(fine)
    h = np.sqrt(fine.cell_measures())
    assert h.max() / h.min() > 100  # strongly graded
    ang = angles(fine)
    classes = np.unique(np.round(ang, 9), axis=0)
    assert len(classes) <= 2 * 4  # two coarse triangles, at most four classes each
    assert ang[:, 0].min() >= angles(m0)[:, 0].min() / 2 - 1e-12


def test_bisection_marks_nothing_changes_nothing_and_all_is_uniform_red():
    m = scalene()
    same, t = bisect(m, [])
    assert np.array_equal(same.cells, m.cells) and t.n_fine == t.n_coarse
    fine, _ = bisect(m, np.arange(m.num_cells))
    red = MeshHierarchy.build(m, 2).finest
    assert fine.num_points == red.num_points and fine.num_cells == red.num_cells == 4 * m.num_cells


def test_bisection_bad_input_is_a_clear_error():
    m = scalene()
    with pytest.raises(ValueError, match="marked cell 5 is outside"):
        bisect(m, [5])
    q = cm.rectangle(2, 2, cell="quad")
    with pytest.raises(ValueError, match="cells"):
        _core.bisect(q.points, q.cells, q.facets, q.facet_tags, np.zeros(0, np.int64))
    with pytest.raises(ValueError, match="not an edge"):
        _core.bisect(m.points, m.cells, np.array([[0, 3]]), np.array([1]), np.zeros(0, np.int64))
    with pytest.raises(ValueError, match="adaptive refinement is for triangle meshes"):
        adaptive_hierarchy(q, 3, lambda h: None)
    with pytest.raises(ValueError, match="theta"):
        adaptive_hierarchy(m, 3, lambda h: None, theta=1.5)
    with pytest.raises(ValueError, match="triangles"):
        hertz_adaptive_hierarchy(3, cell="quad")


def test_bisection_with_projection_lands_new_boundary_nodes_on_the_arc():
    proj = cm.hertz_projector()
    m = cm.hertz_half_disk("triangle")
    m = Mesh(m.points, longest_edge_first(m.points, m.cells), "triangle", m.facets, m.facet_tags)
    meshes, _ = refine_towards(m, np.array([0.0, 0.0]), rounds=10, projector=proj)
    fine = meshes[-1]
    assert_conforming(fine)
    arc = fine.boundary_nodes([cm.HERTZ_ARC])
    assert np.allclose(np.linalg.norm(fine.points[arc] - [0.0, 0.4], axis=1), 0.4, atol=1e-14)


def test_changed_nodes_are_new_nodes_and_their_neighbours():
    m = scalene()
    meshes, transfers = refine_towards(m, np.array([1.0, 0.1]), rounds=6)
    h = MeshHierarchy(meshes, transfers, kind="adaptive")
    assert np.array_equal(h.changed_nodes(0), np.arange(m.num_points))
    for level in range(1, h.levels):
        new = h.new_nodes(level)
        changed = h.changed_nodes(level)
        assert set(new) <= set(changed)
        # independent: a node's hat function changed iff its star of cells changed
        below, here = h.meshes[level - 1], h.meshes[level]
        star = lambda mesh, i: {tuple(sorted(c)) for c in mesh.cells[np.any(mesh.cells == i, axis=1)]}  # noqa: E731
        expect = [i for i in range(below.num_points) if star(below, i) != star(here, i)]
        assert set(changed) - set(new) == set(expect)
    assert len(h.changed_nodes(h.levels - 1)) < h.finest.num_points / 2  # local: a graded level changes few nodes


# -- estimator ------------------------------------------------------------------------------------
def linear_field_problem(h):
    G = np.array([[0.01, -0.02], [0.015, 0.005]])
    return cm.Problem(cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet([1, 2, 3, 4], lambda x: x @ G.T)]))


def test_estimator_vanishes_for_a_solution_exact_in_the_space():
    """A linear displacement is the exact solution of the pure Dirichlet problem with linear data:
    every local defect is zero. A load makes the same estimator positive (it could fail both ways)."""
    m = cm.rectangle(4, 4, distort=0.2, seed=1)
    h = MeshHierarchy.build(m, 2)
    res = linear_field_problem(h).solve(tol=1e-14)
    est = estimate(h, linear_field_problem, res)
    loaded = lambda hh: cm.Problem(cm.Body(hh, cm.Material(100.0, 0.3), [cm.Dirichlet([1, 2, 3, 4], (0.0, 0.0))],
                                           body_force=(0.0, -1.0)))
    est_loaded = estimate(h, loaded, loaded(h).solve(tol=1e-14))
    assert est_loaded.total > 1e-3
    assert est.total < 1e-9 * est_loaded.total * 1e3
    assert est.edge_eta2.max() < 1e-20


def hertz_reference(h, extra=2, friction=0.4):
    proj = cm.hertz_projector()
    meshes, trans = list(h.meshes), list(h.transfers)
    for _ in range(extra):
        m = meshes[-1]
        f, t = _refined(m, _core.refine(m.points, m.cells, m.cell_type, m.facets, m.facet_tags), proj)
        meshes.append(f)
        trans.append(t)
    href = MeshHierarchy(meshes, trans)
    p = hertz_problem_on(href, friction)
    r = p.solve()
    assert r.converged
    return p, r, trans


def test_estimator_tracks_the_energy_error_on_the_adaptive_hertz_hierarchy():
    """Efficiency and reliability proxy: estimate / true energy error (against a reference two
    uniform refinements finer than the finest level) stays in a bounded band over the levels
    while both fall by a factor of about 20."""
    h = hertz_adaptive_hierarchy(6, 0.4)
    pref, rref, trans = hertz_reference(h)
    ratios, errors = [], []
    for level in range(h.levels):
        hl = MeshHierarchy(h.meshes[:level + 1], h.transfers[:level], kind="adaptive")
        r = hertz_problem_on(hl, 0.4).solve()
        u = r.displacement
        for t in trans[level:]:
            u = t.matrix() @ u
        e = u - rref.displacement
        err = np.sqrt(np.sum(e * pref.A.matvec(e)))
        errors.append(err)
        ratios.append(h.estimated_error[level] / err)
        assert np.isclose(estimate(hl, lambda hh: hertz_problem_on(hh, 0.4), r, cm.hertz_projector()).total,
                          h.estimated_error[level], rtol=1e-6)
    ratios = np.array(ratios)
    assert errors[-1] < errors[0] / 5
    assert 0.4 < ratios.min() and ratios.max() < 2.5
    assert ratios.max() / ratios.min() < 1.5


def test_estimator_concentrates_at_the_edge_of_the_contact_zone():
    """Hertz: the pressure has a square-root edge at x = +-a; the largest indicators sit there
    (and not at the centre of the contact zone or in the bulk)."""
    h = hertz_adaptive_hierarchy(5, 0.4)
    p = hertz_problem_on(h, 0.4)
    r = p.solve()
    est = estimate(h, lambda hh: hertz_problem_on(hh, 0.4), r, cm.hertz_projector())
    a = halfwidth(abs(r.reaction[1]))
    top = np.argsort(-est.cell_eta2)[:4]
    centroids = h.finest.points[h.finest.cells[top]].mean(1)
    size = np.sqrt(2 * h.finest.cell_measures()[top])
    assert np.all(np.abs(np.abs(centroids[:, 0]) - a) < 3 * size)
    assert np.all(centroids[:, 1] < 3 * size)


def test_doerfler_marks_the_fewest_cells_of_the_bulk():
    eta2 = np.array([1.0, 4.0, 0.5, 4.0, 0.5])
    marked = doerfler_mark(eta2, 0.5)
    assert set(marked) == {1, 3}
    assert eta2[marked].sum() >= 0.5 * eta2.sum()
    assert set(doerfler_mark(eta2, 0.9)) == {0, 1, 3}
    assert len(doerfler_mark(np.zeros(3), 0.5)) == 0
    with pytest.raises(ValueError, match="theta"):
        doerfler_mark(eta2, 0.0)
    with pytest.raises(ValueError, match="indicators"):
        doerfler_mark(-eta2, 0.5)


# -- adaptive hierarchies -------------------------------------------------------------------------
def test_adaptive_hertz_hierarchy_is_nested_graded_and_near_the_papers_dofs():
    h = hertz_adaptive_hierarchy(7, 0.4)
    assert h.kind == "adaptive" and len(h.estimated_error) == h.levels
    assert np.all(np.diff(h.estimated_error) < 0)
    for level in (3, 5, 7):
        dofs = 2 * h.meshes[level - 1].num_points
        assert PAPER_ADAPTIVE_DOFS[level] / 2 <= dofs <= 2 * PAPER_ADAPTIVE_DOFS[level]
    for coarse, fine, t in zip(h.meshes, h.meshes[1:], h.transfers):
        assert_conforming(fine)
        assert np.array_equal(fine.points[:coarse.num_points], coarse.points)
        assert t.n_fine == fine.num_points and t.n_coarse == coarse.num_points
    # graded towards the contact zone: the smallest cells near y = 0, the bulk stays coarse
    fine = h.finest
    area = fine.cell_measures()
    y = fine.points[fine.cells].mean(1)[:, 1]
    assert y[np.argsort(area)[:20]].max() < 0.05
    assert area.max() / area.min() > 100


def test_algorithm2_on_the_adaptive_hierarchy_is_verified_with_bounded_cycles():
    h = hertz_adaptive_hierarchy(8, 0.4)
    cycles = []
    for F in (0.4, 5.0):
        p = hertz_problem(friction=F, hierarchy=h)
        r = p.solve()
        assert r.converged, r.status
        assert contact_conditions(p, r)["max"] < VIOLATION_TOL
        cycles.append(r.cycles)
        # close to Hertz: the half-width within two contact-zone cells
        a = halfwidth(abs(r.reaction[1]))
        hc = np.diff(np.sort(p.mesh.points[r.contact_nodes[r.contact_state > 0], 0])).max()
        assert abs(r.contact_halfwidth - a) < 2 * hc
    assert max(cycles) <= 30


def test_hertz_problem_hierarchy_option():
    with pytest.raises(ValueError, match="hierarchy must be one of"):
        hertz_problem(levels=2, hierarchy="graded")
    p = hertz_problem(levels=3, hierarchy="adaptive")
    assert p.hierarchy.kind == "adaptive" and p.hierarchy.levels == 3


# -- command line ---------------------------------------------------------------------------------
def run(*args, timeout=120):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=timeout)


def test_cli_hertz_hierarchy_option_and_estimated_error():
    import json

    r = run("hertz", "--hierarchy", "adaptive", "--levels", "6", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["hierarchy"] == "adaptive" and d["converged"] and d["dofs"] == 2 * d["nodes"]
    assert len(d["estimated_error"]) == 6 and np.all(np.diff(d["estimated_error"]) < 0)
    u = json.loads(run("hertz", "--levels", "3", "--json", "-", "-q").stdout)
    assert u["hierarchy"] == "uniform" and "estimated_error" not in u
    bad = run("hertz", "--hierarchy", "adaptive", "--cell", "quad")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "triangles" in bad.stderr.strip().splitlines()[-1]
    bad = run("hertz", "--hierarchy", "graded")
    assert bad.returncode == 2 and "hierarchy" in bad.stderr.strip().splitlines()[-1]


def test_cli_table1_adaptive_levels_near_the_papers_dofs_and_verified():
    import json

    r = run("table1", "--hierarchy", "adaptive", "--levels", "3", "5", "--frictions", "0.4", "5", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["hierarchy"] == "adaptive" and len(d["estimated_error"]) == 2
    for L, dofs in zip(d["levels"], d["dofs"]):
        assert PAPER_ADAPTIVE_DOFS[L] / 2 <= dofs <= 2 * PAPER_ADAPTIVE_DOFS[L]
    assert np.all(np.array(d["nmg_converged"])) and np.max(d["nmg_violation"]) < VIOLATION_TOL


@pytest.fixture(scope="module")
def hertz_adaptive_9():
    return hertz_adaptive_hierarchy(9, 0.4)


@pytest.mark.slow
@pytest.mark.parametrize("F", [0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0])
def test_algorithm2_on_adaptive_levels_for_the_paper_frictions(F, hertz_adaptive_9):
    """Levels 3-9 of the adaptive hierarchy (59k dofs): every Algorithm 2 result converged and
    verified by the independent check, Algorithm 1 = Algorithm 2 where both converge (level 7); for
    F <= 2 cycles bounded (<= 25) and within a spread of 4 from level 5 on. Not met, so not
    asserted: the spread <= 4 from level 3 on (measured 2026-12-02 with the default
    omega = 1.3: levels 3-9 spread 3-5 for F <= 2, 5 at F = 0.4; level 3, a 3-level hierarchy
    with an exact 28-node coarse solve, needs 9-12 cycles; 0018-adaptive-estimator). With
    plain Gauss-Seidel (omega = 1) F = 0.4 failed the level-5-on spread here (12 / 15 / 17)."""
    h = hertz_adaptive_9
    cycles = []
    for L in (3, 5, 7, 9):
        p = hertz_problem(friction=F, hierarchy=h.truncated(L), coulomb_at_zero=True)
        r = p.solve()
        assert r.converged, (F, L, r.status)
        assert contact_conditions(p, r)["max"] < VIOLATION_TOL
        cycles.append(r.cycles)
        if L == 7:
            fp = p.solve("fixed-point")
            if fp.converged:
                e = fp.displacement - r.displacement
                assert np.sqrt(np.sum(e * p.A.matvec(e))) <= 1e-6 * np.sqrt(np.sum(r.displacement * p.A.matvec(r.displacement)))
    if F <= 2:
        assert max(cycles) <= 25 and max(cycles[1:]) - min(cycles[1:]) <= 4, (F, cycles)


def test_adaptive_beats_uniform_at_comparable_dofs():
    """Frictionless Hertz, against a common reference (adaptive level 7 refined uniformly twice):
    adaptive level 6 (2.3k dofs) has less than half the energy error of uniform level 4 (2.45k
    dofs), and its contact half-width and peak pressure are closer to Hertz's."""
    import matplotlib.tri as mtri

    h = hertz_adaptive_hierarchy(7, 0.0)
    pref, rref, trans = hertz_reference(h, friction=0.0)
    norm = np.sqrt(np.sum(rref.displacement * pref.A.matvec(rref.displacement)))

    def err(u):
        e = u - rref.displacement
        return np.sqrt(np.sum(e * pref.A.matvec(e))) / norm

    pa = hertz_problem_on(h.truncated(6), 0.0)
    ra = pa.solve()
    ua = ra.displacement
    for t in trans[5:]:
        ua = t.matrix() @ ua
    pu = hertz_problem(levels=4, friction=0.0)
    ru = pu.solve()
    tri = mtri.Triangulation(pu.mesh.points[:, 0], pu.mesh.points[:, 1], pu.mesh.cells)
    q = pref.mesh.points.copy()
    inside = tri.get_trifinder()(q[:, 0], q[:, 1]) >= 0
    q[~inside] = np.array([0.0, 0.4]) + (q[~inside] - [0.0, 0.4]) * (1 - 2e-2)  # just inside the inscribed polygon
    uu = np.stack([mtri.LinearTriInterpolator(tri, ru.displacement[:, a])(q[:, 0], q[:, 1]).data for a in range(2)], 1)
    assert np.all(np.isfinite(uu))
    assert 2 * pa.mesh.num_points <= 2 * pu.mesh.num_points
    assert err(ua) < 0.5 * err(uu)
    for r in (ra, ru):
        r.hertz = (halfwidth(abs(r.reaction[1])), peak_pressure(abs(r.reaction[1])))
    assert abs(ra.contact_halfwidth - ra.hertz[0]) < abs(ru.contact_halfwidth - ru.hertz[0])
    assert abs(-ra.normal_stress.min() - ra.hertz[1]) < abs(-ru.normal_stress.min() - ru.hertz[1])
