"""Answers that were wrong without a word (all items but 1, partial Dirichlet on contact
nodes). Each case: the setup that used to pass silently now gets a clear error or warning, or the
check/measure that used to be wrong now holds -- and the valid neighbour of each case still works."""
import subprocess
import sys
import warnings

import meshio
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz
from contactmg.results import plots
from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_TOP, rectangle
from contactmg.mesh.mesh import Mesh
from contactmg.model.problem import Body, Dirichlet, Problem

MAT = cm.Material(1000.0, 0.3)


def rotated(mesh: Mesh, angle: float) -> Mesh:
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]])
    return Mesh(mesh.points @ R.T, mesh.cells, mesh.cell_type, mesh.facets, mesh.facet_tags)


def block_on_plane(angle=0.0, push=-0.01, F=0.3, levels=4, cell="triangle", lx=2.0, gap=0.0):
    """A 2 x 1 block whose bottom lies on a plane (at distance `gap`), both tilted by `angle`; the
    top is displaced by `push` along the block's own vertical (negative: onto the plane)."""
    mesh = rotated(rectangle(4, 2, lx, 1.0, cell), angle)
    up = np.array([-np.sin(angle), np.cos(angle)])
    h = cm.MeshHierarchy.build(mesh, levels)
    law = cm.Coulomb(F) if F > 0 else cm.Frictionless()
    return Problem(Body(h, MAT, [Dirichlet(RECT_TOP, tuple(push * up))], contact_tags=RECT_BOTTOM),
                   obstacle=cm.PlaneObstacle(tuple(-gap * up), tuple(-up)), friction=law)


# -- item 2: the independent check on zero-gap, tilted and lifted-off scenes -----------------------
@pytest.mark.parametrize("angle, push", [(0.0, -0.01), (np.radians(10), -0.01), (np.radians(10), 0.01),
                                         (0.0, 0.01)], ids=["flat", "tilted", "tilted-lifted", "lifted"])
def test_check_passes_correct_and_rejects_perturbed_solutions(angle, push):
    p = block_on_plane(angle, push)
    res = p.solve()
    assert res.converged and res.sweep_check < 1e-9
    assert np.abs(p.contact.gaps).max() < 1e-14  # zero gaps up to round-off
    v = contact_conditions(p, res)
    # the tilted scene failed here before: penetration 1e-16 divided by max |u_n| ~ 1e-17
    assert v["max"] < VIOLATION_TOL, v
    # push one contact node into the obstacle, 1e-4 of the displacement scale beyond its gap
    scale = np.abs(res.displacement).max()
    bad = res.__class__(**{**res.__dict__, "displacement": res.displacement.copy()})
    c = len(p.contact.nodes) // 2
    k, n = p.contact.nodes[c], p.contact.normals[c]
    bad.displacement[k] += (p.contact.gaps[c] - res.displacement[k] @ n + 1e-4 * scale) * n
    w = contact_conditions(p, bad)
    assert w["penetration"] > VIOLATION_TOL and w["max"] > VIOLATION_TOL
    # move an interior node: its residual is a force nobody applies
    bad2 = res.__class__(**{**res.__dict__, "displacement": res.displacement.copy()})
    interior = np.flatnonzero(~p.fixed.any(axis=1) & ~np.isin(np.arange(p.mesh.num_points), p.contact.nodes))
    bad2.displacement[interior[0]] += 1e-4 * scale
    assert contact_conditions(p, bad2)["interior"] > VIOLATION_TOL


# -- item 3: contact tags equal to the Dirichlet tags --------------------------------------------
def test_contact_boundary_left_empty_by_dirichlet_is_an_error():
    h = cm.MeshHierarchy.build(rectangle(2, 2), 2)
    with pytest.raises(ValueError, match="contact boundary is empty"):
        Problem(Body(h, MAT, [Dirichlet([RECT_BOTTOM], (0.0, 0.0))], contact_tags=[RECT_BOTTOM]),
                obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    # the same problem with a free contact side is a contact problem
    p = Problem(Body(h, MAT, [Dirichlet([RECT_TOP], (0.0, -0.01))], contact_tags=[RECT_BOTTOM]),
                obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    assert p.law == "frictionless" and len(p.contact.nodes) == 5  # the bottom nodes of level 2


# -- item 4: malformed facets, in 2D and 3D ------------------------------------------------------
def unit_cube(cell):
    x = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], float)  # node i + 2j + 4k
    if cell == "hexahedron":  # two hexahedra side by side: one interior face
        x2 = np.vstack([x, x[[1, 3, 5, 7]] + [1, 0, 0]])
        cells = np.array([[0, 1, 3, 2, 4, 5, 7, 6], [1, 8, 9, 3, 5, 10, 11, 7]])
        return Mesh.from_cells(x2, cells, "hexahedron")
    # six tetrahedra around the diagonal 0-7
    tets = [[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]]
    return Mesh.from_cells(x, np.array(tets), "tetra")


