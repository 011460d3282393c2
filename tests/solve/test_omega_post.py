"""The post-smoothing sweeps' own over-relaxation: SolverOptions.omega_post,
solve(omega_post=...) and its default in resolve_options. Off by default; with omega = 1 before
the coarse correction and 1.7 after it the linear rate on the adaptive Hertz levels falls well below
the symmetric default's at the same cost, the monotone cycles stay monotone and Algorithm 2 reaches
the same solution."""
import contactmg as cm
import numpy as np
import pytest

from contactmg.examples import hertz
from contactmg.model.friction import Tresca
from contactmg.mesh.generators import HERTZ_TOP, hertz_half_disk
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem, hertz_problem_on
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.model.problem import Body, Dirichlet, Problem
from contactmg.solve.options import options_from, resolve_options, with_cycle



@pytest.fixture(scope="module")
def adaptive8():
    return hertz_adaptive_hierarchy(8, 0.4)


def rate(h, omega, omega_post=None):
    """F(3,3) contraction of the linear multigrid (zero load, random start, last 5 of 14 ratios)."""
    q = with_cycle(Problem(Body(h, Material(2000.0, 0.28), [Dirichlet([HERTZ_TOP], (0.0, 0.0))])), "F")
    q.load = np.zeros_like(q.load)
    r = q.solve(u0=np.random.default_rng(0).standard_normal(q.load.shape), tol=1e-300, rtol=1e-300, max_cycles=14,
                omega=omega, omega_post=omega_post)
    c = r.history["correction_norm"]
    return float(np.exp(np.mean(np.log(c[-5:] / c[-6:-1]))))


def test_off_by_default_and_bad_values():
    p = hertz_problem("triangle", 2, 0.4)
    assert p.default_options == cm.SolverOptions(method="nmg", tol=1e-11)
    r = p.solve()
    assert "omega_post" not in r.extra
    same = p.solve(omega_post=resolve_options(p).omega)  # equal to omega: the same sweeps, the same bits
    assert same.cycles == r.cycles
    np.testing.assert_array_equal(same.displacement, r.displacement)
    assert p.solve(omega=1.0, omega_post=1.7).extra["omega_post"] == 1.7
    for bad in (0.0, 2.0, -1.0, True, "1.2", float("nan")):
        with pytest.raises(ValueError, match=r"omega_post must be a number in \(0, 2\)"):
            p.solve(omega_post=bad)


def test_split_omega_lowers_the_linear_rate(adaptive8):
    """Measured on adaptive levels 5 / 6 / 7 / 8: 0.094 / 0.107 / 0.112 / 0.119 (1 / 1.7) against
    0.129 / 0.120 / 0.163 / 0.187 (the symmetric default 1.3); level 11: 0.127 against 0.230."""
    for L, gap in ((5, 0.02), (7, 0.03), (8, 0.05)):
        h = adaptive8.truncated(L)
        split, default = rate(h, 1.0, 1.7), rate(h, 1.3)
        assert split < default - gap, (L, split, default)
        assert split < 0.14, (L, split)


@pytest.mark.parametrize("omega, omega_post", [(1.0, 1.7), (1.8, 1.0), (1.0, 1.95)])
def test_split_omega_tresca_cycles_stay_monotone(omega, omega_post):
    h = MeshHierarchy.build(hertz_half_disk("triangle"), 5, projector=hertz.hertz_projector())
    # Algorithm 2 (the monotone cycles) to the absolute stop 1e-11
    p = with_cycle(Problem(Body(h, Material(hertz.E, hertz.NU),
                                [Dirichlet([HERTZ_TOP], (0.0, hertz.TOP_DISPLACEMENT))], contact_tags=[1]),
                           obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(30.0)))
    r = p.solve(omega=omega, omega_post=omega_post)
    assert r.converged, r.status
    e = r.history["energy"]
    assert len(e) > 5
    assert np.all(np.diff(e) <= 1e-10 * np.abs(e).max()), np.diff(e).max()
    ref = p.solve()
    d = r.displacement - ref.displacement
    assert np.sqrt(np.sum(d * p.A.matvec(d))) <= 1e-8 * np.sqrt(np.sum(ref.displacement * p.A.matvec(ref.displacement)))


def test_algorithm2_same_solution_with_split_omega(adaptive8):
    p = hertz_problem_on(adaptive8.truncated(6), 0.4)
    a = p.solve()
    p.default_options = options_from(p.default_options).replace(omega=1.0, omega_post=1.7)
    b = p.solve()
    assert a.converged and b.converged
    e = a.displacement - b.displacement
    norm = np.sqrt(np.sum(a.displacement * p.A.matvec(a.displacement)))
    assert np.sqrt(np.sum(e * p.A.matvec(e))) <= 1e-8 * norm
    assert np.array_equal(a.contact_state, b.contact_state)
    # the known-state linear solve takes it too, and needs fewer cycles
    la = p.solve("linear", reference=a, omega=1.3, omega_post=1.3)
    lb = p.solve("linear", reference=b)
    assert lb.cycles <= la.cycles, (lb.cycles, la.cycles)


@pytest.mark.parametrize("method", ["tnnmg", "fixed-point"])
def test_other_methods_take_omega_post(method):
    p = hertz_problem("triangle", 4, 0.4)
    ref = p.solve()
    r = p.solve(method, omega=1.0, omega_post=1.7)
    assert r.converged, r.status
    assert r.extra["omega_post"] == 1.7
    assert np.abs(r.displacement - ref.displacement).max() <= 1e-9 * np.abs(ref.displacement).max()
