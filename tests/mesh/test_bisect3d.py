"""Newest-vertex bisection of tetrahedra (Arnold-Mukherjee-Pouly marked bisection)
and adaptive tetrahedral hierarchies: conformity after the closure, volumes, nestedness, shape
regularity under refinement of a point, the boundary projection, the adaptive sphere."""
import json

import numpy as np
import pytest

import contactmg as cm
from contactmg import _core
from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.mesh.generators_3d import BALL_SURFACE, BALL_TOP, ball_projector, half_ball
from contactmg.mesh.hierarchy import MeshHierarchy, _refined
from contactmg.solve.adaptivity import adaptive_hierarchy
from contactmg.mesh.mesh import Mesh

TET_EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
TET_FACES = np.array([(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])


def bisect(mesh, marked, marks=None, projector=None, generations=3):
    r = _core.bisect(mesh.points, mesh.cells, mesh.facets, mesh.facet_tags, np.asarray(marked, dtype=np.int64),
                     marks=marks, generations=generations)
    fine, t = _refined(mesh, r, projector)
    return fine, t, r


def distorted_box(n=2, seed=1):
    m = cm.box(n, n, n, cell="tetra")
    rng = np.random.default_rng(seed)
    p = m.points.copy()
    inner = np.all((p > 1e-9) & (p < 1 - 1e-9), axis=1)
    p[inner] += rng.uniform(-0.15, 0.15, (inner.sum(), 3)) / n
    return Mesh(p, m.cells, "tetra", m.facets, m.facet_tags)


def volumes(mesh):
    X = mesh.points[mesh.cells]
    return np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0])) / 6


def keys(rows, n):
    """One integer per row of sorted node numbers."""
    k = np.zeros(len(rows), dtype=np.int64)
    for j in range(rows.shape[1]):
        k = k * n + rows[:, j]
    return k


def assert_conforming(mesh, r):
    """Every face of a tetrahedron is shared by exactly two of them or is a boundary facet; no new
    node hangs: the edge a new node bisects is an edge of no fine tetrahedron (so the node lies in
    every tetrahedron around that edge)."""
    faces = np.sort(mesh.cells[:, TET_FACES].reshape(-1, 3), axis=1)
    uniq, count = np.unique(faces, axis=0, return_counts=True)
    assert count.max() == 2
    single = {tuple(f) for f in uniq[count == 1]}
    facets = {tuple(sorted(f)) for f in mesh.facets}
    assert single == facets
    edges = keys(np.sort(mesh.cells[:, TET_EDGES].reshape(-1, 2), axis=1), mesh.num_points)
    assert not np.any(np.isin(keys(np.sort(r["edge_parents"], axis=1), mesh.num_points), edges))
    assert np.all(volumes(mesh) > 0)


def min_dihedral(mesh):
    X = mesh.points[mesh.cells]
    normals = []
    for f in TET_FACES:
        n = np.cross(X[:, f[1]] - X[:, f[0]], X[:, f[2]] - X[:, f[0]])
        normals.append(n / np.linalg.norm(n, axis=1)[:, None])
    out = np.full(len(X), np.pi)
    for i in range(4):
        for j in range(i + 1, 4):
            # the dihedral angle at the edge shared by faces i and j is pi minus the normals' angle
            cos = np.abs(np.einsum("ci,ci->c", normals[i], normals[j]))
            out = np.minimum(out, np.arccos(np.clip(cos, -1, 1)))
    return out


def similarity_classes(mesh):
    """Shapes up to scale: the sorted edge lengths over the longest one (rounded)."""
    X = mesh.points[mesh.cells]
    L = np.linalg.norm(X[:, TET_EDGES[:, 0]] - X[:, TET_EDGES[:, 1]], axis=2)
    L = np.sort(L, axis=1) / L.max(axis=1, keepdims=True)
    return len(np.unique(np.round(L, 8), axis=0))


