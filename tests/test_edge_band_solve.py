"""The edge band's nonlinear block solve of benchmarks/edge_band_solve.py (issue 11, eighth part; a
prototype, not in the core): a solution of the whole problem is a fixed point of the band step, and
from a perturbed iterate the band step's result satisfies the band's own Coulomb conditions, is
feasible and is a fixed point of the core's nodal rule on the band."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "benchmarks"))

import edge_band_solve as E  # noqa: E402
from coulomb_newton_diagnosis import hertz_system  # noqa: E402

from contactmg.hertz import hertz_adaptive_hierarchy, hertz_problem_on  # noqa: E402


@pytest.fixture(scope="module")
def hierarchy():
    return hertz_adaptive_hierarchy(5, 0.4)


@pytest.mark.parametrize("F", [0.4, 5.0])
def test_band_step(hierarchy, F):
    p = hertz_problem_on(hierarchy, F)
    r = p.solve("nmg", tol=1e-12, max_cycles=200, threads=1)
    assert r.converged
    S = hertz_system(p)
    x = S["D"] * np.asarray(r.displacement).ravel()
    # the contact edge: the 8 contact nodes nearest to +- the contact half-width (as the nodes whose
    # state changed; band_nodes adds a ring of neighbours)
    C = np.asarray(p.contact.nodes)
    xc = p.mesh.points[C, 0]
    hw = np.abs(xc[np.asarray(r.node_state)[C] > 0]).max()
    edge = np.argsort(np.abs(np.abs(xc) - hw))[:8]
    band, lmax = E.band_nodes(S, x, edge)
    assert 8 < len(band) < len(S["g"])
    # the solution is a fixed point of the band step
    y, info = E.band_step(S, F, x, edge)
    assert np.abs(y - x).max() <= 1e-9 * np.abs(x).max()
    # from a perturbed iterate (the band's dofs moved), the band step solves the band's problem
    rng = np.random.default_rng(1)
    dofs, Kb, bb, g = E.band_system(S, x, band)
    xp = x.copy()
    xp[dofs] += 0.05 * np.abs(x[dofs]).max() * rng.standard_normal(len(dofs))
    xp[dofs[1::2]] = np.minimum(xp[dofs[1::2]], g)  # feasible start
    y, info = E.band_step(S, F, xp, edge)
    assert info["by"] in ("newton", "sweeps")
    dofs2, Kb2, bb2, g2 = E.band_system(S, xp, E.band_nodes(S, xp, edge)[0])
    yb = y[dofs2]
    phi, _, _ = E.ac_phi(Kb2, bb2, g2, F, yb)
    assert np.abs(phi).max() <= 1e-8 * lmax
    assert np.all(yb[1::2] <= g2 + 1e-14)
    ys, _ = E.band_sweeps(Kb2, bb2, g2, F, yb, sweeps=1)
    assert np.abs(ys - yb).max() <= 1e-8 * np.abs(yb).max()
    # every dof off the band untouched
    off = np.ones(len(x), bool)
    off[dofs2] = False
    assert np.array_equal(y[off], xp[off])
