"""The projected coarse correction (SolverOptions.projected_coarse_correction, solve(projected_coarse_correction=...),
its default in resolve_options). The coarse correction leaves out the gap bounds of the
inactive contact nodes. It is then projected onto the gap and taken with the exact line search of
the frozen-bound energy.

It is on by default where a contact frame is rotated (the cork in its conical neck) and off for
axis-aligned frames (Hertz on a plane). With it on a solve reaches the same solution, passes the
independent check, and lowers the energy in every cycle. The cork's cycle count no longer grows
from level 2 to level 3."""
import numpy as np
import pytest

from helpers import check_switch_refuses_bad_values

from contactmg.results.checks import contact_conditions
from contactmg.examples.cork import cork_problem
from contactmg.examples.hertz import hertz_problem
from contactmg.solve.options import options_from, resolve_options



def test_default_follows_the_contact_frames():
    cork = cork_problem(levels=2, friction=0.0)
    assert cork.rotated_frames() and resolve_options(cork).projected_coarse_correction
    hertz = hertz_problem("triangle", 3, 0.4)
    assert not hertz.rotated_frames() and not resolve_options(hertz).projected_coarse_correction
    assert "projected_coarse_correction" not in hertz.solve(threads=1).extra
    r = cork.solve(threads=1)
    assert r.extra["projected_coarse_correction"] is True
    # the line search's step per cycle is recorded: finite, >= 0 (0 would mean no descent along w)
    steps = np.asarray(r.history["step_size"])
    assert len(steps) == r.cycles and np.all(np.isfinite(steps)) and np.all(steps >= 0)
    cork.default_options = options_from(cork.default_options).replace(projected_coarse_correction=False)
    assert not resolve_options(cork, cork.default_options).projected_coarse_correction
    off = cork.solve(threads=1)
    assert "projected_coarse_correction" not in off.extra and off.options["projected_coarse_correction"] is False
    assert resolve_options(cork, cork.default_options).to_core()["projected_coarse_correction"] is False
    # load paths take the problem's own choice (resolve_options)
    assert resolve_options(cork_problem(levels=2, friction=0.0)).to_core().get("projected_coarse_correction") is True


@pytest.mark.parametrize("friction", [0.0, 0.4])
def test_same_solution_as_the_bounded_correction(friction):
    p = cork_problem(levels=2, friction=friction, axial_layers=8)
    a = p.solve(threads=1, projected_coarse_correction=True)
    b = p.solve(threads=1, projected_coarse_correction=False)
    assert a.converged and b.converged
    ua, ub = np.asarray(a.displacement), np.asarray(b.displacement)
    assert np.abs(ua - ub).max() <= 1e-8 * np.abs(ub).max()
    assert contact_conditions(p, a)["max"] <= 1e-8
    assert np.array_equal(a.node_state, b.node_state)


def test_energy_falls_in_every_cycle_without_friction():
    # without friction the cycles minimize one convex energy: each coarse step is a descent step of
    # it (the line search) and each sweep too, so the recorded energy never rises
    p = cork_problem(levels=2, friction=0.0, axial_layers=8)
    r = p.solve(threads=1, projected_coarse_correction=True)
    e = np.asarray(r.history["energy"])
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())


def test_cork_cycles_do_not_grow_with_the_level():
    counts = [cork_problem(levels=L, friction=0.0, axial_layers=8).solve(threads=1).cycles for L in (2, 3)]
    assert counts[1] - counts[0] <= 2, counts


def test_bad_values():
    p = cork_problem(levels=2, friction=0.4)
    check_switch_refuses_bad_values(p, "projected_coarse_correction")
    with pytest.raises(ValueError, match="projected_coarse_correction must be True or False"):
        p.solver.core.solve(None, {"projected_coarse_correction": 1})  # the core refuses what is not a bool
    with pytest.raises(ValueError, match="projected_coarse_correction must be True or False"):
        options_from(p.default_options).replace(projected_coarse_correction=1)
