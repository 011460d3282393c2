"""The independent contact check: right on every step of a load path (slip measured from the
step's slip origin), on several bodies (the conditions on the relative unknowns w), for every law
in 2D and 3D; and it fails where the conditions are violated, naming the condition."""
import dataclasses

import numpy as np
import pytest

from contactmg import Body, Problem, Tresca
from contactmg.examples.cylinders import cylinders_problem
from contactmg.examples.hertz import TOP_DISPLACEMENT, hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.mesh.generators import HERTZ_TOP
from contactmg.results.checks import VIOLATION_TOL, check_contact, contact_conditions
from contactmg.results.result import SLIP
from contactmg.solve.loadpath import two_phase_path


@pytest.fixture(scope="module")
def press_then_shear():
    p = hertz_problem("triangle", 4, 0.4)
    path = two_phase_path(p, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), 3, (0.001, 0.0), 2).solve(tol=1e-12)
    assert path.converged
    return p, path


def test_every_load_path_step_meets_the_incremental_conditions(press_then_shear):
    p, path = press_then_shear
    for k, r in enumerate(path.steps):
        assert r.problem is p and r.slip_origin is not None
        if k:
            assert np.array_equal(r.slip_origin, path.steps[k - 1].displacement)
        assert r.check(raise_on_violation=True)["max"] <= VIOLATION_TOL
        assert check_contact(p, r)["max"] <= VIOLATION_TOL


def test_the_total_slip_is_not_the_step_slip(press_then_shear):
    """The shear steps slide: measured from u = 0 instead of the previous step, the direction of
    the friction force is wrong at some sliding node (the check does see the slip origin)."""
    p, path = press_then_shear
    last = path.steps[-1]
    assert np.any(last.contact_state == SLIP)
    without = dataclasses.replace(last, slip_origin=None)
    without.problem = p
    assert contact_conditions(p, without)["slip_direction"] > 1e-3
    with pytest.raises(ValueError, match="slip_direction"):
        check_contact(p, without)


@pytest.fixture(scope="module")
def cylinders():
    p = cylinders_problem(5, friction=0.4)
    return p, p.solve(tol=1e-12)


def test_two_bodies_meet_the_conditions_on_the_relative_displacement(cylinders):
    p, r = cylinders
    assert r.converged and p.multibody
    v = r.check(raise_on_violation=True)
    assert v["max"] <= VIOLATION_TOL
    # the canonical u in the transformed matrix T^T A T is no solution of anything
    u = np.asarray(r.displacement)
    assert np.abs(p.A.matvec(u) - p.load).max() > 1e-3 * np.abs(r.contact_force).max()


def test_a_perturbed_displacement_is_flagged(cylinders):
    p, r = cylinders
    bad = dataclasses.replace(r, displacement=r.displacement.copy())
    bad.problem = p
    c = np.argmax(np.abs(r.contact_force[:, 0]))  # the most loaded contact node, pushed along its outward normal
    bad.displacement[p.contact.nodes[c]] += 1e-3 * np.abs(r.displacement).max() * p.contact.normals[c]
    v = bad.check()
    assert v["max"] > 1e-6 and v["penetration"] > 0
    with pytest.raises(ValueError, match="penetration"):
        bad.check(raise_on_violation=True)
    with pytest.raises(ValueError, match="interior"):
        check_contact(p, bad)


def _tresca(levels=4):
    h = hertz_problem("triangle", levels, 0.0)
    return Problem(h.bodies[0], h.obstacle, Tresca(2.0))


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 4, 0.0), _tresca,
                                  lambda: hertz_problem("quad", 4, 0.3),
                                  lambda: sphere_problem("tetra", 2, 0.3), lambda: sphere_problem("hexahedron", 2, 0.0)],
                         ids=["frictionless", "tresca", "coulomb-quad", "coulomb-3d", "frictionless-3d"])
def test_every_law_and_dimension_passes_and_a_push_into_the_obstacle_fails(make):
    p = make()
    r = p.solve(tol=1e-12)
    assert r.converged
    assert r.check(raise_on_violation=True)["max"] <= VIOLATION_TOL
    bad = dataclasses.replace(r, displacement=r.displacement.copy())
    bad.problem = p
    # along the outward normal: into the obstacle
    bad.displacement[p.contact.nodes] += 1e-2 * np.abs(r.displacement).max() * p.contact.normals
    with pytest.raises(ValueError, match="penetration"):
        bad.check(raise_on_violation=True)


def test_a_result_without_its_problem_and_bad_tolerances_are_refused(cylinders):
    p, r = cylinders
    orphan = dataclasses.replace(r)
    orphan.problem = None
    with pytest.raises(ValueError, match="needs the problem"):
        orphan.check()
    for tol in (-1.0, "1e-6", None):
        with pytest.raises(ValueError, match="tol must be a number"):
            check_contact(p, r, tol=tol)


def test_a_two_body_load_path_meets_the_conditions_on_every_step():
    """The steps of several bodies start and measure slip from the previous step's unknowns w."""
    from contactmg.solve.loadpath import LoadPath

    p = cylinders_problem(5, friction=0.4)
    path = LoadPath.proportional(p, 3).solve(tol=1e-12)
    assert path.converged
    for k, r in enumerate(path.steps):
        if k:
            previous = path.steps[k - 1].displacement
            assert np.array_equal(r.slip_origin, p.relative_displacement(previous))
        assert r.check(raise_on_violation=True)["max"] <= VIOLATION_TOL


def _held_block(levels=4):
    """A 2 x 1 block with no supports on a rigid floor, traction (0.2, -1) on its top, Coulomb 0.3:
    held by friction alone (0.2 < 0.3 x 1)."""
    import contactmg as cm
    from contactmg.mesh.generators import RECT_BOTTOM, RECT_TOP, rectangle

    h = cm.MeshHierarchy.build(rectangle(4, 2, 2.0, 1.0), levels)
    body = cm.Body(h, cm.Material(1000.0, 0.3), [], contact_tags=[RECT_BOTTOM], traction={RECT_TOP: (0.2, -1.0)})
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))


def test_a_runaway_iterate_cannot_pass_the_check():
    """Violations are measured against the load's scale, not one the iterate sets: the solution
    blown up a million times (every reaction and contact force with it) fails by far, where a scale
    from its own contact forces made it look like round-off."""
    p = _held_block()
    r = p.solve("tnnmg")
    assert r.converged and contact_conditions(p, r)["max"] < VIOLATION_TOL
    bad = dataclasses.replace(r, displacement=1e6 * r.displacement)
    bad.problem = p
    v = contact_conditions(p, bad)
    assert v["interior"] > 1.0 and v["balance"] > 1e-3


@pytest.mark.parametrize("method", ["tnnmg", None])
def test_converged_is_said_only_after_the_final_check(method):
    """A body held by friction alone: the solve says "converged" only with its equations solved and
    its forces balanced (the final check, against the load), whatever stopped the cycles."""
    p = _held_block(5)
    r = p.solve(method)
    if r.converged:
        v = r.extra["final_check"]
        assert v["max"] <= r.extra["final_check_tol"] and v["balance"] < 1e-8
        force = r.contact_forces()["obstacle"]
        assert np.allclose(force + r.canonical_load().sum(axis=0), 0.0, atol=1e-8 * 2.0)
    else:
        assert "not converged" in r.status or "no convergence" in r.status or "diverged" in r.status
