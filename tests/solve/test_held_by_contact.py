"""Bodies held only by contact (semi-coercive problems): solved with no artificial spring, the
reactions balancing the load to round-off; a body that nothing holds is refused, naming the motion."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.results.checks import contact_conditions

B, R, T, L = cm.RECT_BOTTOM, cm.RECT_RIGHT, cm.RECT_TOP, cm.RECT_LEFT
MAT = cm.Material(100.0, 0.3)
FLOOR = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0))


def _block(levels=5, cell="triangle"):
    return cm.MeshHierarchy.build(cm.rectangle(4, 2, 2.0, 1.0, cell=cell), levels)


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_a_block_pressed_onto_the_floor_with_no_support(cell):
    """Nothing but the floor holds the block (no Dirichlet data at all): the floor's force equals
    minus the load to round-off, and the cycles stay within 1.5x of the same block held at its top
    edge at the displacement the free one found."""
    h = _block(cell=cell)
    p = cm.Problem(cm.Body(h, MAT, [], contact_tags=B, pressure={T: 1.0, L: 0.2}), obstacle=FLOOR,
                   friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.converged, res.status
    assert contact_conditions(p, res)["max"] < 1e-6
    force = res.contact_forces()["obstacle"]
    total = p.load.sum(axis=0)
    assert np.abs(force + total).max() <= 1e-10 * np.abs(total).max()
    top = h.finest.points[:, 1] == 1.0
    held = cm.Problem(cm.Body(h, MAT, [cm.Dirichlet(T, lambda x: res.displacement[top])], contact_tags=B),
                      obstacle=FLOOR, friction=cm.Coulomb(0.3))
    ref = held.solve()
    assert ref.converged
    assert res.cycles <= 1.5 * ref.cycles, (res.cycles, ref.cycles)


def test_a_block_falling_onto_the_floor_from_a_gap():
    h = _block(4)
    p = cm.Problem(cm.Body(h, MAT, [], contact_tags=B, pressure={T: 1.0}),
                   obstacle=cm.PlaneObstacle((0.0, -0.01), (0.0, -1.0)), friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.converged and contact_conditions(p, res)["max"] < 1e-6
    assert res.contact_forces()["obstacle"][1] == pytest.approx(2.0, rel=1e-10)
    assert res.displacement[:, 1].max() <= -0.01 + 1e-12   # it fell the whole gap


@pytest.mark.parametrize("cell", ["tetra", "hexahedron"])
def test_a_3d_box_on_the_floor_with_no_support(cell):
    h = cm.MeshHierarchy.build(cm.box(2, 2, 1, cell=cell), 3)
    floor = cm.PlaneObstacle((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    p = cm.Problem(cm.Body(h, MAT, [], contact_tags=5, pressure={6: 1.0, 1: 0.1}), obstacle=floor,
                   friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.converged, res.status
    assert contact_conditions(p, res)["max"] < 1e-6
    total = p.load.sum(axis=0)
    assert np.abs(res.contact_forces()["obstacle"] + total).max() <= 1e-10 * np.abs(total).max()


def test_coulomb_sliding_carries_f_times_the_normal_force():
    """A block pressed by a pressure (held vertically by the floor alone) and pushed sideways by
    its top edge: every bottom node slides, so the floor's tangential force is F times its normal
    force."""
    F, p_top = 0.3, 1.0
    h = _block(4)
    p = cm.Problem(cm.Body(h, MAT, [cm.Dirichlet(T, (0.05, None))], contact_tags=B, pressure={T: p_top}),
                   obstacle=FLOOR, friction=cm.Coulomb(F))
    res = p.solve()
    assert res.converged and contact_conditions(p, res)["max"] < 1e-6
    fx, fy = res.contact_forces()["obstacle"]
    assert fy == pytest.approx(2.0 * p_top, rel=1e-10)
    assert fx == pytest.approx(-F * fy, rel=1e-10)


def test_a_load_pulling_the_body_off_is_refused_naming_the_motion():
    with pytest.raises(ValueError, match=r"nothing holds the body in a translation along \[0.0, 1.0\]"):
        cm.Problem(cm.Body(_block(2), MAT, [], contact_tags=B, pressure={T: -1.0}), obstacle=FLOOR,
                   friction=cm.Coulomb(0.3))


def test_a_load_beyond_friction_is_refused():
    """Pushed sideways by 0.7 against a friction of at most 0.3 x 2: no equilibrium."""
    with pytest.raises(ValueError, match=r"nothing holds the body in a translation along \[0.9.*beyond what friction holds"):
        cm.Problem(cm.Body(_block(2), MAT, [], contact_tags=B, pressure={T: 1.0, L: 0.7}), obstacle=FLOOR,
                   friction=cm.Coulomb(0.3))
    # within the friction it stands
    cm.Problem(cm.Body(_block(2), MAT, [], contact_tags=B, pressure={T: 1.0, L: 0.5}), obstacle=FLOOR,
               friction=cm.Coulomb(0.3))


def test_frictionless_contact_cannot_hold_a_sliding_motion():
    with pytest.raises(ValueError, match=r"translation along \[1.0, 0.0\].*frictionless contact exerts no force"):
        cm.Problem(cm.Body(_block(2), MAT, [], contact_tags=B, pressure={T: 1.0}), obstacle=FLOOR)
    # held sideways by a roller on its left edge it solves, the floor carrying the pressure
    p = cm.Problem(cm.Body(_block(4), MAT, [cm.Dirichlet(L, (0.0, None))], contact_tags=B, pressure={T: 1.0}),
                   obstacle=FLOOR)
    res = p.solve()
    assert res.converged
    assert res.contact_forces()["obstacle"][1] == pytest.approx(2.0, rel=1e-10)
    assert np.allclose(res.stress()[:, 1, 1], -1.0, rtol=1e-8)   # the uniform stress of a free block


def test_a_free_piece_that_touches_nothing_is_refused():
    """Two disconnected blocks, the lower on the floor, the upper in the air: the upper one has
    nothing to hold it."""
    m1, m2 = cm.rectangle(2, 1, cell="quad"), cm.rectangle(2, 1, cell="quad", origin=(0.0, 2.0))
    pts = np.vstack([m1.points, m2.points])
    cells = np.vstack([m1.cells, m2.cells + len(m1.points)])
    mesh = cm.Mesh.from_cells(pts, cells, "quad", tagger=lambda mid: np.where(mid[:, 1] == 0.0, B, T))
    h = cm.MeshHierarchy.build(mesh, 2)
    with pytest.raises(ValueError, match="piece 2 of the 2 .*no contact boundary touches it"):
        cm.Problem(cm.Body(h, MAT, [], contact_tags=B, pressure={T: 1.0}), obstacle=FLOOR, friction=cm.Coulomb(0.3))
    with pytest.raises(ValueError, match=r"leave rigid-body motion free.*\(or let an obstacle hold it\)"):
        cm.Problem(cm.Body(_block(2), MAT, [cm.Dirichlet(L, (0.0, None))]))
