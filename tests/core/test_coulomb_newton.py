"""Algorithm 2's Coulomb solutions against an independent solver: semismooth Newton on the
Alart-Curnier conditions with sparse direct solves, on the adaptive Hertz hierarchy."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from contactmg import _core
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem_on


def hertz_system(p):
    """The problem in the contact frames of the Hertz plane obstacle (2D): K = D A D, b = D f,
    x = D u with D = -1 at the y dofs of contact nodes; normal dof 2c+1, tangential 2c."""
    m = p.mesh
    A = _core.assemble_elasticity(m.points, m.cells, m.cell_type, p.material.E, p.material.nu)
    A = sp.bsr_matrix((np.asarray(A.data).reshape(-1, 2, 2), np.asarray(A.indices), np.asarray(A.indptr)),
                      shape=A.shape).tocsr()
    C, g = np.asarray(p.contact.nodes), np.asarray(p.contact.gaps)
    D = np.ones(A.shape[0])
    D[2 * C + 1] = -1
    return {"K": (sp.diags(D) @ A @ sp.diags(D)).tocsr(), "b": D * np.asarray(p.load).ravel(), "D": D,
            "g": g, "n": 2 * C + 1, "t": 2 * C, "fixed": p.fixed.ravel().astype(bool),
            "fixed_values": D * p.fixed_values.ravel()}


def ac_residual(S, F, x):
    """The Alart-Curnier residual of x (c_p the node's own diagonal entries)."""
    K, n, t, g = S["K"], S["n"], S["t"], S["g"]
    r = S["b"] - K @ x
    diag = K.diagonal()
    phi = r.copy()
    phi[S["fixed"]] = x[S["fixed"]] - S["fixed_values"][S["fixed"]]
    lam = np.maximum(0.0, r[n] + diag[n] * (x[n] - g))
    phi[n] = r[n] - lam
    phi[t] = r[t] - np.clip(r[t] + diag[t] * x[t], -F * lam, F * lam)
    return phi


def newton_target(S, F, x):
    """The full Newton step's target: the linear problem of x's contact state (active, stick, slip)."""
    K, b, n, t, g = S["K"], S["b"], S["n"], S["t"], S["g"]
    r = b - K @ x
    diag = K.diagonal()
    lam = r[n] + diag[n] * (x[n] - g)
    z = r[t] + diag[t] * x[t]
    active = lam > 0
    stick = active & (np.abs(z) <= F * lam)
    slip = active & ~stick
    N = K.shape[0]
    ident = np.zeros(N, bool)
    ident[S["fixed"]] = True
    ident[n[active]] = True
    ident[t[stick]] = True
    rhs = b.copy()
    rhs[S["fixed"]] = S["fixed_values"][S["fixed"]]
    rhs[n[active]] = g[active]
    rhs[t[stick]] = 0
    sgn = np.sign(z[slip])
    # sliding rows: r_T - sign F r_n = 0, i.e. (K_T - sign F K_n) x = b_T - sign F b_n
    E = sp.csr_matrix((-sgn * F, (t[slip], n[slip])), shape=(N, N))
    M = sp.diags((~ident).astype(float)) @ (K + E @ K) + sp.diags(ident.astype(float))
    rhs[t[slip]] = b[t[slip]] - sgn * F * b[n[slip]]
    return spla.spsolve(M.tocsc(), rhs)


def semismooth_newton(S, F, x, max_steps=30, tol=1e-10):
    """Newton with an Armijo line search on |phi|^2; returns (x, |phi| history)."""
    phi = ac_residual(S, F, x)
    theta = 0.5 * phi @ phi
    hist, stuck = [float(np.sqrt(2 * theta))], 0
    for _ in range(max_steps):
        if hist[-1] <= tol:
            break
        y = newton_target(S, F, x)
        step = 1.0
        while True:
            xt = x + step * (y - x)
            ph = ac_residual(S, F, xt)
            tn = 0.5 * ph @ ph
            if tn <= (1 - 1e-4 * step) * theta or step < 2.0 ** -20:
                break
            step *= 0.5
        x, theta = xt, tn
        hist.append(float(np.sqrt(2 * theta)))
        stuck = stuck + 1 if step < 2.0 ** -20 else 0
        if stuck >= 3:
            break
    return x, hist


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
    x, hist = semismooth_newton(S, F, S["fixed_values"].copy(), max_steps=60, tol=1e-12 * scale)
    assert hist[-1] < 1e-9 * scale
    du = (S["D"] * x - u).reshape(-1, 2)
    uu = u.reshape(-1, 2)
    assert np.sqrt(np.sum(du * p.A.matvec(du))) < 1e-7 * np.sqrt(np.sum(uu * p.A.matvec(uu)))
