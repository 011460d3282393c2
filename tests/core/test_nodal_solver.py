"""The exact nodal solver against independent minimizations of the local problem
    min 1/2 x^T B x - b^T x + s |x_T|  subject to x_n <= g."""
import itertools

import numpy as np
import pytest

from contactmg import _core

SOLVE_T = {2: _core.solve_node_tresca_2D, 3: _core.solve_node_tresca_3D}
SOLVE_C = {2: _core.solve_node_coulomb_2D, 3: _core.solve_node_coulomb_3D}


def energy(B, b, s, x):
    return 0.5 * x @ B @ x - b @ x + s * np.linalg.norm(x[1:])


def assert_kkt(B, b, g, s, x, fix_normal=False, tol=1e-10):
    """First-order conditions, necessary and sufficient for this convex problem."""
    G = B @ x - b
    scale = 1 + np.abs(b).max() + np.abs(B).max() * np.abs(x).max()
    if not fix_normal:
        assert x[0] <= g
        if x[0] < g:
            assert abs(G[0]) <= tol * scale
        else:
            assert G[0] <= tol * scale
    xt = x[1:]
    if np.all(xt == 0):
        assert np.linalg.norm(G[1:]) <= s + tol * scale
    else:
        np.testing.assert_allclose(G[1:], -s * xt / np.linalg.norm(xt), atol=tol * scale)