# -- the bisection -------------------------------------------------------------------------------
def test_random_marking_stays_conforming_nested_and_keeps_volume_and_facets():
    rng = np.random.default_rng(3)
    m = distorted_box(2)
    marks = None
    G = np.array([[0.3, -1.1, 0.2], [0.7, 0.4, -0.5], [0.1, 0.0, 2.0]])
    area0 = {t: m.facet_measures()[m.facet_tags == t].sum() for t in range(1, 7)}
    for level in range(3):
        marked = np.flatnonzero(rng.random(m.num_cells) < 0.15)
        fine, t, r = bisect(m, marked, marks)
        assert_conforming(fine, r)
        assert len(r["marks"]) == fine.num_cells and np.all((r["marks"] >= 0) & (r["marks"] < 18))
        # nested: the coarse nodes keep their numbers and places, a linear field is interpolated exactly
        assert np.array_equal(fine.points[:m.num_points], m.points)
        f = m.points @ G.T + [0.5, -2.0, 1.0]
        assert np.allclose(t.matrix() @ f, fine.points @ G.T + [0.5, -2.0, 1.0], atol=1e-13)
        # every new node is the midpoint of its two parents; its interpolation lives on one coarse cell
        ep = r["edge_parents"]
        assert np.allclose(fine.points[m.num_points:], 0.5 * (fine.points[ep[:, 0]] + fine.points[ep[:, 1]]), atol=1e-15)
        size = np.diff(t.ptr)[m.num_points:]
        for k, local in ((2, TET_EDGES), (3, TET_FACES), (4, np.arange(4)[None])):
            rows = np.flatnonzero(size == k) + m.num_points
            support = np.sort(t.parent[t.ptr[rows][:, None] + np.arange(k)], axis=1)
            own = np.sort(m.cells[:, local].reshape(-1, k), axis=1)
            assert np.all(np.isin(keys(support, m.num_points), keys(own, m.num_points)))
        assert np.all((size >= 2) & (size <= 4))
        assert np.isclose(volumes(fine).sum(), 1.0, rtol=1e-13)
        # each boundary facet split with its tag: tagged areas kept
        for tag, a in area0.items():
            assert np.isclose(fine.facet_measures()[fine.facet_tags == tag].sum(), a, rtol=1e-12)
        # the marked cells were bisected three times: none of them is left, their volume went to 8+ pieces
        assert fine.num_cells >= m.num_cells + 7 * len(marked)
        m, marks = fine, r["marks"]


def test_one_generation_bisects_each_marked_cell_once_and_closes():
    rng = np.random.default_rng(5)
    m, marks = distorted_box(1, seed=4), None
    for _ in range(5):
        marked = np.flatnonzero(rng.random(m.num_cells) < 0.3)
        fine, t, r = bisect(m, marked, marks, generations=1)
        assert_conforming(fine, r)
        assert fine.num_cells >= m.num_cells + len(marked)
        assert np.isclose(volumes(fine).sum(), 1.0, rtol=1e-13)
        m, marks = fine, r["marks"]


def test_marking_every_cell_three_times_splits_every_edge_once():
    """Three generations of bisection of all cells put a node on every edge and nowhere else, and
    give 8 children per cell: the node count of red refinement, for the Kuhn box and the ball."""
    for mesh in (distorted_box(2), half_ball("tetra", k=1)):
        fine, t, r = bisect(mesh, np.arange(mesh.num_cells))
        red = MeshHierarchy.build(mesh, 2).finest
        assert fine.num_points == red.num_points
        assert fine.num_cells == 8 * mesh.num_cells
        assert_conforming(fine, r)
        # every new node is the midpoint of a coarse edge: weights 1/2, 1/2 on its two parents
        assert np.all(np.diff(t.ptr)[mesh.num_points:] == 2)
        assert set(map(tuple, np.sort(r["edge_parents"], axis=1))) == \
            set(map(tuple, np.sort(mesh.cells[:, TET_EDGES].reshape(-1, 2), axis=1)))


def test_repeated_refinement_of_a_point_keeps_the_shapes():
    """AMP: the descendants of a tetrahedron fall into finitely many similarity classes, so the
    smallest dihedral angle stays bounded below however often a point is refined."""
    mesh = cm.box(1, 1, 1, cell="tetra")  # 6 Kuhn tetrahedra
    point = np.array([0.3, 0.2, 0.1])
    marks = None
    angle0 = min_dihedral(mesh).min()
    seen = []
    m = mesh
    for _ in range(8):
        centroid = m.points[m.cells].mean(axis=1)
        dist = np.linalg.norm(centroid - point, axis=1)
        marked = np.flatnonzero(dist <= np.sort(dist)[min(3, len(dist) - 1)])
        m, t, r = bisect(m, marked, marks)
        marks = r["marks"]
        seen.append(min_dihedral(m).min())
    h = np.cbrt(volumes(m))
    assert h.max() / h.min() > 50  # strongly graded
    # Kuhn tetrahedra: bisection keeps them Kuhn-like (measured: 3 classes, the angle stays 45 degrees)
    assert min(seen) >= 0.9 * angle0
    assert similarity_classes(m) <= 6