MESHES = {"triangle": lambda: rectangle(2, 2, cell="triangle"), "quad": lambda: rectangle(2, 2, cell="quad"),
          "tetra": lambda: unit_cube("tetra"), "hexahedron": lambda: unit_cube("hexahedron")}


def interior_facet(m: Mesh) -> np.ndarray:
    from contactmg.mesh.mesh import _LOCAL_FACETS

    local = np.array(_LOCAL_FACETS[m.cell_type])
    all_f = m.cells[:, local].reshape(-1, local.shape[1])
    key = np.sort(all_f, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return all_f[np.flatnonzero(cnt[inv.ravel()] == 2)[0]]


@pytest.mark.parametrize("cell", list(MESHES))
def test_malformed_facets_are_rejected(cell):
    m = MESHES[cell]()
    assert m.cell_type == cell and len(m.facets) > 0
    facets, tags = m.facets, m.facet_tags
    with pytest.raises(ValueError, match="given 2 times"):
        Mesh(m.points, m.cells, cell, np.vstack([facets, facets[:1]]), np.r_[tags, tags[:1]])
    with pytest.raises(ValueError, match="given 2 times"):  # the same facet with its nodes in another order
        Mesh(m.points, m.cells, cell, np.vstack([facets, facets[:1, ::-1]]), np.r_[tags, tags[:1]])
    with pytest.raises(ValueError, match="not a boundary facet"):
        Mesh(m.points, m.cells, cell, np.vstack([facets, interior_facet(m)]), np.r_[tags, 7])
    for bad in (np.nan, 1.5, np.inf):
        t = tags.astype(float)
        t[0] = bad
        with pytest.raises(ValueError, match="facet tags must be integers"):
            Mesh(m.points, m.cells, cell, facets, t)
    with pytest.raises(ValueError, match="facet tags must be integers"):  # a tagger that gives NaN
        Mesh.from_cells(m.points, m.cells, cell, lambda mid: np.where(mid[:, 0] > 0.5, np.nan, 1.0))
    # integer-valued floats are integers; a facet given against its cell's orientation is turned
    # outward (its normal is the outward one)
    ok = Mesh(m.points, m.cells, cell, facets[:, ::-1], tags.astype(float))
    np.testing.assert_array_equal(ok.facet_tags, tags)
    np.testing.assert_allclose(ok.facet_normals(), m.facet_normals())


def test_read_mesh_rejects_non_integer_tags(tmp_path):
    r = rectangle(2, 2)
    tags = np.arange(len(r.facets), dtype=float)
    meshio.write(tmp_path / "ok.vtu", meshio.Mesh(r.points, [("triangle", r.cells), ("line", r.facets)],
                                                  cell_data={"tag": [np.zeros(r.num_cells), tags]}))
    np.testing.assert_array_equal(np.sort(cm.read_mesh(tmp_path / "ok.vtu").facet_tags), np.arange(len(r.facets)))
    tags[3] = np.nan
    meshio.write(tmp_path / "nan.vtu", meshio.Mesh(r.points, [("triangle", r.cells), ("line", r.facets)],
                                                   cell_data={"tag": [np.zeros(r.num_cells), tags]}))
    with pytest.raises(ValueError, match="facet tags must be integers"):
        cm.read_mesh(tmp_path / "nan.vtu")


def test_mesh_that_is_no_manifold_or_overlaps_is_rejected():
    pts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1], [1.5, 0.5]], float)
    # three triangles on the edge 0-1
    with pytest.raises(ValueError, match="not a manifold"):
        Mesh.from_cells(pts, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]), "triangle")
    # two triangles that overlap and share no edge: a node of one inside the other
    pts2 = np.array([[0, 0], [2, 0], [0, 2], [0.5, 0.5], [3, 0.5], [0.5, 3]], float)
    with pytest.raises(ValueError, match="overlaps itself"):
        Mesh.from_cells(pts2, np.array([[0, 1, 2], [3, 4, 5]]), "triangle")
    # a star of David: edges cross, no node inside the other triangle
    star = np.array([[0, 1], [-0.866, -0.5], [0.866, -0.5], [0, -1], [0.866, 0.5], [-0.866, 0.5]])
    with pytest.raises(ValueError, match="overlaps itself"):
        Mesh.from_cells(star, np.array([[0, 1, 2], [3, 4, 5]]), "triangle")
    # neighbours that touch in one node, or in one edge, are fine
    Mesh.from_cells(np.array([[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]], float),
                    np.array([[0, 1, 2], [0, 3, 4]]), "triangle")
    Mesh.from_cells(pts[:4], np.array([[0, 1, 2], [1, 0, 3]]), "triangle")


