"""Engineering output of a result: support reactions and contact forces that balance the load, the
VTU fields read back with meshio, the summary table."""
import meshio
import numpy as np
import pytest

from contactmg.examples.cylinders import cylinders_problem
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.mesh.generators import HERTZ_TOP
from contactmg.mesh.generators_3d import BALL_TOP
from contactmg.results.result import STICK, SLIP


@pytest.fixture(scope="module", params=["hertz", "sphere"])
def solved(request):
    p = hertz_problem("triangle", 5, 0.4) if request.param == "hertz" else sphere_problem("tetra", 2, 0.4)
    r = p.solve(tol=1e-13)
    assert r.converged
    return p, r


@pytest.fixture(scope="module")
def cylinders():
    p = cylinders_problem(5, friction=0.4)
    r = p.solve(tol=1e-13)
    assert r.converged
    return p, r


def test_reactions_contact_force_and_load_balance(solved):
    p, r = solved
    R, C = r.reactions(), r.contact_forces()
    top = HERTZ_TOP if p.mesh.dim == 2 else BALL_TOP
    assert set(R) == {top} and set(C) == {"obstacle"}
    load = p.load.sum(axis=0)
    total = R[top] + C["obstacle"] + load
    scale = np.abs(C["obstacle"]).max()
    assert scale > 0 and np.abs(total).max() <= 1e-10 * scale
    # the contact force is the one the result reports per node, turned to global axes
    np.testing.assert_allclose(C["obstacle"], r.reaction, rtol=0, atol=1e-12 * scale)
    # the obstacle pushes the body up, the top support holds it down
    assert C["obstacle"][-1] > 0 > R[top][-1]


def test_two_bodies_each_in_equilibrium(cylinders):
    p, r = cylinders
    R, C = r.reactions(), r.contact_forces()
    assert set(R) == {(0, HERTZ_TOP), (1, HERTZ_TOP)} and set(C) == {"pair 0"}
    f = r.canonical_load()
    nonmortar, mortar = p.pairs[0].nonmortar, p.pairs[0].mortar
    scale = np.abs(C["pair 0"]).max()
    assert scale > 0
    for body, sign in ((nonmortar, 1.0), (mortar, -1.0)):  # the mortar body feels the opposite force
        total = R[(body, HERTZ_TOP)] + sign * C["pair 0"] + f[p.body_id == body].sum(axis=0)
        assert np.abs(total).max() <= 1e-10 * scale, (body, total)


def test_vtu_holds_the_fields(cylinders, tmp_path):
    p, r = cylinders
    path = tmp_path / "two.vtu"
    p.write_vtu(path, r)
    m = meshio.read(path)
    c = p.contact
    pressure = m.point_data["contact_pressure"]
    np.testing.assert_allclose(pressure[c.nodes], -r.contact_force[:, 0] / c.measure, rtol=1e-12)
    assert np.all(pressure[np.setdiff1d(np.arange(p.mesh.num_points), c.nodes)] == 0)
    assert pressure[c.nodes].max() > 0  # positive in compression
    # the tangential traction in global axes: orthogonal to the normal, as long as in the nodal frame
    tt = m.point_data["tangential_traction"][:, :2]
    np.testing.assert_allclose(np.einsum("ci,ci->c", tt[c.nodes], c.normals), 0.0,
                               atol=1e-12 * np.abs(r.contact_force).max())
    np.testing.assert_allclose(np.linalg.norm(tt[c.nodes], axis=1), np.abs(r.contact_force[:, 1]) / c.measure,
                               rtol=1e-12)
    np.testing.assert_array_equal(m.point_data["node_state"], r.node_state)
    np.testing.assert_array_equal(m.point_data["body_id"], p.body_id)
    # slip: the relative tangential displacement at the sliding nodes, none at sticking ones
    w = p.relative_displacement(r.displacement)[c.nodes]
    slip = m.point_data["slip"][c.nodes, :2]
    state = r.contact_state
    assert np.any(state == SLIP)
    tangent = np.c_[-c.normals[:, 1], c.normals[:, 0]]
    np.testing.assert_allclose(np.einsum("ci,ci->c", slip, tangent)[state == SLIP],
                               np.einsum("ci,ci->c", w, tangent)[state == SLIP], rtol=1e-10)
    assert np.all(np.abs(slip[state == STICK]) <= 1e-12 * np.abs(w).max())
    # cell data of the volume cells: stress and strain tensors, von Mises
    k = [b.type for b in m.cells].index(p.mesh.cell_type)
    stress = m.cell_data["stress"][k].reshape(-1, 3, 3)
    np.testing.assert_allclose(stress, r.stress(), rtol=0, atol=1e-12 * np.abs(stress).max())
    np.testing.assert_allclose(m.cell_data["von_mises"][k], r.von_mises(), rtol=1e-12)
    np.testing.assert_allclose(m.cell_data["strain"][k].reshape(-1, 3, 3), r.strain(), rtol=0,
                               atol=1e-12 * np.abs(r.strain()).max())
    np.testing.assert_allclose(m.point_data["von_mises"], r.von_mises("nodes"), rtol=1e-12)
    # the nodal-frame fields stay
    np.testing.assert_allclose(m.point_data["normal_stress"][c.nodes], r.normal_stress, rtol=1e-12)


def test_write_vtu_of_a_3d_result(solved, tmp_path):
    p, r = solved
    r.write_vtu(tmp_path / "r.vtu")
    m = meshio.read(tmp_path / "r.vtu")
    d = p.mesh.dim
    np.testing.assert_allclose(m.point_data["displacement"][:, :d], r.displacement, rtol=0, atol=0)
    tt = m.point_data["tangential_traction"][p.contact.nodes, :d]
    np.testing.assert_allclose(np.linalg.norm(tt, axis=1), np.linalg.norm(r.tangential_stress.reshape(len(tt), -1), axis=1),
                               rtol=1e-12)
    assert m.cell_data["stress"][0].shape == (p.mesh.num_cells, 9)


def test_summary_holds_the_numbers(solved):
    p, r = solved
    text = r.summary()
    check = r.check()
    for want in (r.method, r.law, str(r.cycles), str(r.displacement.size), f"{r.contact_extent:.6g}",
                 f"{float(r.von_mises().max()):.6g}", f"{check['max']:.3g}"):
        assert want in text, want
    for key, value in r.counts().items():
        assert f"{key.replace('_', ' ')}" in text and str(value) in text
    for force in (r.contact_forces()["obstacle"], *r.reactions().values()):
        assert "(" + ", ".join(f"{x:.6g}" for x in force) + ")" in text


def test_output_needs_the_problem(solved):
    import dataclasses

    p, r = solved
    orphan = dataclasses.replace(r)
    orphan.problem = None
    for call in (orphan.reactions, orphan.contact_forces, orphan.stress):
        with pytest.raises(ValueError, match="needs the problem"):
            call()
    assert orphan.cell_data() == {} and "von_mises" not in orphan.point_data()
    assert "contact force" not in orphan.summary() and str(r.cycles) in orphan.summary()