def test_shapes_stay_in_finitely_many_classes_on_a_general_mesh():
    """The 12-tetrahedra split of a box-shaped hexahedron (not a Kuhn mesh: 3 shapes, a centre
    node) refined towards a point 10 times: the similarity classes saturate (measured: 42 after
    round 4) and the smallest dihedral angle stays put (31.6 degrees initially, 26.2 from the first
    bisections on) while the cell sizes spread over three decades."""
    from contactmg.mesh.generators_3d import _hexes_to_tets

    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
                 float) * [1.0, 0.8, 1.3]
    pts, tets = _hexes_to_tets(P, np.arange(8)[None])
    m = Mesh.from_cells(pts, tets, "tetra", lambda mid: np.ones(len(mid), np.int64))
    angle0 = min_dihedral(m).min()
    point, marks, classes, angles = np.array([0.3, 0.2, 0.1]), None, [], []
    for _ in range(10):
        d = np.linalg.norm(m.points[m.cells].mean(axis=1) - point, axis=1)
        m, t, r = bisect(m, np.flatnonzero(d <= np.sort(d)[min(3, len(d) - 1)]), marks)
        marks = r["marks"]
        classes.append(similarity_classes(m))
        angles.append(min_dihedral(m).min())
    h = np.cbrt(volumes(m))
    assert h.max() / h.min() > 500
    assert classes[-1] <= classes[4]  # no new shapes in the last five rounds
    assert min(angles) >= 0.75 * angle0


def test_new_boundary_nodes_lie_on_the_sphere_and_tags_are_inherited():
    center, radius = (0.0, 0.0, 0.4), 0.4
    mesh = half_ball("tetra", center, radius, k=1)
    proj = ball_projector(center, radius)
    marks = None
    m = mesh
    for _ in range(2):
        bottom = m.points[m.cells].mean(axis=1)[:, 2] < 0.15
        fine, t, r = bisect(m, np.flatnonzero(bottom), marks, projector=proj)
        assert_conforming(fine, r)
        new = np.arange(m.num_points, fine.num_points)
        on_sphere = np.unique(fine.facets[fine.facet_tags == BALL_SURFACE])
        on_sphere = np.intersect1d(on_sphere, new)
        assert len(on_sphere) > 0
        assert np.allclose(np.linalg.norm(fine.points[on_sphere] - center, axis=1), radius, rtol=1e-13)
        top = np.unique(fine.facets[fine.facet_tags == BALL_TOP])
        assert np.allclose(fine.points[top, 2], 0.4)
        # facets face outwards: their normals point away from the ball's centre
        X = fine.points[fine.facets]
        nrm = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        assert np.all(np.einsum("ci,ci->c", nrm, X.mean(axis=1) - center) > 0)
        m, marks = fine, r["marks"]


def test_bisection_bad_input_is_a_clear_error():
    m = cm.box(1, 1, 1, cell="tetra")
    args = (m.points, m.cells, m.facets, m.facet_tags)
    with pytest.raises(ValueError, match="marked cell 6 is outside"):
        _core.bisect(*args, np.array([6]))
    with pytest.raises(ValueError, match="outside 0..17"):
        _core.bisect(*args, np.array([0]), marks=np.full(6, 18))
    bad = m.cells.copy()
    bad[0] = bad[0][[1, 0, 2, 3]]
    with pytest.raises(ValueError, match="inverted"):
        _core.bisect(m.points, bad, m.facets, m.facet_tags, np.array([0]))
    with pytest.raises(ValueError, match="not a face of any cell"):
        _core.bisect(m.points, m.cells, np.array([[0, 1, 2]]), np.array([1]), np.array([0]))
    with pytest.raises(ValueError, match="generations"):
        _core.bisect(*args, np.array([0]), generations=0)
    # marks from another mesh: the neighbours disagree on a common face
    r = _core.bisect(*args, np.array([0]))
    wrong = (r["marks"] + 1) % 9
    with pytest.raises(ValueError, match="disagree"):
        _core.bisect(r["points"], r["cells"], r["facets"], r["facet_tags"], np.array([0]), marks=wrong)
    with pytest.raises(ValueError, match="marks are for tetrahedra"):
        tri = cm.rectangle(2, 2)
        _core.bisect(tri.points, tri.cells, tri.facets, tri.facet_tags, np.array([0]), marks=np.zeros(8))


