"""Loads, elastic supports and materials per region against exact solutions of linear elasticity."""
import meshio
import numpy as np
import pytest

import contactmg as cm
from contactmg.model.loads import PointLoad

BOTTOM, RIGHT, TOP, LEFT = cm.RECT_BOTTOM, cm.RECT_RIGHT, cm.RECT_TOP, cm.RECT_LEFT


def _solve(body, **kw):
    return cm.Problem(body).solve("linear", tol=1e-13, **kw)


def _rollers():
    """Left edge held in x, bottom edge in y: symmetry planes, no constraint on a uniform stress."""
    return [cm.Dirichlet(LEFT, (0.0, None)), cm.Dirichlet(BOTTOM, (None, 0.0))]


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_pressure_on_top_gives_the_uniform_uniaxial_stress(cell):
    p, mat = 3.0, cm.Material(200.0, 0.3)
    h = cm.MeshHierarchy.build(cm.rectangle(3, 2, 2.0, 1.0, cell=cell, distort=0.2), 3)
    res = _solve(cm.Body(h, mat, _rollers(), pressure={TOP: p}))
    s = res.stress()
    assert np.allclose(s[:, 1, 1], -p, atol=1e-9 * p)
    assert np.allclose(s[:, 0, 0], 0.0, atol=1e-9 * p)
    assert np.allclose(s[:, 2, 2], -mat.nu * p, atol=1e-9 * p)  # plane strain
    # the bottom's reaction carries the pressure times the top's length
    r = res.reactions()
    assert r[BOTTOM][1] == pytest.approx(2.0 * p, rel=1e-10)


def test_pressure_follows_each_facets_normal_on_a_curved_boundary():
    """A uniform pressure on a closed curve integrates to zero net force; on a half circle to 2 p R."""
    h = cm.MeshHierarchy.build(cm.hertz_half_disk(), 4, projector=cm.hertz_projector())
    mesh = h.finest
    from contactmg.model.loads import assemble_load
    f = assemble_load(mesh, pressure={cm.HERTZ_ARC: 1.5})
    # the arc of the unit half disk: -p * integral of n over the arc = (0, 2 p R) pointing into the body (up)
    R = np.abs(mesh.points[mesh.boundary_nodes([cm.HERTZ_ARC])]).max()
    assert f.sum(axis=0)[0] == pytest.approx(0.0, abs=1e-12)
    assert f.sum(axis=0)[1] == pytest.approx(2 * 1.5 * R, rel=1e-12)


def _two_region_bar(cell="quad"):
    m = cm.rectangle(4, 2, 2.0, 1.0, cell=cell)
    centroid = m.points[m.cells].mean(axis=1)
    tags = np.where(centroid[:, 0] < 1.0, 1, 2)
    return cm.Mesh(m.points, m.cells, m.cell_type, m.facets, m.facet_tags, tags)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_two_material_bar_has_the_exact_piecewise_strain(cell):
    """A bar of two materials in series, pulled by a traction t, held laterally on both long sides:
    sigma_xx = t everywhere and eps_xx = t / (lambda + 2 mu) of each region (constrained modulus)."""
    t, m1, m2 = 2.0, cm.Material(100.0, 0.25), cm.Material(400.0, 0.35)
    h = cm.MeshHierarchy.build(_two_region_bar(cell), 3)
    assert set(np.unique(h.finest.cell_tags)) == {1, 2}
    held = _rollers() + [cm.Dirichlet(TOP, (None, 0.0))]
    res = _solve(cm.Body(h, {1: m1, 2: m2}, held, traction={RIGHT: (t, 0.0)}))
    eps = res.strain()
    tags = h.finest.cell_tags
    for tag, mat in ((1, m1), (2, m2)):
        assert np.allclose(eps[tags == tag, 0, 0], t / (mat.lam + 2 * mat.mu), rtol=1e-9)
    assert np.allclose(res.stress()[:, 0, 0], t, rtol=1e-9)
    right = h.finest.points[:, 0] == 2.0
    expected = t / (m1.lam + 2 * m1.mu) + t / (m2.lam + 2 * m2.mu)
    assert np.allclose(res.displacement[right, 0], expected, rtol=1e-9)


def test_refinement_keeps_each_cell_in_its_region():
    h = cm.MeshHierarchy.build(_two_region_bar("triangle"), 3)
    m = h.finest
    centroid = m.points[m.cells].mean(axis=1)
    assert np.array_equal(m.cell_tags, np.where(centroid[:, 0] < 1.0, 1, 2))


def test_regions_survive_a_gmsh_file(tmp_path):
    mesh = _two_region_bar("triangle")
    path = tmp_path / "bar.msh"
    cm.write_mesh(path, mesh)
    back = cm.read_mesh(path)
    assert np.array_equal(back.cell_tags, mesh.cell_tags)


