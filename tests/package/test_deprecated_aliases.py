"""The 0.1 classes ContactProblem, MultiBodyProblem and TwoBodyProblem are deprecated aliases kept for
one release: each warns (DeprecationWarning naming the replacement, at the caller's line) and builds
the very problem of its replacement, contactmg.Problem with the alias's cycle as the solve defaults
(contactmg.solve.options.with_cycle). The rest of the suite makes these warnings errors
(pyproject.toml): this is the one module that makes the aliases."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples.hertz import TOP_DISPLACEMENT, hertz_problem
from contactmg.solve.options import PAPER_TOL, SolverOptions, with_cycle

MAT = cm.Material(1000.0, 0.3)
PAIR_TAGS = dict(nonmortar_tags=[cm.RECT_BOTTOM], mortar_tags=[cm.RECT_TOP], search=0.1)


def _made_here(record):
    """Did the one warning of `record` name a line of this file (stacklevel 2: the caller's)?"""
    assert len(record) == 1, [str(w.message) for w in record]
    return record[0].filename == __file__


def _same_problem(alias, problem):
    """The same load, Dirichlet data, contact nodes and gaps, and the same solve defaults."""
    assert isinstance(alias, cm.Problem)
    np.testing.assert_array_equal(alias.load, problem.load)
    np.testing.assert_array_equal(alias.fixed, problem.fixed)
    np.testing.assert_array_equal(alias.fixed_values, problem.fixed_values)
    np.testing.assert_array_equal(alias.contact.nodes, problem.contact.nodes)
    np.testing.assert_array_equal(alias.contact.gaps, problem.contact.gaps)
    assert alias.default_options == problem.default_options


def _one_body(cycle="F", nu1=3, nu2=3):
    h = cm.MeshHierarchy.build(cm.hertz_half_disk("triangle"), 3,
                               projector=cm.hertz_projector((0.0, 0.4), 0.4))
    args = (h, cm.Material(2000.0, 0.28), [cm.Dirichlet([cm.HERTZ_TOP], (0.0, TOP_DISPLACEMENT))])
    kw = dict(contact_tags=[cm.HERTZ_ARC], body_force=(0.0, -1.0))
    obstacle, friction = cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), cm.Coulomb(0.4)
    with pytest.warns(DeprecationWarning, match=r"^contactmg\.ContactProblem is deprecated.*contactmg\.Problem\(") as rec:
        alias = cm.ContactProblem(*args, obstacle=obstacle, friction=friction, cycle=cycle, nu1=nu1, nu2=nu2, **kw)
    assert _made_here(rec)
    problem = with_cycle(cm.Problem(cm.Body(*args, **kw), obstacle=obstacle, friction=friction), cycle, nu1, nu2)
    return alias, problem


def _blocks():
    """Two stacked blocks with non-matching meshes: the upper one pushed down and sideways."""
    upper = cm.MeshHierarchy.build(cm.rectangle(7, 4, 1, 1, origin=(0.0, 0.0)), 3)
    lower = cm.MeshHierarchy.build(cm.rectangle(5, 3, 1, 1, origin=(0.0, -1.0)), 3)
    return [cm.Body(upper, MAT, [cm.Dirichlet([cm.RECT_TOP], (0.002, -0.01))]),
            cm.Body(lower, MAT, [cm.Dirichlet([cm.RECT_BOTTOM], (0.0, 0.0))])]


def test_contact_problem_warns_and_is_the_one_body_problem():
    alias, problem = _one_body("V", 2, 1)
    _same_problem(alias, problem)
    assert alias.default_options == SolverOptions(method="nmg", cycle="V", nu1=2, nu2=1, tol=PAPER_TOL)
    assert alias.law == problem.law == "coulomb" and len(alias.contact.nodes) > 0
    a, b = alias.solve(), problem.solve()
    assert a.converged and a.method == "nmg" and a.cycles == b.cycles
    np.testing.assert_array_equal(a.displacement, b.displacement)


def test_contact_problem_solves_as_the_example_it_was():
    """The alias's defaults (nmg F(3,3), tol 1e-11) are those of the Hertz example: the same bits."""
    p = hertz_problem("triangle", 3, 0.4)
    with pytest.warns(DeprecationWarning, match=r"^contactmg\.ContactProblem is deprecated"):
        alias = cm.ContactProblem(p.hierarchy, cm.Material(2000.0, 0.28),
                                  [cm.Dirichlet([cm.HERTZ_TOP], (0.0, TOP_DISPLACEMENT))], contact_tags=[cm.HERTZ_ARC],
                                  obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.4))
    assert isinstance(alias, cm.Problem) and cm.ContactProblem.__doc__
    np.testing.assert_array_equal(alias.solve().displacement, p.solve().displacement)


@pytest.mark.parametrize("name", ["MultiBodyProblem", "TwoBodyProblem"])
def test_two_body_aliases_warn_and_are_the_problem_of_the_pairs(name):
    bodies = _blocks()
    pair = cm.ContactPair(0, 1, **PAIR_TAGS)
    alias_cls = getattr(cm, name)
    with pytest.warns(DeprecationWarning, match=rf"^contactmg\.{name} is deprecated.*contactmg\.Problem\(bodies, pairs=") as rec:
        alias = alias_cls(bodies, [pair] if name == "MultiBodyProblem" else pair, cm.Coulomb(0.3), cycle="W", nu1=2, nu2=2)
    assert _made_here(rec)
    problem = with_cycle(cm.Problem(bodies, pairs=[pair], friction=cm.Coulomb(0.3)), "W", 2, 2)
    _same_problem(alias, problem)
    assert alias.multibody and alias.tied_correction == problem.tied_correction
    np.testing.assert_array_equal(alias.body_id, problem.body_id)
    a, b = alias.solve(), problem.solve()
    assert a.converged and a.method == "nmg" and a.cycles == b.cycles
    np.testing.assert_array_equal(a.displacement, b.displacement)


def test_aliases_keep_refusing_what_they_refused():
    """The aliases' own checks stay (after their warning)."""
    bodies = _blocks()
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError, match="pair must be a ContactPair"):
        cm.TwoBodyProblem(bodies, "pair")
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError, match="at least two Body"):
        cm.MultiBodyProblem(bodies[:1], [cm.ContactPair(0, 1, **PAIR_TAGS)])


def test_the_suite_turns_the_alias_warnings_into_errors():
    """pyproject.toml's filterwarnings makes a use of an alias outside pytest.warns fail a test."""
    with pytest.raises(DeprecationWarning, match="ContactProblem is deprecated"):
        _plain_contact_problem()


def _plain_contact_problem():
    h = cm.MeshHierarchy.build(cm.rectangle(2, 2), 1)
    return cm.ContactProblem(h, MAT, [cm.Dirichlet([cm.RECT_LEFT], (0.0, 0.0))])
