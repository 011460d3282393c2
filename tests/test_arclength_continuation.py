"""The exact piecewise arc-length continuation of the discrete Coulomb problem in (x, F)
(benchmarks/arclength_continuation.py, issue 11, ninth part) on a small adaptive Hertz level:
its tangent against a finite difference of two Newton solutions, its residual along the path,
its end point against Algorithm 2, and the orientation rule at its kinks."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "benchmarks"))

from arclength_continuation import PiecewisePath, run, state_of  # noqa: E402
from coulomb_newton_diagnosis import ac_residual, hertz_system, semismooth_newton  # noqa: E402

from contactmg.hertz import hertz_adaptive_hierarchy, hertz_problem_on  # noqa: E402

F0 = 0.4


@pytest.fixture(scope="module")
def setup():
    H = hertz_adaptive_hierarchy(7, 0.4)
    p = hertz_problem_on(H, F0)
    r = p.solve("nmg", tol=1e-12, max_cycles=200)
    assert r.converged
    S = hertz_system(p)
    x0 = S["D"] * np.asarray(r.displacement).ravel()
    scale = float(np.abs(ac_residual(S, F0, S["fixed_values"].copy())).max())
    return H, S, x0, scale


def test_tangent_matches_finite_difference_of_newton_solutions(setup):
    H, S, x0, scale = setup
    st = state_of(S, F0, x0)
    assert ((st >= 2).sum()) > 5  # sliding nodes: the branch depends on F
    P = PiecewisePath(S, st, verbose=False)
    P.set_state(st)
    # a short step inside the first piece (its first kink is beyond F0 + 1e-3 on this level)
    h = 1e-4
    assert P.indicators(F0 + h).min() > 0
    xs = []
    for F in (F0, F0 + h):
        x, hist, _ = semismooth_newton(S, F, x0.copy(), max_steps=20, tol=1e-13 * scale)
        assert hist[-1] < 1e-11 * scale
        xs.append(x)
    fd = (xs[1] - xs[0])[P.J] / h
    tangent = P.tangent_J(F0 + 0.5 * h)
    assert np.abs(tangent).max() > 0
    assert np.abs(fd - tangent).max() < 1e-5 * np.abs(tangent).max()  # measured 2.4e-7
    # and the piece's own solution at F0 + h is Newton's
    assert np.abs(P.full_x(F0 + h) - xs[1]).max() < 1e-9 * np.abs(xs[1]).max()


def test_path_residual_end_point_and_orientation(setup):
    H, S, x0, scale = setup
    F1 = 1.0
    out, P, F_end, x_end = run(S, x0, F0, F1, 0.1, max_pieces=100, deadline=60, check_every=1, verbose=False)
    assert F_end == F1
    assert len(out["pieces"]) > 5  # several state changes on the way
    # the residual at every kink and at the end stays at round-off
    assert out["checks"] and max(c["phi"] for c in out["checks"]) < 1e-9 * scale
    assert out["end_phi"] < 1e-9 * scale
    # the inequalities of every piece were met (no piece ended without a valid continuation)
    assert all("end" not in q for q in out["pieces"][:-1])
    # a turn in F happens exactly where sign det M_S changes
    for q in out["pieces"][:-1]:
        assert (q["new_direction"] != q["direction"]) == (q["det_sign_before"] != q["det_sign_after"])
        assert q["jump"] < 1e-9
    # the end point is Algorithm 2's solution at F1
    p1 = hertz_problem_on(H, F1)
    r1 = p1.solve("nmg", tol=1e-12, max_cycles=200)
    assert r1.converged
    x1 = S["D"] * np.asarray(r1.displacement).ravel()
    assert np.abs(x_end - x1).max() < 1e-8 * np.abs(x1).max()
