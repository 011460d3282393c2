"""The public API: Problem (the description), SolverOptions (one validated list of options),
resolve_options (the problem-dependent defaults), Solver (the core built once)."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples.cylinders import cylinders_problem
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem_on


def hertz_description(levels=4, friction=0.4):
    h = cm.MeshHierarchy.build(cm.hertz_half_disk("triangle"), levels=levels, projector=cm.hertz_projector())
    body = cm.Body(h, cm.Material(E=2000.0, nu=0.28), dirichlet=[cm.Dirichlet([cm.HERTZ_TOP], (0.0, -0.01))],
                   contact_tags=[cm.HERTZ_ARC])
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(friction))


@pytest.mark.parametrize("field, value", [("tol", -1.0), ("max_cycles", 0), ("cycle", "X"), ("nu1", 1.5),
                                          ("omega", 2.0), ("ordering", "random"), ("method", "cg"),
                                          ("petrov_galerkin", "yes"), ("threads", -1), ("lines", 1)])
def test_options_name_the_bad_field(field, value):
    with pytest.raises(ValueError, match=field):
        cm.SolverOptions(**{field: value})
    with pytest.raises(ValueError, match=field):
        cm.SolverOptions().replace(**{field: value})


def test_options_replace_and_core_dict():
    o = cm.SolverOptions(tol=1e-10)
    v = o.replace(cycle="V", nu2=1)
    assert (o.cycle, v.cycle, v.nu2, v.tol) == ("F", "V", 1, 1e-10)
    with pytest.raises(TypeError, match="unknown"):
        o.replace(smoother="gs")
    core = cm.SolverOptions(method="linear", petrov_galerkin=True).to_core()
    assert core["method"] == "nmg"  # the known-state solve is linear: the core's cycles without contact
    assert "local_smoothing" not in core and "release_hierarchy" not in core and "start" not in core  # the package's own


def test_resolve_options_fills_every_problem_dependent_default():
    uniform = hertz_description(3)
    r = cm.resolve_options(uniform)
    assert all(getattr(r, k) is not None for k in ("omega", "omega_post", "ordering", "local_smoothing",
                                                   "petrov_galerkin", "upwind_contact_sweep",
                                                   "projected_coarse_correction"))
    assert (r.omega, r.omega_post, r.ordering) == (1.3, 1.3, "coloured")
    assert not (r.local_smoothing or r.petrov_galerkin or r.upwind_contact_sweep or r.projected_coarse_correction)
    adaptive = hertz_problem_on(hertz_adaptive_hierarchy(4, 0.4), 0.4)
    a = cm.resolve_options(adaptive, adaptive.default_options)
    assert a.local_smoothing and a.petrov_galerkin and a.upwind_contact_sweep and a.omega_post == 1.5
    assert not cm.resolve_options(adaptive, cm.SolverOptions(petrov_galerkin=False)).petrov_galerkin  # given wins
    assert cm.resolve_options(adaptive, dict(omega=1.1)).omega_post == 1.1  # a given omega is the post omega too
    res = adaptive.solve()
    assert res.options == a.to_dict()


def test_solver_builds_once_and_equals_problem_solve():
    p = hertz_description(4)
    s = cm.Solver(p, cm.SolverOptions(tol=1e-10))
    core = s.core
    a = s.solve()
    b = s.solve()
    assert s.core is core and a.cycles == b.cycles
    np.testing.assert_array_equal(a.displacement, b.displacement)
    q = hertz_description(4)
    c = q.solve("nmg", tol=1e-10)
    np.testing.assert_array_equal(a.displacement, c.displacement)
    assert q.solver.core is q.solver.core  # kept
    fast = s.with_options(cycle="V")
    assert fast.core is core and fast.options.cycle == "V" and s.options.cycle == "F"
    assert fast.solve().extra["cycle_options"]["cycle"] == "V"
    with pytest.raises(ValueError, match="local_smoothing"):
        s.with_options(local_smoothing=True)
    with pytest.raises(ValueError, match="release_hierarchy"):
        s.solve(options=dict(release_hierarchy=True))
    # another sweep order on the solver stored by colours: the same solution (to round-off)
    lex = s.solve(options=dict(ordering="lexicographic"))
    assert lex.extra["ordering"] == "lexicographic" and s.core is core
    assert np.abs(lex.displacement - a.displacement).max() <= 1e-8 * np.abs(a.displacement).max()


def test_solver_takes_the_load_step_data():
    """Scaling load and Dirichlet values by 2 through the solve scales the linear (frictionless,
    contact-free) answer by 2; a slip origin of zero changes nothing."""
    h = cm.MeshHierarchy.build(cm.rectangle(2, 1, 2, 1), levels=3)
    body = cm.Body(h, cm.Material(E=100.0, nu=0.3), dirichlet=[cm.Dirichlet([cm.RECT_LEFT], (0.0, 0.0))],
                   traction={cm.RECT_RIGHT: (1.0, 0.5)})
    p = cm.Problem(body)
    s = cm.Solver(p)
    one = s.solve()
    two = s.solve(load=2 * p.load, fixed_values=2 * p.fixed_values)
    np.testing.assert_allclose(two.displacement, 2 * one.displacement, rtol=1e-8, atol=1e-12)
    zero = hertz_description(3)
    s = cm.Solver(zero)
    plain = s.solve()
    origin = s.solve(slip_origin=np.zeros_like(plain.displacement))
    np.testing.assert_array_equal(plain.displacement, origin.displacement)


def test_several_bodies_are_one_problem_class():
    p = cylinders_problem(levels=3, friction=0.4)
    assert isinstance(p, cm.Problem) and p.multibody and len(p.bodies) == 2
    r = cm.Solver(p).solve()
    assert r.converged and np.array_equal(r.extra["body_id"], p.body_id)
    with pytest.raises(ValueError, match="obstacle"):
        cm.Problem(p.bodies, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), pairs=p.pairs)
    with pytest.raises(TypeError, match="pairs"):
        cm.Problem(p.bodies)
    with pytest.raises(TypeError, match="Problem"):
        cm.Solver(object())
