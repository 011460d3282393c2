"""Checks shared by several test modules.

The "nmg" cycle switches (petrov_galerkin, upwind_contact_sweep,
projected_coarse_correction): a bad value of solve(name=...) is refused with a message naming the
switch, and switching one on is refused for the methods that have no such cycle."""
import numpy as np
import pytest
import scipy.sparse as sp

from contactmg.results.result import SLIP, STICK
from contactmg.solve.solver import Solver


def check_switch_refuses_bad_values(p, name, methods=("tnnmg", "fixed-point")):
    for bad in ("yes", 1, 0.0, [True]):
        with pytest.raises(ValueError, match=f"{name} must be True or False"):
            p.solve(**{name: bad})
    for method in methods:
        with pytest.raises(ValueError, match=f"{name} is a choice of method 'nmg'"):
            p.solve(method, **{name: True})


def to_scipy(A):
    """BlockMatrix -> scipy CSR (an independent view of the same numbers)."""
    d = A.block_size
    data = A.data
    indptr, indices = A.indptr, A.indices
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    r = (rows[:, None, None] * d + np.arange(d)[None, :, None]).repeat(d, 2)
    c = (indices[:, None, None] * d + np.arange(d)[None, None, :]).repeat(d, 1)
    return sp.csr_matrix((data.ravel(), (r.ravel(), c.ravel())), shape=A.shape)


def assert_contact_conditions(res, F, gaps, rtol=1e-8):
    """u_n <= g, s_n <= 0, s_n (u_n - g) = 0, |s_T| <= F |s_n|, slip opposite to s_T."""
    Q = res.contact_frames
    u = np.einsum("cji,cj->ci", Q, res.displacement[res.contact_nodes])  # local frame
    s = res.contact_force
    scale = np.abs(s[:, 0]).max()
    assert scale > 0
    un, sn, uT, sT = u[:, 0], s[:, 0], u[:, 1], s[:, 1]
    assert np.all(un <= gaps)                                   # exact: the smoother assigns g
    assert np.all(sn <= rtol * scale)
    assert np.all(np.abs(sn * (un - gaps)) <= rtol * scale * np.abs(gaps).max())
    active = un == gaps
    assert np.all(np.abs(sn[~active]) <= rtol * scale)
    assert np.all(np.abs(sT) <= F * np.abs(sn) + rtol * scale)
    slip = active & (uT != 0)
    np.testing.assert_allclose(sT[slip], -F * np.abs(sn[slip]) * np.sign(uT[slip]), atol=rtol * scale)
    state = res.contact_state
    assert np.all((state == STICK) == (active & (uT == 0)))
    assert np.all((state == SLIP) == slip)


def contraction(problem, cycles=14, seed=0):
    """Zero load, random start: the correction norms decay like the error; the rate is the
    geometric mean of the last five ratios. Returns (rate, seconds per cycle)."""
    rng = np.random.default_rng(seed)
    u0 = rng.standard_normal(problem.load.shape)
    # a solver of its own, whose core takes the zero load (the problem's kept solver is untouched)
    res = Solver(problem, problem.default_options).solve(
        u0, load=np.zeros_like(problem.load), options=dict(tol=1e-300, rtol=1e-300, max_cycles=cycles))
    c = np.asarray(res.history["correction_norm"])
    ratios = c[1:] / c[:-1]
    return float(np.exp(np.mean(np.log(ratios[-5:])))), res.solve_seconds / res.cycles
