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
    with pytest.raises(ValueError, match=r"nothing holds the body in a translation along \[1.0, 0.0\]: the load drives it "
                                         r"that way beyond what friction holds: it needs a friction coefficient of about "
                                         r"0.35\d? where the contacts have 0.3"):
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


def _stack(levels, count, cell="quad"):
    """`count` blocks stacked on a rigid floor, each narrower than the one below, none supported:
    the top one pressed by a pressure, each held by the one below and the lowest by the floor."""
    bodies, contacts = [], []
    for k in range(count):
        width = 2.0 - 0.5 * k
        mesh = cm.rectangle(4 - k, 2, width, 1.0, cell=cell, origin=(0.25 * k, float(k)))
        bodies.append(cm.Body(cm.MeshHierarchy.build(mesh, levels), MAT, [],
                              pressure={T: 1.0} if k == count - 1 else None))
    for k in range(1, count):
        contacts.append(cm.ContactPair(k, k - 1, [B], [T], search=0.1))
    contacts.append(cm.ObstacleContact(0, B, FLOOR))
    return bodies, contacts


@pytest.mark.parametrize("count", [2, 3])
def test_a_stack_of_unsupported_blocks(count):
    """Several bodies with several pairs and no supports at all: every contact carries the top's
    load to round-off."""
    bodies, contacts = _stack(4, count)
    p = cm.Problem(bodies, contacts=contacts, friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.converged, res.status
    assert contact_conditions(p, res)["max"] < 1e-6
    load = 1.0 * (2.0 - 0.5 * (count - 1))   # the pressure on the top block's width
    for name, force in res.contact_forces().items():
        assert force[1] == pytest.approx(load, rel=1e-10), name
        assert abs(force[0]) <= 1e-10 * load


def test_a_body_of_several_pulled_off_is_refused_by_number():
    bodies, contacts = _stack(2, 2)
    bodies[1].pressure = {T: -1.0}
    with pytest.raises(ValueError, match=r"nothing holds body 1 in a translation along \[0.0, 1.0\]"):
        cm.Problem(bodies, contacts=contacts, friction=cm.Coulomb(0.3))


@pytest.mark.parametrize("F,held", [(0.26, False), (0.27, True)])
def test_a_box_on_a_15_degree_slope_slides_below_tan_15_degrees(F, held):
    """A box under gravity on a plane tilted by 15 degrees, no supports: it stays where F >= tan 15
    = 0.268 (the friction cone, not a pyramid around it, decides), and below that the refusal names
    the slide down the slope and the friction it needs."""
    from contactmg.mesh.generators_3d import box

    a = np.deg2rad(15.0)
    normal = (np.sin(a), 0.0, -np.cos(a))
    body = cm.Body(cm.MeshHierarchy.build(box(2, 2, 1, 1.0, 1.0, 0.5), 2), cm.Material(1000.0, 0.3, density=1.0), [],
                   contact_tags=[5], gravity=(0.0, 0.0, -9.81))

    def make():
        return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0, 0.0), normal), friction=cm.Coulomb(F))
    if held:
        res = make().solve()
        assert res.converged
        force = res.contact_forces()["obstacle"]
        weight = res.canonical_load().sum(axis=0)
        assert np.allclose(force + weight, 0.0, atol=1e-8 * np.abs(weight).max())
    else:
        with pytest.raises(ValueError, match=r"translation along \[-0.966, 0.0, -0.259\].*needs a friction coefficient "
                                             r"of about 0.26[89] where the contacts have 0.26"):
            make()


def _free_block(levels, origin=(0.0, 0.0), **loads):
    from contactmg.mesh.generators import RECT_BOTTOM, rectangle

    h = cm.MeshHierarchy.build(rectangle(4, 2, 2.0, 1.0, origin=origin), levels)
    body = cm.Body(h, MAT, [], contact_tags=[RECT_BOTTOM], **loads)
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))


@pytest.mark.parametrize("levels", [3, 4, 5])
def test_a_block_pushed_sideways_is_held_by_friction_alone(levels):
    """No supports, traction (0.2, -1) on the top, Coulomb 0.3: only friction holds the block
    sideways, and before it touches nothing does. The default solve converges in at most 30 cycles
    at every level, the floor's force balancing the load."""
    from contactmg.mesh.generators import RECT_TOP

    p = _free_block(levels, traction={RECT_TOP: (0.2, -1.0)})
    r = p.solve()
    assert r.converged and r.cycles <= 30
    force = r.contact_forces()["obstacle"]
    assert np.allclose(force + r.canonical_load().sum(axis=0), 0.0, atol=1e-8 * 2.0)