# -- item 5: a disconnected piece without Dirichlet data -----------------------------------------
def two_blocks(cell="triangle"):
    a, b = rectangle(2, 2, cell=cell), rectangle(2, 2, cell=cell, origin=(2.0, 0.0))
    n = a.num_points
    tags = np.r_[a.facet_tags, b.facet_tags + 10]
    return Mesh(np.vstack([a.points, b.points]), np.vstack([a.cells, b.cells + n]), cell,
                np.vstack([a.facets, b.facets + n]), tags)


def test_rigid_motion_is_checked_piece_by_piece():
    h = cm.MeshHierarchy.build(two_blocks(), 3)
    with pytest.raises(ValueError, match="rigid-body motion of piece 2 of the 2 disconnected pieces"):
        Problem(Body(h, MAT, [Dirichlet([RECT_LEFT], (0.0, 0.0))], body_force=(0.0, -1.0)))
    # both pieces held: solves, and each behaves as the block alone
    p = Problem(Body(h, MAT, [Dirichlet([RECT_LEFT], (0.0, 0.0)), Dirichlet([RECT_LEFT + 10], (0.0, 0.0))],
                     body_force=(0.0, -1.0)))
    res = p.solve()
    assert res.converged
    single = Problem(Body(cm.MeshHierarchy.build(rectangle(2, 2), 3), MAT, [Dirichlet([RECT_LEFT], (0.0, 0.0))],
                          body_force=(0.0, -1.0))).solve()
    from scipy.spatial import cKDTree

    x = res.mesh.points
    dist, twin = cKDTree(single.mesh.points).query(np.where(x[:, :1] >= 2.0, x - [2.0, 0.0], x))
    assert dist.max() < 1e-12 and res.mesh.num_points == 2 * single.mesh.num_points
    np.testing.assert_allclose(res.displacement, single.displacement[twin], atol=1e-12)


# -- smaller ones -------------------------------------------------------------------------------
def test_cycle_counts_out_of_range_are_refused_first():
    p = hertz.hertz_problem("triangle", 2, 0.4)
    for bad in (2 ** 31, -1, 0):
        with pytest.raises(ValueError, match=r"max_cycles must be an integer in 1\.\.2147483647"):
            p.solve(max_cycles=bad)
    with pytest.raises(ValueError, match="fixed_point_max"):
        p.solve("fixed-point", fixed_point_max=2 ** 31)
    assert p.solve(max_cycles=2 ** 31 - 1).converged


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, cwd=cwd)


def test_cli_refuses_unusable_outputs_before_the_solve(tmp_path):
    r = run_cli("hertz", "--levels", "3", "--max-cycles", "2147483648")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "--max-cycles must lie in 1..2147483647" in r.stderr.strip().splitlines()[-1]
    for flag, path in (("--vtu", "-"), ("--plot", "-"), ("--vtu", ""), ("--vtu", str(tmp_path))):
        out = tmp_path / "report.json"
        r = run_cli("hertz", "--levels", "3", "--json", str(out), flag, path)
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert flag in r.stderr.strip().splitlines()[-1]
        assert not out.exists()  # nothing was solved: the JSON report is written right after the solve


