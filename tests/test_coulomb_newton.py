"""Algorithm 2's Coulomb solutions against an independent solver: semismooth Newton on the
Alart-Curnier conditions with sparse direct solves (benchmarks/coulomb_newton_diagnosis.py),
on the adaptive Hertz hierarchy (issue 11)."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "benchmarks"))

from coulomb_newton_diagnosis import ac_residual, hertz_system, line_system, semismooth_newton  # noqa: E402

from contactmg.hertz import hertz_adaptive_hierarchy, hertz_problem_on  # noqa: E402


@pytest.fixture(scope="module")
def hierarchy():
    return hertz_adaptive_hierarchy(6, 0.4)


@pytest.mark.parametrize("F", [0.4, 5.0, 40.0])
def test_algorithm2_matches_semismooth_newton(hierarchy, F):
    p = hertz_problem_on(hierarchy, F)
    r = p.solve("nmg", tol=1e-11, max_cycles=200)
    assert r.converged
    S = hertz_system(p)
    u = np.asarray(r.displacement).ravel()
    scale = np.abs(ac_residual(S, F, np.zeros_like(u) + S["fixed_values"])).max()
    # Algorithm 2's result satisfies the Alart-Curnier equations up to round-off ...
    assert np.abs(ac_residual(S, F, S["D"] * u)).max() < 1e-8 * scale
    # ... and Newton, started from the frictionless state's neighbourhood (u = 0 with the Dirichlet
    # values), reaches the same displacement
    x, hist, _ = semismooth_newton(S, F, S["fixed_values"].copy(), max_steps=60, tol=1e-12 * scale)
    assert hist[-1] < 1e-9 * scale
    du = (S["D"] * x - u).reshape(-1, 2)
    uu = u.reshape(-1, 2)
    assert np.sqrt(np.sum(du * p.A.matvec(du))) < 1e-7 * np.sqrt(np.sum(uu * p.A.matvec(uu)))


def test_line_newton_solution_is_a_fixed_point_of_the_nodal_rule(hierarchy):
    """The contact nodes alone (every other node frozen): Newton's solution of that problem is
    left in place by the point rule (the diagnosis' claim that an exact line solve is consistent
    with the smoother), from an iterate one cycle into Algorithm 2 at F = 5."""
    from contact_line_diagnosis import point_sweep
    F = 5.0
    p = hertz_problem_on(hierarchy, F)
    u = np.asarray(p.solve("nmg", tol=1e-11, max_cycles=1).displacement).ravel()
    S = hertz_system(p)
    x = S["D"] * u
    Ls = line_system(S, x)
    xl, hist, _ = semismooth_newton(Ls, F, x[Ls["dofs"]].copy(), max_steps=60)
    assert hist[-1] < 1e-9 * max(1.0, np.abs(Ls["b"]).max())
    # contact_line_diagnosis orders (n, T) per node: swap the pairs
    y = xl.reshape(-1, 2)[:, ::-1].ravel().copy()
    K = Ls["K"].tocoo()
    perm = np.arange(len(y)).reshape(-1, 2)[:, ::-1].ravel()
    inv = np.argsort(perm)
    import scipy.sparse as sp
    Kp = sp.csr_matrix((K.data, (inv[K.row], inv[K.col])), shape=K.shape)
    b = Ls["b"][perm]
    y0 = y.copy()
    point_sweep(Kp, b, Ls["g"], F, y)
    assert np.abs(y - y0).max() <= 1e-12 * max(np.abs(y0).max(), 1e-3)
