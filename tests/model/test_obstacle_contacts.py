"""Several rigid obstacles per body, obstacles beside body pairs, and obstacles given the wrong way
round."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.results.checks import contact_conditions

BOTTOM, RIGHT, TOP, LEFT = cm.RECT_BOTTOM, cm.RECT_RIGHT, cm.RECT_TOP, cm.RECT_LEFT
MAT = cm.Material(100.0, 0.3)


def _block(levels=4, origin=(0.0, 0.0)):
    return cm.MeshHierarchy.build(cm.rectangle(2, 2, cell="quad", origin=origin), levels)


def test_a_block_pressed_into_a_corner_touches_floor_and_wall():
    """A block pushed down and to the left by its top edge, between a floor (y = 0) and a wall
    (x = 0): both obstacles carry load, the contact forces balance the support reaction, and the
    conditions hold for each node against its own obstacle."""
    h = _block()
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (-0.01, -0.02))])
    floor = cm.ObstacleContact(0, BOTTOM, cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    wall = cm.ObstacleContact(0, LEFT, cm.PlaneObstacle((0.0, 0.0), (-1.0, 0.0)))
    p = cm.Problem(body, contacts=[floor, wall], friction=cm.Coulomb(0.2))
    res = p.solve(tol=0.0, rtol=1e-12)
    assert res.converged, res.status
    assert contact_conditions(p, res)["max"] < 1e-8
    forces = res.contact_forces()
    assert set(forces) == {"obstacle 0", "obstacle 1"}
    assert forces["obstacle 0"][1] > 0 and forces["obstacle 1"][0] > 0   # the floor pushes up, the wall right
    total = forces["obstacle 0"] + forces["obstacle 1"] + res.reactions()[TOP]
    assert np.abs(total).max() <= 1e-10 * np.abs(forces["obstacle 0"]).max()
    # the corner node (0, 0) belongs to both boundaries and keeps one obstacle: it lies on both planes
    corner = int(np.argmin(np.linalg.norm(h.finest.points, axis=1)))
    assert np.count_nonzero(p.contact.nodes == corner) == 1
    u = res.displacement[p.contact.nodes]
    on_floor, on_wall = p.contact_source == -1, p.contact_source == -2
    assert u[on_floor, 1].min() >= -1e-14 and u[on_wall, 0].min() >= -1e-14


def test_a_node_claimed_by_two_obstacles_takes_the_nearer():
    h = _block(2)
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (0.0, -0.01))])
    near = cm.ObstacleContact(0, BOTTOM, cm.PlaneObstacle((0.0, -0.001), (0.0, -1.0)))
    far = cm.ObstacleContact(0, BOTTOM, cm.PlaneObstacle((0.0, -0.002), (0.0, -1.0)))
    for contacts in ([near, far], [far, near]):
        p = cm.Problem(body, contacts=contacts)
        assert np.allclose(p.contact.gaps, 0.001)


def test_an_obstacle_beside_a_body_pair():
    """Two stacked blocks: the upper one pressed onto the lower one (a mortar pair), the lower one
    onto a rigid floor; the floor carries what the top edge pushes."""
    lower, upper = _block(3), _block(3, origin=(0.0, 1.0))
    bodies = [cm.Body(upper, MAT, [cm.Dirichlet(TOP, (0.0, -0.01))]),
              cm.Body(lower, MAT, [cm.Dirichlet(LEFT, (0.0, None))])]
    # the lower block is held sideways by its left edge; vertically only by the floor and the pair:
    # give it a soft spring so that the test does not rest on semi-coercive solves
    bodies[1].springs = {RIGHT: (0.0, 1e-6)}
    pair = cm.ContactPair(0, 1, [BOTTOM], [TOP], search=0.1)
    floor = cm.ObstacleContact(1, BOTTOM, cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    p = cm.Problem(bodies, contacts=[pair, floor])
    res = p.solve(tol=0.0, rtol=1e-12)
    assert res.converged, res.status
    assert contact_conditions(p, res)["max"] < 1e-8
    f = res.contact_forces()
    assert set(f) == {"pair 0", "obstacle 0"}
    assert f["obstacle 0"][1] > 0
    # the floor carries the push less what the weak spring takes
    push = -res.reactions()[(0, TOP)][1]
    assert f["obstacle 0"][1] == pytest.approx(push, rel=1e-4)


def test_a_flipped_plane_under_a_resting_body_is_refused():
    """The trap of a normal given as a rigid surface's (towards the body): gaps 0, converged with
    no reaction and the body through the floor. Refused, saying which way the normal points."""
    h = _block(2)
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (0.0, -0.01))], contact_tags=BOTTOM)
    with pytest.raises(ValueError, match="normal pointing into the body.*from the body into the obstacle"):
        cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, 1.0)))
    assert cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0))).contact.gaps.max() == 0.0


def test_swapped_contact_tags_are_refused():
    """The top facets named as the contact facets of a floor below the body."""
    h = _block(2)
    body = cm.Body(h, MAT, [cm.Dirichlet(BOTTOM, (0.0, 0.0))], contact_tags=TOP)
    with pytest.raises(ValueError, match="contact tags name the facets that face the obstacle"):
        cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))


def test_a_sphere_given_inside_out_is_refused():
    h = cm.MeshHierarchy.build(cm.hertz_half_disk(), 3, projector=cm.hertz_projector())
    body = cm.Body(h, MAT, [cm.Dirichlet(cm.HERTZ_TOP, (0.0, -0.01))], contact_tags=cm.HERTZ_ARC)
    ball = (0.0, -1.0)  # a rigid disk of radius 1 under the half disk, touching it at the origin
    assert cm.Problem(body, obstacle=cm.SphereObstacle(ball, 1.0)).contact.gaps.min() == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError, match="normal pointing into the body"):
        cm.Problem(body, obstacle=cm.SphereObstacle(ball, 1.0, inside=True))


def test_a_shallow_initial_penetration_is_reported_too():
    """0.02 inside a block of facets 0.125 long: below the facet size, still a load on the body."""
    h = _block(3)
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (0.0, 0.0))])
    with pytest.warns(UserWarning, match=r"start inside the obstacle by up to 0.02 "):
        cm.Problem(body, contacts=[cm.ObstacleContact(0, BOTTOM, cm.PlaneObstacle((0.0, 0.02), (0.0, -1.0)))])


def test_deep_initial_penetration_is_reported_unless_intended():
    h = _block(3)
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (0.0, 0.0))])
    deep = cm.PlaneObstacle((0.0, 0.5), (0.0, -1.0))   # half the block inside the floor
    with pytest.warns(UserWarning, match="start inside the obstacle deeper"):
        cm.Problem(body, contacts=[cm.ObstacleContact(0, BOTTOM, deep)])
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cm.Problem(body, contacts=[cm.ObstacleContact(0, BOTTOM, deep, allow_penetration=True)])


def test_bad_contacts_are_named():
    h = _block(1)
    body = cm.Body(h, MAT, [cm.Dirichlet(TOP, (0.0, 0.0))])
    plane = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0))
    with pytest.raises(ValueError, match="names body 3"):
        cm.Problem(body, contacts=[cm.ObstacleContact(3, BOTTOM, plane)])
    with pytest.raises(TypeError, match="contacts must hold"):
        cm.Problem(body, contacts=[plane])
    with pytest.raises(TypeError, match="gaps_and_normals"):
        cm.ObstacleContact(0, BOTTOM, "floor")
    with pytest.raises(ValueError, match="no boundary facet carries the contact tags"):
        cm.Problem(body, contacts=[cm.ObstacleContact(0, 77, plane)])
