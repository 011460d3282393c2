"""Algorithm 2 at large friction on a graded mesh: cases that stalled in a limit
cycle of the nonlinear smoother or contracted slowly once the contact state had settled now converge
and are verified by the independent check (contactmg.results.checks), and the settled-cycle acceleration
leaves the solution where Algorithm 1 and the unaccelerated method put it."""
import numpy as np
import pytest

from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem


@pytest.fixture(scope="module")
def adaptive_9():
    return hertz_adaptive_hierarchy(9, 0.4)  # 59k dofs at level 9, about 5 s


def energy_norm(p, v):
    return float(np.sqrt(np.sum(v * p.A.matvec(v))))


@pytest.mark.parametrize("F", [20.0, 40.0])
def test_adaptive_level_9_large_friction_converges_and_verifies(F, adaptive_9):
    """Adaptive Hertz level 9 (59k dofs): F = 20 and 40 stalled before (the cycle returned to an
    iterate that one more sweep moved by 1.8 and 2.7e-1 relative violation). Now:
    converged, confirmed by the sweep check, every nodal condition met, in at most 30 cycles."""
    p = hertz_problem(friction=F, hierarchy=adaptive_9.truncated(9), coulomb_at_zero=True)
    r = p.solve(max_cycles=100)
    assert r.converged, r.status
    assert contact_conditions(p, r)["max"] < VIOLATION_TOL
    assert r.cycles <= 30, r.cycles
    # the contact zone carries friction: sticking interior, sliding edge nodes
    assert np.count_nonzero(r.node_state == 1) > 0 and np.count_nonzero(r.node_state == 2) > 0


def test_settled_slow_case_within_the_target(adaptive_9):
    """Adaptive level 7 at F = 8 took 41 cycles (Algorithm 1: 59 outer iterations): once the contact
    state has settled the cycle contracted by about 0.8, because the coarse problem freezes the
    friction bound F |s_n| of the sliding nodes. The target (<= 25 cycles) holds."""
    p = hertz_problem(friction=8.0, hierarchy=adaptive_9.truncated(7), coulomb_at_zero=True)
    r = p.solve()
    assert r.converged, r.status
    assert contact_conditions(p, r)["max"] < VIOLATION_TOL
    assert r.cycles <= 25, r.cycles


@pytest.mark.parametrize("F", [0.4, 1.1])
def test_accelerated_algorithm_2_agrees_with_algorithm_1(F, adaptive_9):
    """Where the discrete Coulomb problem has a unique solution (small F), Algorithm 2 -- with its
    settled cycles Anderson-mixed -- and the fixed point of Algorithm 1 reach the same displacement."""
    p = hertz_problem(friction=F, hierarchy=adaptive_9.truncated(6), coulomb_at_zero=True)
    a = p.solve()
    b = p.solve("fixed-point")
    assert a.converged and b.converged
    e = a.displacement - b.displacement
    assert energy_norm(p, e) <= 1e-7 * energy_norm(p, a.displacement)
    assert contact_conditions(p, a)["max"] < VIOLATION_TOL


def test_accelerated_cycles_decrease_the_error_to_the_tolerance(adaptive_9):
    """The stopping test still measures the step ||u^{k+1} - u^k||_A: at the stop the error against
    a solution solved 100 times tighter is of the order of the tolerance (not a stagnating mixture)."""
    p = hertz_problem(friction=40.0, hierarchy=adaptive_9.truncated(7), coulomb_at_zero=True)
    ref = p.solve(tol=1e-13)
    assert ref.converged
    r = p.solve(tol=1e-9, error_reference=ref.displacement)
    assert r.converged
    assert r.history["error"][-1] <= 1e-8


@pytest.mark.slow
def test_adaptive_level_11_friction_8_converges_and_verifies():
    """The paper's adaptive hierarchy at level 11 (465k dofs), F = 8: the plain cycle wandered at a
    correction of about 2e-3 for 200 cycles while a few nodes at the contact edge switched between
    free and sliding in every cycle, and the Anderson history restarted at every switch. The
    history is now kept across a switch where the cycle has stopped making progress: converged,
    confirmed by the sweep check and by the independent check of the contact conditions (measured:
    99 cycles; the bound leaves room, the count is far from the paper's h-independent one)."""
    h = hertz_adaptive_hierarchy(11, 0.4)
    p = hertz_problem(friction=8.0, hierarchy=h, coulomb_at_zero=True)
    r = p.solve(max_cycles=200)
    assert r.converged, r.status
    assert contact_conditions(p, r)["max"] < VIOLATION_TOL
    assert r.cycles <= 160, r.cycles
    assert np.count_nonzero(r.node_state == 2) > 0  # friction acts: sliding edge nodes