def test_write_vtu_and_write_mesh_write_what_the_extension_says(tmp_path):
    res = hertz.hertz_problem("triangle", 2, 0.4).solve()
    with pytest.raises(ValueError, match="does not end in .vtu"):
        res.write_vtu(tmp_path / "x.msh")
    assert not (tmp_path / "x.msh").exists()
    res.write_vtu(tmp_path / "x.vtu")
    back = meshio.read(tmp_path / "x.vtu")
    np.testing.assert_allclose(back.point_data["displacement"][:, :2], res.displacement)
    # .msh is Gmsh (meshio would pick ANSYS and fail); the tags come back
    cm.write_mesh(tmp_path / "y.msh", res.mesh, point_data=res.point_data())
    again = cm.read_mesh(tmp_path / "y.msh")
    np.testing.assert_array_equal(np.sort(again.facet_tags), np.sort(res.mesh.facet_tags))
    for ext in (".stl", ".obj", ".foo", ""):  # formats that would drop cells or data: refused
        with pytest.raises(ValueError, match="write_mesh writes"):
            cm.write_mesh(tmp_path / f"z{ext}", res.mesh)


def test_zone_measures_hold_for_every_problem():
    # a flat block pressed down: the whole bottom (length 2) is in contact; large F: all of it sticks
    p = block_on_plane(push=-0.01, F=5.0, levels=4)
    res = p.solve()
    assert res.converged and res.counts()["contact_nodes"] == len(p.contact.nodes)
    assert res.contact_extent == pytest.approx(2.0, rel=1e-12)
    assert res.stick_extent == pytest.approx(2.0, rel=1e-12) and res.slip_extent == 0.0
    with pytest.raises(ValueError, match="Hertz benchmark"):
        res.contact_halfwidth
    # tilted by 10 degrees: the same zone, the same measure (|x| from 0 would not be)
    tilted = block_on_plane(np.radians(10), push=-0.01, F=5.0, levels=4).solve()
    assert tilted.contact_extent == pytest.approx(2.0, rel=1e-12)
    # Hertz: the extent is the contact zone 2a plus half a facet on either side (the zone may
    # reach one node further on one side than on the other)
    h = hertz.hertz_problem("triangle", 6, 0.4).solve()
    facet = np.linalg.norm(np.diff(h.mesh.points[h.contact_facets], axis=1), axis=-1).max()
    for width, extent in ((h.contact_halfwidth, h.contact_extent), (h.stick_halfwidth, h.stick_extent)):
        assert 2 * width - facet <= extent <= 2 * width + 2 * facet


def test_boundary_stress_along_arc_length_keeps_every_node():
    p = block_on_plane(np.radians(10), push=-0.01, F=0.3, levels=4)
    res = p.solve()
    s = res.arc_length()
    # the bottom of the tilted block: arc length is the distance from its left end
    left = res.mesh.points[0]  # the bottom-left corner, the end of the bottom with the smallest x
    np.testing.assert_allclose(s, np.linalg.norm(res.mesh.points[res.contact_nodes] - left, axis=1), atol=1e-12)
    ax = plots.plot_boundary_stress(res, along="arc")
    blue = [ln for ln in ax.get_lines() if ln.get_color() == "tab:blue"][0]
    assert len(blue.get_xdata()) == len(res.contact_nodes)  # no node cropped
    np.testing.assert_allclose(blue.get_xdata(), np.sort(s))
    assert "arc length" in ax.get_xlabel()
    ax = plots.plot_boundary_stress(res, along="y")
    assert ax.get_xlabel() == "y"
    with pytest.raises(ValueError, match="along must be"):
        plots.plot_boundary_stress(res, along="w")
    # Hertz along the arc: the order is the order in x, and every node is drawn
    hr = hertz.hertz_problem("triangle", 4, 0.4).solve()
    sh = hr.arc_length()
    x = hr.mesh.points[hr.contact_nodes, 0]
    assert np.all(np.diff(sh[np.argsort(x)]) > 0)


def test_a_flipped_obstacle_normal_is_refused():
    h = cm.MeshHierarchy.build(rectangle(2, 2), 2)
    body = Body(h, MAT, [Dirichlet([RECT_TOP], (0.0, -0.01))], contact_tags=[RECT_BOTTOM])
    with pytest.raises(ValueError, match="normal pointing into the body"):
        Problem(body, obstacle=cm.PlaneObstacle((0.0, -0.1), (0.0, 1.0)))  # normal into the body
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Problem(body, obstacle=cm.PlaneObstacle((0.0, -0.1), (0.0, -1.0)))
    # some nodes inside (a tilted plane cutting the corner): a defined initial penetration, said
    with pytest.warns(UserWarning, match=r"start inside the obstacle by up to"):
        p = Problem(body, obstacle=cm.PlaneObstacle((0.5, 0.0), (0.1, -1.0)))
    assert p.contact.gaps.min() < 0 < p.contact.gaps.max()


