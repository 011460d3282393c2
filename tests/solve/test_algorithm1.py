"""Algorithm 1 (fixed point in the normal stresses) against Algorithm 2."""
import numpy as np
import pytest

from contactmg.examples import hertz
from contactmg.results.checks import contact_conditions
from contactmg import _core


def energy_norm(p, u):
    return float(np.sqrt(u.ravel() @ p.A.matvec(u).ravel()))


@pytest.mark.parametrize("cell", ["triangle", "quad"])
@pytest.mark.parametrize("F", [0.08, 0.4, 1.0])
def test_fixed_point_reaches_the_nmg_solution(cell, F):
    p = hertz.hertz_problem(cell, 5, F)
    fp = p.solve("fixed-point")
    nm = p.solve("nmg")
    assert fp.converged and nm.converged, (fp.status, nm.status)
    assert fp.outer_iterations >= 2
    rel = energy_norm(p, fp.displacement - nm.displacement) / energy_norm(p, nm.displacement)
    assert rel <= 1e-8, rel
    # and both are solutions by an independent check of the contact conditions
    assert contact_conditions(p, nm)["max"] < 1e-9 and contact_conditions(p, fp)["max"] < 1e-7
    np.testing.assert_array_equal(fp.contact_state, nm.contact_state)


def test_outer_iterations_grow_with_level_while_nmg_cycles_do_not():
    its, fp_cycles, nmg_cycles = {}, {}, {}
    for F in (0.7, 2.0):
        its[F], fp_cycles[F], nmg_cycles[F] = [], [], []
        for L in (3, 4, 5, 6, 7):
            p = hertz.hertz_problem("triangle", L, F)
            fp, nm = p.solve("fixed-point"), p.solve("nmg")
            assert fp.converged and nm.converged
            its[F].append(fp.outer_iterations)
            fp_cycles[F].append(fp.cycles)
            nmg_cycles[F].append(nm.cycles)
    msg = f"fixed-point iterations {its}, nmg cycles {nmg_cycles}"
    for F in its:
        assert its[F][-1] >= 3 * its[F][0], msg          # e.g. 3 -> 11 for F = 0.7
        assert its[F][-1] >= its[F][-2] >= its[F][-3], msg
        assert max(nmg_cycles[F][-2:]) <= max(nmg_cycles[F][:3]) + 3, msg
    # on the finest level Algorithm 1 costs several times the V-cycles of Algorithm 2
    assert fp_cycles[0.7][-1] >= 4 * nmg_cycles[0.7][-1], msg


def test_fixed_point_costs_several_times_more_cycles_at_f_0_4():
    p = hertz.hertz_problem("triangle", 7, 0.4)
    fp, nm = p.solve("fixed-point"), p.solve("nmg")
    ratio = fp.cycles / nm.cycles
    print(f"F = 0.4, level 7: fixed point {fp.outer_iterations} outer / {fp.cycles} V-cycles, nmg {nm.cycles}: {ratio:.1f}x")
    assert fp.converged and nm.converged
    assert ratio >= 3, ratio


def test_fixed_point_slows_down_for_f_5_on_finer_levels():
    """The paper's Algorithm 1 fails for F = 5 on its finer, contact-refined levels; on the uniform
    levels the suite affords (up to 7) it converges but needs more outer iterations on the finest
    one: 3 on levels 2-6, 55 on level 7 (where it converges slowly to a state with two sliding nodes
    at the edge of the contact zone); measured: 7 on level 8, not part of the suite. Algorithm 2
    reaches the same solution in a flat number of cycles."""
    out, cyc = {}, {}
    for L in (3, 7):
        p = hertz.hertz_problem("triangle", L, 5.0)
        fp = p.solve("fixed-point")
        nm = p.solve("nmg")
        out[L] = fp.outer_iterations if fp.converged else np.inf
        cyc[L] = nm.cycles
        assert nm.converged and contact_conditions(p, nm)["max"] < 1e-9
        if fp.converged:
            assert contact_conditions(p, fp)["max"] < 1e-6
            rel = energy_norm(p, fp.displacement - nm.displacement) / energy_norm(p, nm.displacement)
            assert rel < 1e-7, rel
    print("F = 5 outer iterations", out, "nmg cycles", cyc)
    assert out[7] > out[3], out
    # bounded, not growing like Algorithm 1 (measured 11 on level 3 and 17 on level 7 with the
    # settled cycles mixed; 14 and 19 before): within the target with room
    assert cyc[7] <= 20, cyc


def test_nmg_never_reports_a_non_solution_as_converged_at_f_5_level_7():
    """At F = 5 on level 7 the nonlinear Gauss-Seidel falls into a limit cycle at the edge of the
    contact zone (16,000 plain sweeps do not settle either), and with an even number of sweeps per
    cycle the correction norm drops below the tolerance on an iterate that is not a solution
    (interior residual 0.30 of the largest contact force). The solver must not call that converged:
    one more sweep moves it, and the result says so."""
    p = hertz.hertz_problem("triangle", 7, 5.0)
    nm = p.solve("nmg")
    v = contact_conditions(p, nm)
    if nm.converged:
        assert v["max"] < 1e-8, v
        assert nm.sweep_check <= 1e-9
    else:
        assert "stalled" in nm.status or "no convergence" in nm.status, nm.status
        assert v["max"] > 1e-6, v  # the check is not a false alarm: the iterate is no solution
        assert nm.sweep_check > 1e3 * 1e-11


@pytest.mark.parametrize("F", [0.0, 0.4, 2.0])
def test_converged_solves_are_fixed_points_of_the_smoother(F):
    """A solution is a fixed point of the nonlinear smoother: one more sweep from a converged
    result moves it by less than the tolerance (measured independently with `smooth`)."""
    p = hertz.hertz_problem("quad", 5, F)
    r = p.solve("nmg")
    assert r.converged and r.sweep_check < 1e-11
    u1 = _core.testing.smooth(p.solver.core, r.displacement, 1)
    assert np.abs(u1 - r.displacement).max() < 1e-10 * np.abs(r.displacement).max()


def test_fixed_point_reports_non_convergence():
    p = hertz.hertz_problem("triangle", 6, 2.0)
    res = p.solve("fixed-point", fixed_point_max=3)
    assert not res.converged and res.outer_iterations == 3
    assert "no convergence" in res.status