@pytest.mark.parametrize("levels", [3, 5])
def test_a_block_starting_above_the_floor_falls_onto_it(levels):
    """0.5 above the floor (half its height), pressed down by a pressure: the default solve (its
    nested start) brings it onto the floor in at most 30 cycles of the finest level, and the floor
    then carries the whole load."""
    from contactmg.mesh.generators import RECT_TOP

    p = _free_block(levels, origin=(0.0, 0.5), pressure={RECT_TOP: 1.0})
    r = p.solve()
    assert r.converged and r.cycles <= 30
    assert r.extra["nested_start"]["kept"]
    force = r.contact_forces()["obstacle"]
    assert force[1] == pytest.approx(2.0, rel=1e-8)
    assert np.all(r.displacement[p.contact.nodes, 1] <= -0.5 + 1e-12)


def _plate_on_cylinder(levels, friction):
    """A 2 x 0.2 half plate (E 1000: its free end would deflect by about 3) pressed by a pressure of
    1 onto a rigid cylinder of radius 1 under its symmetry plane x = 0, held by the cylinder and
    the symmetry condition alone (nothing holds it vertically but the contact)."""
    from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_TOP, rectangle

    h = cm.MeshHierarchy.build(rectangle(8, 2, 2.0, 0.2), levels)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [cm.Dirichlet(RECT_LEFT, (0.0, None))], contact_tags=[RECT_BOTTOM],
                   pressure={RECT_TOP: 1.0})
    return cm.Problem(body, obstacle=cm.SphereObstacle((0.0, -1.0), 1.0), friction=friction)


@pytest.mark.parametrize("friction", [None, cm.Coulomb(0.3)], ids=["frictionless", "coulomb"])
def test_a_plate_held_by_a_cylinder_converges_in_cycles_that_do_not_grow(friction):
    """Levels 3-5 in at most 30 cycles each, not growing from level 4 to 5 (18/25/24 frictionless,
    18/17/18 Coulomb when written); the reactions, the cylinder's force and
    the load balance to 1e-8 of the load (from u = 0 the monotone corrections crept by 1e-3 a cycle
    and 1000 cycles did not reach it)."""
    counts = []
    for levels in (3, 4, 5):
        p = _plate_on_cylinder(levels, friction)
        r = p.solve()
        assert r.converged, r.status
        counts.append(r.cycles)
        total = r.contact_forces()["obstacle"] + sum(r.reactions().values()) + r.canonical_load().sum(axis=0)
        assert np.abs(total).max() <= 1e-8 * np.abs(r.canonical_load().sum(axis=0)).max()
        assert contact_conditions(p, r)["max"] < 1e-6
    assert max(counts) <= 30 and counts[2] <= counts[1] + 2, counts


def test_the_nested_start_reaches_the_answer_of_the_zero_start():
    """The start changes the path, not the answer: the sideways-pushed block (unique answer) from
    the nested start and from u = 0 agree to the stop's accuracy, and the nested start's energy was
    below that of u = 0 (it is kept only then)."""
    from contactmg.mesh.generators import RECT_TOP

    p = _free_block(4, traction={RECT_TOP: (0.2, -1.0)})
    nested = cm.Solver(p, {"rtol": 1e-12}).solve()
    zero = cm.Solver(p, {"rtol": 1e-12, "start": "zero"}).solve()
    assert nested.converged and zero.converged
    assert nested.options["start"] == "nested" and zero.options["start"] == "zero"
    assert nested.extra["nested_start"]["kept"] and "nested_start" not in zero.extra
    assert np.abs(nested.displacement - zero.displacement).max() <= 1e-8 * np.abs(zero.displacement).max()
    assert nested.extra["nested_start"]["levels"] == [0, 1, 2]