def test_per_node_data_by_node_ids():
    base = hertz.hertz_problem("triangle", 4, 0.4)
    ids = base.contact.nodes
    x = base.mesh.points
    # every node of the arc facets (the two Dirichlet corners too), in a shuffled order
    arc = np.unique(base.mesh.facets[base.mesh.facet_tags == cm.HERTZ_ARC])
    arc = np.random.default_rng(3).permutation(arc)
    F = 0.2 + 0.5 * np.abs(x[arc, 0])  # a coefficient that varies along the arc
    gaps, normals = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)).gaps_and_normals(x[arc])

    def build(obstacle, friction):
        return Problem(Body(base.hierarchy, base.material, [Dirichlet(cm.HERTZ_TOP, (0.0, -0.005))],
                            contact_tags=cm.HERTZ_ARC), obstacle=obstacle, friction=friction)

    by_id = build(cm.NodalObstacle(gaps, normals, nodes=arc), cm.Coulomb(F, nodes=arc)).solve()
    order = {int(k): i for i, k in enumerate(arc)}
    in_order = np.array([order[int(k)] for k in ids])
    by_order = build(cm.NodalObstacle(gaps[in_order], normals[in_order]), cm.Coulomb(F[in_order])).solve()
    plane = build(cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), cm.Coulomb(F[in_order])).solve()
    assert by_id.converged and by_order.converged
    np.testing.assert_array_equal(by_id.displacement, by_order.displacement)
    np.testing.assert_allclose(by_id.displacement, plane.displacement, atol=1e-14)
    np.testing.assert_array_equal(by_id.contact_nodes, ids)
    # a node the ids do not cover is named
    with pytest.raises(ValueError, match=f"friction coefficient gives no value for contact node {int(ids[0])}"):
        build(cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), cm.Coulomb(F[arc != ids[0]], nodes=arc[arc != ids[0]]))
    keep = arc != ids[0]
    with pytest.raises(ValueError, match=f"NodalObstacle gives no value for contact node {int(ids[0])}"):
        build(cm.NodalObstacle(gaps[keep], normals[keep], nodes=arc[keep]), cm.Coulomb(0.4))
    with pytest.raises(ValueError, match="repeats a node id"):
        build(cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), cm.Tresca(np.ones(2), nodes=[ids[0], ids[0]]))


