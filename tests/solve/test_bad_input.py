"""Bad input to the Python API gets a ValueError/TypeError (or MemoryError before allocating) whose
message names what is wrong — never a crash, a hang or a silent wrong answer (issues 2 and 5)."""
import math

import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz
from contactmg.mesh.generators import HERTZ_ARC, HERTZ_TOP, hertz_half_disk, hertz_projector
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.problem import Dirichlet
from contactmg.solve.options import with_cycle


@pytest.fixture(scope="module")
def hier():
    return MeshHierarchy.build(hertz_half_disk("triangle"), 3, projector=hertz_projector())


def problem(hier, **kw):
    """The Hertz problem on `hier` with the Body, obstacle and friction arguments `kw` changed; cycle,
    nu1 and nu2 (if given) set as its solve defaults by with_cycle."""
    cycle = {k: kw.pop(k) for k in ("cycle", "nu1", "nu2") if k in kw}
    args = dict(material=cm.Material(2000.0, 0.28), dirichlet=[Dirichlet([HERTZ_TOP], (0.0, -0.005))],
                contact_tags=[HERTZ_ARC], obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.4))
    args.update(kw)
    obstacle, friction = args.pop("obstacle"), args.pop("friction")
    p = cm.Problem(cm.Body(hier, **args), obstacle=obstacle, friction=friction)
    return with_cycle(p, **cycle) if cycle else p


@pytest.mark.parametrize("E, nu, exc, match", [
    (0.0, 0.3, ValueError, "Young's modulus"), (-1.0, 0.3, ValueError, "Young's modulus"),
    (math.nan, 0.3, ValueError, "Young's modulus"), (math.inf, 0.3, ValueError, "Young's modulus"),
    (1.0, 0.5, ValueError, "Poisson"), (1.0, -1.0, ValueError, "Poisson"), (1.0, math.nan, ValueError, "Poisson"),
    ("1", 0.3, TypeError, "E must be a number"), (1.0, True, TypeError, "nu must be a number")])
def test_material(E, nu, exc, match):
    with pytest.raises(exc, match=match):
        cm.Material(E, nu)


def test_rigid_body_motion_left_free(hier):
    # only the horizontal component of the top edge is held: the body can rotate about a point of
    # that edge, and no load presses it onto the obstacle
    with pytest.raises(ValueError, match=r"nothing holds the body in a rotation in the plane about \[0.0, 0.4\]"):
        problem(hier, dirichlet=[Dirichlet([HERTZ_TOP], (0.0, None))])
    with pytest.raises(ValueError, match="no boundary facet carries the Dirichlet tags"):
        problem(hier, dirichlet=[Dirichlet([99], (0.0, 0.0))])


def test_more_levels_than_memory_allows():
    # estimated before anything is allocated: the call returns at once
    with pytest.raises(MemoryError, match="levels need about"):
        MeshHierarchy.build(hertz_half_disk("triangle"), 14, projector=hertz_projector())
    with pytest.raises(ValueError, match="at least 1"):
        MeshHierarchy.build(hertz_half_disk("triangle"), 0)
    with pytest.raises(TypeError, match="integer"):
        MeshHierarchy.build(hertz_half_disk("triangle"), 2.5)


@pytest.mark.parametrize("kw, exc, match", [
    (dict(dirichlet=[Dirichlet([HERTZ_TOP], -0.005)]), TypeError, "Dirichlet value must be a vector"),
    (dict(dirichlet=[Dirichlet([HERTZ_TOP], (0.0, -0.005, 1.0))]), ValueError, "needs 2 components"),
    (dict(dirichlet=[Dirichlet([HERTZ_TOP], (0.0, math.nan))]), ValueError, "finite"),
    (dict(dirichlet=[(HERTZ_TOP, (0.0, 0.0))]), TypeError, "Dirichlet\\(tags, value\\)"),
    (dict(obstacle="the floor"), TypeError, "obstacle must be"),
    (dict(obstacle=None), ValueError, "no obstacle"),
    (dict(obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, 0.0))), ValueError, "non-zero"),
    (dict(obstacle=cm.PlaneObstacle((0.0, 0.0, 0.0), (0.0, -1.0, 0.0))), ValueError, "2 components"),
    (dict(obstacle=cm.NodalObstacle(np.zeros(3), np.zeros((3, 2)))), ValueError, "NodalObstacle needs"),
    (dict(contact_tags=[42]), ValueError, "contact tags"),
    (dict(friction=cm.Coulomb(-0.1)), ValueError, ">= 0"),
    (dict(friction=cm.Coulomb(math.nan)), ValueError, ">= 0"),
    (dict(friction=cm.Coulomb(np.ones(3))), ValueError, "one value per contact node"),
    (dict(friction=cm.Tresca(-1.0)), ValueError, ">= 0"),
    (dict(friction=0.4), TypeError, "friction must be"),
    (dict(cycle="X"), ValueError, "cycle must be"),
    (dict(nu1=0, nu2=0), ValueError, "at least 1"),
    (dict(nu1=-1), ValueError, "nu1 must be"),
    (dict(material="steel"), TypeError, "material must be"),
])
def test_problem_setup(hier, kw, exc, match):
    with pytest.raises(exc, match=match):
        problem(hier, **kw)


@pytest.mark.parametrize("kw, match", [
    (dict(method="newton"), "method must be"), (dict(tol=-1.0), "tol must be"), (dict(tol=math.nan), "tol must be"),
    (dict(tol=0.0, rtol=0.0), "one of tol and rtol"), (dict(max_cycles=0), "max_cycles"),
    (dict(max_cycles=2.5), "max_cycles"), (dict(method="fixed-point", fixed_point_max=0), "fixed_point_max"),
    (dict(u0=np.zeros((3, 2))), "u0"), (dict(u0=np.full((1, 1), np.nan)), "u0"),
])
def test_solve_arguments(hier, kw, match):
    p = problem(hier)
    u0 = kw.pop("u0", None)
    with pytest.raises(ValueError, match=match):
        p.solve(u0=u0, **kw)


def test_non_finite_initial_guess(hier):
    p = problem(hier)
    u0 = np.zeros((p.mesh.num_points, 2))
    u0[5, 1] = np.inf
    with pytest.raises(ValueError, match="initial guess has a non-finite entry"):
        p.solve(u0=u0)


def test_fixed_point_needs_coulomb(hier):
    with pytest.raises(ValueError, match="needs Coulomb friction"):
        problem(hier, friction=cm.Tresca(1.0)).solve("fixed-point")


def test_hertz_problem_arguments():
    with pytest.raises(ValueError, match="friction coefficient"):
        hertz.hertz_problem("triangle", 3, -0.4)
    with pytest.raises(ValueError):
        hertz.hertz_problem("hexagon", 3, 0.4)