def assert_no_better_point(B, b, g, s, x, rng, fix_normal=False, trials=2000):
    """Brute force: no feasible point in a cloud around x (radii 1e-6..1) has lower energy."""
    e0 = energy(B, b, s, x)
    for r in (1e-6, 1e-4, 1e-2, 1.0):
        Y = x + r * rng.normal(size=(trials // 4, len(x)))
        Y[:, 0] = g if fix_normal else np.minimum(Y[:, 0], g)
        e = 0.5 * np.einsum("ki,ij,kj->k", Y, B, Y) - Y @ b + s * np.linalg.norm(Y[:, 1:], axis=1)
        assert e.min() >= e0 - 1e-13 * (1 + abs(e0))


def enumerate_2d(B, b, g, s):
    """2D only: enumerate the pieces (x_n free or on g; x_T = 0, > 0 or < 0) and keep the best
    feasible stationary point."""
    best, best_e = None, np.inf
    for normal_on_gap, sign in itertools.product([False, True], [0, 1, -1]):
        x = np.zeros(2)
        if normal_on_gap:
            x[0] = g
            if sign:
                x[1] = (b[1] - B[1, 0] * g - s * sign) / B[1, 1]
        else:
            if sign:
                x[:] = np.linalg.solve(B, b - np.array([0, s * sign]))
            else:
                x[0] = b[0] / B[0, 0]
        if x[0] > g + 1e-14 or (sign and np.sign(x[1]) != sign):
            continue
        e = energy(B, b, s, x)
        if e < best_e:
            best, best_e = x, e
    return best


def random_case(rng, d):
    M = rng.normal(size=(d, d))
    B = M @ M.T + 0.3 * np.eye(d)
    b = rng.normal(size=d) * 2
    g = rng.normal() * 0.5
    s = abs(rng.normal()) * rng.choice([0, 0.3, 1, 3])
    return B, b, g, s


@pytest.mark.parametrize("d", [2, 3])
def test_tresca_node_is_the_minimizer(d):
    rng = np.random.default_rng(7 + d)
    regimes = set()
    for _ in range(200):
        B, b, g, s = random_case(rng, d)
        x = SOLVE_T[d](B, b, g, s)
        assert_kkt(B, b, g, s, x)
        assert_no_better_point(B, b, g, s, x, rng)
        regimes.add((x[0] == g, bool(np.all(x[1:] == 0))))
        # exact assignments: on the gap exactly g, stuck exactly 0
        assert x[0] <= g
    assert len(regimes) == 4  # free/on-gap x slip/stick all exercised


def test_tresca_node_2d_matches_enumeration():
    rng = np.random.default_rng(3)
    for _ in range(500):
        B, b, g, s = random_case(rng, 2)
        np.testing.assert_allclose(_core.solve_node_tresca_2D(B, b, g, s), enumerate_2d(B, b, g, s), atol=1e-12)


def coupling_ratio(B, F):
    """q = F |B_Tn| / lambda_min(B_TT): below 1 the node's own Coulomb condition on the gap has a
    unique solution (nodal_solve.hpp, coulomb_on_gap)."""
    return F * np.linalg.norm(B[1:, 0]) / np.linalg.eigvalsh(B[1:, 1:]).min()


def gap_normal_force(B, b, g, x):
    """s_n = (B x - b)_n at (g, x_T)."""
    return B[0, 0] * g + B[0, 1:] @ x[1:] - b[0]


@pytest.mark.parametrize("d", [2, 3])
def test_coulomb_node_rule(d):
    """The nodal Coulomb rule of the smoother, case by case, for any F (also where F |B_Tn| exceeds
    the tangential stiffness and the local problem is not monotone):
    - a node on the gap whose gap solution is compressive stays on the gap;
    - otherwise the frictionless trial; a node it leaves off the obstacle carries no friction;
    - otherwise on the gap: x is the Tresca minimizer (x_n = g) for the bound s = F max(0, -s_n),
      with s_n at x itself where q = F |B_Tn| / lambda_min(B_TT) < 1 (the node's own Coulomb
      condition, solved exactly), at (g, old_T) where q >= 1 (lagged)."""
    rng = np.random.default_rng(11 + d)
    seen = {"kept": 0, "off": 0, "on": 0, "own bound": 0, "lagged": 0}
    for _ in range(600):
        B, b, g, _ = random_case(rng, d)
        F = rng.choice([0.1, 0.5, 2.0, 40.0])
        old = rng.normal(size=d) * 0.3
        if rng.random() < 0.5:
            old[0] = g
        x = SOLVE_C[d](B, b, g, F, old)
        trial = SOLVE_T[d](B, b, g, 0.0)
        sn_new = gap_normal_force(B, b, g, x)
        if old[0] >= g and x[0] == g and sn_new <= 0:
            seen["kept"] += 1
        elif trial[0] < g:
            seen["off"] += 1
            np.testing.assert_allclose(x, trial, atol=1e-13)
            continue
        else:
            seen["on"] += 1
        assert x[0] == g
        own = coupling_ratio(B, F) < 1
        seen["own bound" if own else "lagged"] += 1
        s = F * max(0.0, -(sn_new if own else gap_normal_force(B, b, g, old)))
        assert_kkt(B, b, g, s, x, fix_normal=True, tol=1e-9)
        assert_no_better_point(B, b, g, s, x, rng, fix_normal=True)
    assert min(seen.values()) > 10, seen


def contractive_case(rng, d):
    """A node block with q < 1 and data that put the node on the gap with pressure."""
    while True:
        B, b, g, _ = random_case(rng, d)
        F = rng.choice([0.3, 1.0, 5.0, 40.0])
        B[1:, 0] *= rng.uniform(0.05, 0.99) / max(coupling_ratio(B, F), 1e-300)  # set q below 1
        B[0, 1:] = B[1:, 0]
        if np.linalg.eigvalsh(B).min() <= 1e-3:
            continue
        return B, b, g, F


@pytest.mark.parametrize("d", [2, 3])
def test_coulomb_on_gap_solves_the_nodes_own_condition_where_q_below_1(d):
    """Where q < 1, a node the rule leaves on the gap satisfies the nodal Coulomb conditions with
    the bound of its own position: |s_T| <= F |s_n| with x_T = 0 (stick) or s_T = -F |s_n| x_T/|x_T|
    (slip), compressive s_n <= 0 -- and the result does not depend on the old tangential position."""
    rng = np.random.default_rng(21 + d)
    seen = {"stick": 0, "slip": 0}
    for _ in range(400):
        B, b, g, F = contractive_case(rng, d)
        old = np.concatenate([[g], rng.normal(size=d - 1)])
        x = SOLVE_C[d](B, b, g, F, old)
        if x[0] != g:
            continue
        G = B @ x - b
        scale = 1 + np.abs(b).max() + np.abs(B).max() * np.abs(x).max()
        assert G[0] <= 1e-12 * scale
        bound = F * abs(G[0])
        if np.all(x[1:] == 0):
            seen["stick"] += 1
            assert np.linalg.norm(G[1:]) <= bound + 1e-12 * scale
        else:
            seen["slip"] += 1
            np.testing.assert_allclose(G[1:], -bound * x[1:] / np.linalg.norm(x[1:]), atol=1e-11 * scale)
        for _ in range(3):
            other = np.concatenate([[g], rng.normal(size=d - 1) * 3])
            np.testing.assert_allclose(SOLVE_C[d](B, b, g, F, other), x, atol=1e-12 * scale)
    assert min(seen.values()) > 20, seen


@pytest.mark.parametrize("d", [2, 3])
def test_coulomb_on_gap_is_lipschitz_in_the_data_where_q_below_1(d):
    """Continuity of the on-gap rule (q < 1): for data b, b' whose solutions both stay on the gap,
    |x_T - x'_T| <= (|dc| + F |dp0|) / (lambda_min(B_TT) (1 - q)), c = b_T - B_Tn g and
    p0 = b_n - B_nn g: the Tresca minimizer is 1/lambda-Lipschitz in (c, s) and the bound
    F max(0, p0 - B_nT x_T) is q-Lipschitz in x_T. The lagged rule has no such bound (it depends on
    old_T; its fixed point is reached only by a factor q per visit)."""
    rng = np.random.default_rng(31 + d)
    checked = 0
    for _ in range(400):
        B, b, g, F = contractive_case(rng, d)
        old = np.concatenate([[g], np.zeros(d - 1)])
        db = rng.normal(size=d) * rng.choice([1e-8, 1e-4, 1e-1])
        x, y = SOLVE_C[d](B, b, g, F, old), SOLVE_C[d](B, b + db, g, F, old)
        if x[0] != g or y[0] != g:
            continue
        q = coupling_ratio(B, F)
        lam = np.linalg.eigvalsh(B[1:, 1:]).min()
        dc, dp0 = np.linalg.norm(db[1:]), abs(db[0])
        assert np.linalg.norm(x[1:] - y[1:]) <= (dc + F * dp0) / (lam * (1 - q)) * (1 + 1e-9) + 1e-13
        checked += 1
    assert checked > 100


@pytest.mark.parametrize("d", [2, 3])
def test_local_coulomb_solutions_are_fixed_points_of_the_rule(d):
    """A local Coulomb solution — on the gap, compressive, x_T the Tresca minimizer for the bound
    F |s_n(x)| of its own position, sliding or sticking — is returned unchanged when it is the old
    value: so a solution of the whole problem is a fixed point of the smoother. Built backwards:
    pick x on the gap, a compressive s_n and x_T, then the b that makes it a solution."""
    rng = np.random.default_rng(3 + d)
    for _ in range(300):
        B, _, g, _ = random_case(rng, d)
        F = rng.choice([0.1, 0.5, 2.0, 5.0, 40.0])
        sn = -abs(rng.normal())                       # compressive normal force
        xt = rng.normal(size=d - 1) * (rng.random() < 0.7)  # sliding, or sticking at 0
        x = np.concatenate([[g], xt])
        G = np.empty(d)
        G[0] = sn
        if np.any(xt):
            G[1:] = -F * abs(sn) * xt / np.linalg.norm(xt)
        else:
            v = rng.normal(size=d - 1)
            G[1:] = 0.9 * F * abs(sn) * v / np.linalg.norm(v)   # strictly inside the cone
        b = B @ x - G                                 # so that B x - b = G
        y = SOLVE_C[d](B, b, g, F, x)
        np.testing.assert_allclose(y, x, atol=1e-12 * (1 + np.abs(x).max()))


def test_3d_slip_direction_opposes_friction_force():
    """In 3D the sliding solution satisfies S x_T - c = -s x_T/|x_T| (stationarity)."""
    rng = np.random.default_rng(5)
    for _ in range(100):
        B, b, g, _ = random_case(rng, 3)
        s = 0.2
        x = _core.solve_node_tresca_3D(B, b, 1e3, s)  # gap far away: normal free
        if np.linalg.norm(x[1:]) == 0:
            continue
        grad = B @ x - b
        np.testing.assert_allclose(grad[0], 0, atol=1e-12)
        np.testing.assert_allclose(grad[1:], -s * x[1:] / np.linalg.norm(x[1:]), atol=1e-11)