def test_numpy_scalars_planar_round_off_and_unambiguous_tags(tmp_path):
    m = cm.Material(np.float64(2000.0), np.float32(0.28))
    assert isinstance(m.E, float) and m.mu == pytest.approx(2000.0 / (2 * 1.28), rel=1e-7)
    assert cm.Material(np.int64(5), np.array(0.25)).E == 5.0
    with pytest.raises(TypeError, match="E must be a number"):
        cm.Material(np.array([1.0]), 0.3)
    # a planar mesh whose z is round-off reads as 2D; a real third coordinate does not
    r = rectangle(2, 2)
    z = np.r_[0.0, 1e-17 * np.ones(r.num_points - 1)]
    meshio.write(tmp_path / "p.vtu", meshio.Mesh(np.c_[r.points, z], [("triangle", r.cells)]))
    assert cm.read_mesh(tmp_path / "p.vtu").dim == 2
    meshio.write(tmp_path / "q.vtu", meshio.Mesh(np.c_[r.points, 1e-3 * z / 1e-17], [("triangle", r.cells)]))
    with pytest.raises(ValueError, match="non-zero coordinates beyond dimension 2"):
        cm.read_mesh(tmp_path / "q.vtu")
    # one integer tag means that tag; anything else is named
    h = cm.MeshHierarchy.build(r, 2)
    one = Problem(Body(h, MAT, [Dirichlet(RECT_TOP, (0.0, -0.01))], contact_tags=RECT_BOTTOM),
                  obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    seq = Problem(Body(h, MAT, [Dirichlet([RECT_TOP], (0.0, -0.01))], contact_tags=[RECT_BOTTOM]),
                  obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    np.testing.assert_array_equal(one.contact.nodes, seq.contact.nodes)
    np.testing.assert_array_equal(one.fixed, seq.fixed)
    single = Problem(Body(h, MAT, Dirichlet(RECT_TOP, (0.0, -0.01))))  # one Dirichlet condition, not a list
    np.testing.assert_array_equal(single.fixed, seq.fixed)
    with pytest.raises(TypeError, match="Dirichlet tags must be an integer tag or a sequence"):
        Dirichlet("top", (0.0, 0.0))
    with pytest.raises(TypeError, match="contact_tags must hold integer tags, got 1.5"):
        Problem(Body(h, MAT, [Dirichlet(RECT_TOP, (0.0, -0.01))], contact_tags=[1.5]),
                obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    with pytest.raises(TypeError, match="contact_tags must be an integer tag"):
        Problem(Body(h, MAT, [Dirichlet(RECT_TOP, (0.0, -0.01))], contact_tags=1.0),
                obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    with pytest.raises(ValueError, match="Dirichlet values must be finite numbers"):
        Problem(Body(h, MAT, [Dirichlet(RECT_TOP, ("0", -0.01))]))


def test_box_pairs_and_components_match_brute_force():
    from contactmg.mesh.mesh import _box_pairs, connected_components

    rng = np.random.default_rng(5)
    lo = rng.uniform(0, 10, (300, 2))
    hi = lo + rng.uniform(1e-3, 1, (300, 1)) * 10.0 ** rng.uniform(-2, 0.5, (300, 1))  # sizes over 2.5 decades
    a, b = _box_pairs(lo, hi)
    i, j = np.triu_indices(300, 1)
    meet = np.all((lo[i] < hi[j]) & (lo[j] < hi[i]), axis=1)
    assert sorted(zip(a.tolist(), b.tolist())) == sorted(zip(i[meet].tolist(), j[meet].tolist()))
    # components against scipy's, on three blocks numbered at random, plus a node in no cell
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components as scipy_components

    blocks = [rectangle(3, 2, origin=(3.0 * k, 0.0)) for k in range(3)]
    offsets = np.cumsum([0] + [m.num_points for m in blocks])
    cells = np.vstack([m.cells + o for m, o in zip(blocks, offsets)])
    n = offsets[-1] + 1
    perm = rng.permutation(n)
    cells = perm[cells]
    count, label = connected_components(cells, n)
    assert count == 3 and label[perm[n - 1]] == -1
    g = sp.coo_matrix((np.ones(cells.size), (np.repeat(cells[:, 0], 3), cells.ravel())), shape=(n, n))
    _, ref = scipy_components(g, directed=False)
    used = label >= 0
    # the same partition: a label of ours maps to exactly one of scipy's and back
    pairs = set(zip(label[used].tolist(), ref[used].tolist()))
    assert len(pairs) == 3 and len({p[0] for p in pairs}) == 3 and len({p[1] for p in pairs}) == 3


def test_rigid_motion_per_piece_in_3d():
    cube = unit_cube("tetra")
    n = cube.num_points
    two = Mesh(np.vstack([cube.points, cube.points + [2.0, 0.0, 0.0]]), np.vstack([cube.cells, cube.cells + n]),
               "tetra", np.vstack([cube.facets, cube.facets + n]),
               np.r_[np.where(cube.points[cube.facets].mean(axis=1)[:, 2] < 1e-9, 1, 0),
                     np.where(cube.points[cube.facets].mean(axis=1)[:, 2] < 1e-9, 2, 0)])
    h = cm.MeshHierarchy.build(two, 1)
    with pytest.raises(ValueError, match="piece 2 of the 2 disconnected pieces"):
        Problem(Body(h, MAT, [Dirichlet(1, (0.0, 0.0, 0.0))]))
    # rollers on the bottom (u_z = 0) leave the in-plane motion of each cube free
    with pytest.raises(ValueError, match="piece 1 of the 2"):
        Problem(Body(h, MAT, [Dirichlet(1, (None, None, 0.0)), Dirichlet(2, (0.0, 0.0, 0.0))]))
    p = Problem(Body(h, MAT, [Dirichlet(1, (0.0, 0.0, 0.0)), Dirichlet(2, (0.0, 0.0, 0.0))], body_force=(0, 0, -1.0)))
    assert p.mesh.dim == 3 and p.fixed.sum() == 2 * 4 * 3