# -- adaptive tetrahedral hierarchies ------------------------------------------------------------
@pytest.fixture(scope="module")
def adaptive_sphere():
    from contactmg.examples import sphere

    coarse = half_ball("tetra", sphere.CENTER, sphere.RADIUS, k=2, inner=sphere.INNER)
    h = sphere.sphere_adaptive_hierarchy(4, friction=0.4, coarse=coarse)
    return h


def test_adaptive_sphere_hierarchy_is_nested_graded_and_its_solve_verified(adaptive_sphere):
    from contactmg.examples import sphere

    h = adaptive_sphere
    assert h.kind == "adaptive" and h.levels == 4 and len(h.estimated_error) == 4
    assert h.bisection_marks is not None and len(h.bisection_marks) == h.finest.num_cells
    for coarse, fine, t in zip(h.meshes, h.meshes[1:], h.transfers):
        assert np.array_equal(fine.points[:coarse.num_points], coarse.points)
        assert fine.num_points > coarse.num_points
        assert np.isclose(volumes(fine).sum(), volumes(coarse).sum(), rtol=0.05)  # the sphere's facets move out
        assert np.all(volumes(fine) > 0)
    # refined towards the contact disc: the finest cells sit at the bottom
    fine = h.finest
    vol = volumes(fine)
    z = fine.points[fine.cells].mean(axis=1)[:, 2]
    assert np.median(vol[z < 0.05]) < 0.2 * np.median(vol[z > 0.3])
    # the estimate decreases
    assert h.estimated_error[-1] < h.estimated_error[0]
    problem = sphere.sphere_problem_on(h, friction=0.4)
    result = problem.solve()
    assert result.converged
    rep = contact_conditions(problem, result)
    assert rep["max"] < VIOLATION_TOL
    assert result.counts()["contact_nodes"] > 10


def test_estimator_tracks_the_energy_error_in_3d(adaptive_sphere):
    """Efficiency and reliability proxy in 3D: estimate / energy error against a reference (the
    finest adaptive level refined once more, red; coarser solutions prolongated through the nested
    hierarchy) stays in a band while the error falls by 4 (measured: 0.73, 1.17, 0.93, 0.93)."""
    from contactmg.examples import sphere

    h = adaptive_sphere
    m = h.finest
    f, t = _refined(m, _core.refine(m.points, m.cells, "tetra", m.facets, m.facet_tags),
                    ball_projector(sphere.CENTER, sphere.RADIUS))
    href = MeshHierarchy(list(h.meshes) + [f], list(h.transfers) + [t])
    pref = sphere.sphere_problem_on(href, 0.4)
    rref = pref.solve()
    assert rref.converged
    ratios, errors = [], []
    for level in range(h.levels):
        r = sphere.sphere_problem_on(h.truncated(level + 1), 0.4).solve(max_cycles=sphere.ADAPTIVE_MAX_CYCLES)
        assert r.converged
        u = r.displacement
        for tt in href.transfers[level:]:
            u = tt.matrix() @ u
        e = u - rref.displacement
        errors.append(np.sqrt(np.sum(e * pref.A.matvec(e))))
        ratios.append(h.estimated_error[level] / errors[-1])
    assert errors[-1] < errors[0] / 3
    assert 0.5 < min(ratios) and max(ratios) < 2.0


def test_adaptive_needs_simplices():
    hexes = half_ball("hexahedron", k=1)
    with pytest.raises(ValueError, match="simplices"):
        adaptive_hierarchy(hexes, 2, lambda h: None)
    from contactmg.examples import sphere

    with pytest.raises(ValueError, match="simplices"):
        sphere.sphere_problem("hexahedron", 2, hierarchy="adaptive")


def test_sphere_cli_adaptive_json_and_hexahedron_error(tmp_path, capsys):
    from contactmg.cli.main import main

    code = main(["sphere", "--cell", "hexahedron", "--hierarchy", "adaptive", "--levels", "2", "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "simplices" in err[0]
    out = tmp_path / "s.json"
    # frictionless: the level-1 solve (no coarser level) needs more than the default 200 cycles
    code = main(["sphere", "--cell", "tetra", "--hierarchy", "adaptive", "--levels", "2", "--friction", "0",
                 "--json", str(out), "-q"])
    rep = json.loads(out.read_text())
    assert code == 0 and rep["converged"]
    assert rep["hierarchy"] == "adaptive" and len(rep["estimated_error"]) == 2
    assert rep["estimated_error"][1] < rep["estimated_error"][0]
    assert rep["dim"] == 3 and rep["levels"] == 2