def test_a_hierarchy_without_injection_starts_from_zero():
    """Aggregated coarse spaces have no coarse node that is a fine node: the nested start has no
    coarse problems to solve, says so by an empty record, and the solve starts from u = 0."""
    from contactmg.mesh.generators import RECT_BOTTOM, RECT_TOP, rectangle

    fine = cm.MeshHierarchy.build(rectangle(4, 2, 2.0, 1.0), 4).finest
    h = cm.MeshHierarchy.aggregated(fine, coarsest=30)
    p = cm.Problem(cm.Body(h, MAT, [], contact_tags=[RECT_BOTTOM], pressure={RECT_TOP: 1.0}), obstacle=FLOOR,
                   friction=cm.Coulomb(0.3))
    r = p.solve()
    assert r.converged
    assert r.extra["nested_start"]["levels"] == []
    assert r.contact_forces()["obstacle"][1] == pytest.approx(2.0, rel=1e-8)


@pytest.mark.parametrize("n,start", [(4, None), (8, "zero"), (8, None), (16, "zero"), (16, None), (32, "zero"),
                                     (32, None)])
def test_a_coarsest_level_that_nothing_holds_yet_moves_the_body_onto_the_floor(n, start):
    """A block 0.5 above the floor given as a lone mesh (its coarse levels made from it), 90 to 4,290
    dofs, from u = 0 and from the default (nested) start. The coarsest level's matrix is (nearly)
    semi-definite: its correction moves the block as a whole along the ray of its solution up to the
    first bound, and where that level's factorization is shifted it is solved exactly (mg/box_qp.hpp).
    Every size converges in a multigrid's cycles with the floor carrying the load and the block on
    it. Without the ray the coarse correction fell back to x = 0 and 200 cycles did not reach the
    floor (floor force 0.38 and 0.015 of 2); without the exact solve 1,122 dofs took 63 cycles. The
    nested start's lowest stage, a level made from the mesh, is coarsened through the Delaunay
    simplices of its nodes: every stage converges, at a few finest cycles of work (27-60 when that
    stage was only smoothed)."""
    from contactmg.mesh.generators import RECT_BOTTOM, RECT_TOP, rectangle

    h = cm.MeshHierarchy.build(rectangle(2 * n, n, 2.0, 1.0, origin=(0.0, 0.5)), 1)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM], pressure={RECT_TOP: 1.0})
    p = cm.Problem(body, obstacle=FLOOR, friction=cm.Coulomb(0.3))
    r = cm.Solver(p, {"start": start}).solve()
    assert r.converged and r.cycles <= 30, (r.cycles, r.status)
    assert r.contact_forces()["obstacle"][1] == pytest.approx(2.0, rel=1e-8)
    assert r.displacement[:, 1].max() <= -0.5 + 1e-12  # it fell the whole gap
    if start is None and n >= 8:  # the nested start: every stage converged, the lowest on coarse levels of
        # its own (a lowest level of 6 nodes, n = 4, has none below it and is still only smoothed)
        record = r.extra["nested_start"]
        assert record["kept"] and all(record["converged"]) and record["work"] <= 10, record


def test_the_nested_start_solves_its_lowest_stage_with_coarse_levels_of_its_own():
    """A clamped 4 x 0.2 plate pressed across a gap of 0.005 onto a plane, its coarse mesh of 405
    nodes refined once: the nested start's lowest stage (the coarse mesh alone) gets coarse levels
    made from that mesh, as a lone mesh does, so it converges in a multigrid's cycles instead of
    being smoothed for 200 (the largest part of the start's work before); the start costs a few
    finest cycles, and the finest level converges in a third of the cycles of u = 0 (9 and 37 when
    written), to the same answer."""
    from contactmg.mesh.generators import RECT_BOTTOM, RECT_LEFT, RECT_RIGHT, RECT_TOP, rectangle

    h = cm.MeshHierarchy.build(rectangle(80, 4, 4.0, 0.2), 2)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [cm.Dirichlet(RECT_LEFT, (0.0, 0.0)), cm.Dirichlet(RECT_RIGHT, (0.0, 0.0))],
                   contact_tags=[RECT_BOTTOM], pressure={RECT_TOP: 1.0})
    p = cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, -0.005), (0.0, -1.0)), friction=cm.Coulomb(0.3))
    nested = cm.Solver(p, {"start": "nested"}).solve()
    zero = cm.Solver(p, {"start": "zero"}).solve()
    record = nested.extra["nested_start"]
    assert record["levels"] == [0] and record["converged"] == [True] and record["cycles"][0] <= 30, record
    assert record["kept"] and record["work"] <= 10
    assert nested.converged and zero.converged and nested.cycles <= 15
    assert np.abs(nested.displacement - zero.displacement).max() <= 1e-7 * np.abs(zero.displacement).max()
    assert contact_conditions(p, nested)["max"] < 1e-6
