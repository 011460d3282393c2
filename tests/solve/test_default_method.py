"""The method chosen when none is given: TNNMG with its line smoother where Algorithm 2's point
smoother is slow (nearly incompressible materials, stretched cells), Algorithm 2 elsewhere; the
result says which ran."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz
from contactmg.results.checks import contact_conditions
from contactmg.solve.options import cell_aspect_ratio, default_method


def _hertz_with(nu, level=6):
    geo = hertz.hertz_problem("triangle", level, 0.4)
    b = geo.bodies[0]
    return cm.Problem(cm.Body(geo.hierarchy, cm.Material(b.material.E, nu), b.dirichlet, contact_tags=b.contact_tags),
                      obstacle=geo.obstacle, friction=geo.friction)


def test_nearly_incompressible_takes_tnnmg_and_converges():
    p = _hertz_with(0.49)
    res = p.solve()
    assert res.method == "tnnmg" and res.options["method"] == "tnnmg"
    assert res.converged and res.cycles <= 30
    assert contact_conditions(p, res)["max"] < 1e-6


def test_a_stretched_layer_takes_tnnmg_and_converges():
    h = cm.MeshHierarchy.build(cm.rectangle(4, 4, lx=32.0, ly=1.0, cell="quad"), 5)
    assert cell_aspect_ratio(h.finest) == pytest.approx(32.0)
    p = cm.Problem(cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet([3], (0.01, -0.01))], contact_tags=[1]),
                   obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3))
    res = p.solve()
    assert res.method == "tnnmg" and res.converged and res.cycles <= 30
    assert contact_conditions(p, res)["max"] < 1e-6


def test_an_ordinary_problem_keeps_algorithm_2_and_the_paper_names_it():
    p = _hertz_with(0.28, level=4)
    assert default_method(p) == "nmg" and p.solve().method == "nmg"
    # the paper's benchmark names its method: the same whatever the default rule says
    assert hertz.hertz_problem("triangle", 3, 0.4).default_options.method == "nmg"
    # a method given is the method used
    assert _hertz_with(0.49, level=4).solve("nmg").method == "nmg"


def test_the_choice_agrees_with_algorithm_2s_answer():
    p = _hertz_with(0.49, level=5)
    auto = p.solve()
    nmg = p.solve("nmg", tol=0.0, rtol=1e-12)
    assert auto.method == "tnnmg"
    assert np.abs(auto.displacement - nmg.displacement).max() <= 1e-7 * np.abs(nmg.displacement).max()


def test_algorithm_2_goes_on_with_tnnmg_where_coarse_levels_from_a_mesh_contract_slowly():
    """The cork's 4-layer mesh, its coarse levels made from it: Algorithm 2's corrections contract
    slowly there, the solve goes on with TNNMG from its iterate under the same stop, and finds the
    answer of Algorithm 2 alone in fewer cycles."""
    from contactmg.examples.cork import cork_problem

    geo = cork_problem(2, 0.4, axial_layers=4)
    b = geo.bodies[0]
    p = cm.Problem(cm.Body(cm.MeshHierarchy.coarsened(geo.mesh), b.material, b.dirichlet, contact_tags=b.contact_tags),
                   obstacle=geo.obstacle, friction=geo.friction)
    auto = p.solve()
    alone = p.solve(switch_rate=0)
    assert auto.options["switch_rate"] == 0.5 and alone.options["switch_rate"] == 0
    assert auto.converged and alone.converged
    after = auto.extra.get("switched_to_tnnmg_after")
    assert after is not None and 5 <= after < auto.cycles < alone.cycles
    c = alone.history["correction_norm"]
    # the switch came when Algorithm 2's last three corrections had contracted by less than 0.5 each
    assert c[after - 1] > 0.5 ** 3 * c[after - 4]
    assert np.abs(auto.displacement - alone.displacement).max() <= 1e-7 * np.abs(alone.displacement).max()
    assert contact_conditions(p, auto)["max"] < 1e-6
    assert "then tnnmg after cycle" in auto.summary()


def test_the_switch_is_off_where_the_method_is_given_or_the_levels_are_refined():
    geo = hertz.hertz_problem("triangle", 4, 0.4)   # a refined hierarchy: no switch
    assert cm.resolve_options(geo, cm.SolverOptions()).switch_rate == 0
    b = geo.bodies[0]
    p = cm.Problem(cm.Body(cm.MeshHierarchy.coarsened(geo.mesh), b.material, b.dirichlet, contact_tags=b.contact_tags),
                   obstacle=geo.obstacle, friction=geo.friction)
    assert cm.resolve_options(p, cm.SolverOptions()).switch_rate == 0.5
    assert cm.resolve_options(p, cm.SolverOptions(method="nmg")).switch_rate == 0
    with pytest.raises(ValueError, match="switch_rate is a choice of method 'nmg'"):
        cm.SolverOptions(method="tnnmg", switch_rate=0.5)
    with pytest.raises(ValueError, match=r"switch_rate must be a number in \[0, 1\)"):
        cm.SolverOptions(switch_rate=1.0)