def test_a_region_without_material_is_named():
    h = cm.MeshHierarchy.build(_two_region_bar(), 1)
    with pytest.raises(ValueError, match=r"region\(s\) \[2\] have no material"):
        cm.Body(h, {1: cm.Material(1.0, 0.3)})
    with pytest.raises(ValueError, match=r"region tag\(s\) \[7\]"):
        cm.Body(h, {1: cm.Material(1.0, 0.3), 2: cm.Material(1.0, 0.3), 7: cm.Material(1.0, 0.3)})


def test_springs_hold_the_body_and_give_the_exact_settlement():
    """A block on vertical springs (stiffness k per length) under pressure p: the bottom settles by
    p / k and the block shortens by its plane-strain strain."""
    p, k, mat = 2.0, 50.0, cm.Material(100.0, 0.3)
    h = cm.MeshHierarchy.build(cm.rectangle(2, 2, 1.0, 1.0, cell="quad"), 3)
    body = cm.Body(h, mat, [cm.Dirichlet(LEFT, (0.0, None))], pressure={TOP: p}, springs={BOTTOM: (0.0, k)})
    res = _solve(body)
    y = h.finest.points[:, 1]
    settle = -p / k
    shorten = -p * (1 - mat.nu ** 2) / mat.E
    assert np.allclose(res.displacement[y == 0.0, 1], settle, rtol=1e-9)
    assert np.allclose(res.displacement[y == 1.0, 1], settle + shorten, rtol=1e-9)
    # the springs carry the pressure: their force balances the load
    assert res.spring_forces()[BOTTOM] == pytest.approx([0.0, p * 1.0], abs=1e-9 * p)


def test_springs_are_counted_as_support():
    h = cm.MeshHierarchy.build(cm.rectangle(2, 2, cell="quad"), 1)
    with pytest.raises(ValueError, match="Dirichlet conditions and springs leave rigid-body motion"):
        cm.Problem(cm.Body(h, cm.Material(1.0, 0.3), springs={BOTTOM: (0.0, 1.0)}))
    with pytest.raises(ValueError, match="must not be negative"):
        cm.Problem(cm.Body(h, cm.Material(1.0, 0.3), springs={BOTTOM: -1.0}))


def test_gravity_load_is_density_times_volume_per_region():
    g = (0.0, -9.81)
    h = cm.MeshHierarchy.build(_two_region_bar("triangle"), 2)
    mats = {1: cm.Material(1.0, 0.3, density=2.0), 2: cm.Material(1.0, 0.3, density=5.0)}
    p = cm.Problem(cm.Body(h, mats, [cm.Dirichlet(BOTTOM, (0.0, 0.0))], gravity=g))
    assert p.load.sum(axis=0) == pytest.approx([0.0, -9.81 * (2.0 * 1.0 + 5.0 * 1.0)], rel=1e-12)
    with pytest.raises(ValueError, match="gravity needs a density"):
        cm.Problem(cm.Body(h, {1: cm.Material(1.0, 0.3), 2: cm.Material(1.0, 0.3)}, [cm.Dirichlet(BOTTOM, (0.0, 0.0))],
                           gravity=g))


def test_point_load_acts_at_its_node_and_is_balanced():
    h = cm.MeshHierarchy.build(cm.rectangle(2, 2, cell="quad"), 3)
    f = (0.3, -1.0)
    res = _solve(cm.Body(h, cm.Material(10.0, 0.3), [cm.Dirichlet(BOTTOM, (0.0, 0.0))],
                         point_loads=[PointLoad((0.5, 1.0), f)]))
    node = int(np.argmin(np.linalg.norm(h.finest.points - (0.5, 1.0), axis=1)))
    assert np.allclose(res.problem.load[node], f) and np.abs(res.problem.load).sum() == pytest.approx(1.3)
    assert res.reactions()[BOTTOM] == pytest.approx(-np.asarray(f), rel=1e-10)
    with pytest.raises(ValueError, match="no mesh node at"):
        cm.Problem(cm.Body(h, cm.Material(10.0, 0.3), [cm.Dirichlet(BOTTOM, (0.0, 0.0))],
                           point_loads=[PointLoad((0.123, 1.0), f)]))


def test_point_loads_none_means_no_point_loads():
    # None is accepted as for every other optional load, and gives the same problem as no point loads
    h = cm.MeshHierarchy.build(cm.rectangle(2, 2, cell="quad"), 2)
    bc = [cm.Dirichlet(BOTTOM, (0.0, 0.0))]
    body = cm.Body(h, cm.Material(10.0, 0.3), bc, pressure={TOP: 1.0}, point_loads=None)
    assert body.point_loads == []
    ref = cm.Problem(cm.Body(h, cm.Material(10.0, 0.3), bc, pressure={TOP: 1.0}))
    assert np.array_equal(cm.Problem(body).load, ref.load)
    with pytest.raises(TypeError, match="point_loads must be"):
        cm.Body(h, cm.Material(10.0, 0.3), bc, point_loads=3.0)
