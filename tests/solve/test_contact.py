"""Contact with friction: truncated monotone multigrid and Algorithm 2."""
import numpy as np
import pytest

from contactmg.examples import hertz
from contactmg.model.friction import Coulomb, Frictionless, Tresca
from contactmg.mesh.generators import rectangle
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.model.problem import Body, Dirichlet, Problem
from contactmg.results.result import FREE, SLIP, STICK
from contactmg import _core
from helpers import assert_contact_conditions

FRICTIONS = [0.0, 0.4, 2.0, 40.0]


@pytest.mark.parametrize("cell", ["triangle", "quad"])
@pytest.mark.parametrize("F", FRICTIONS)
def test_hertz_solution_satisfies_contact_and_coulomb_conditions(cell, F):
    p = hertz.hertz_problem(cell, 5, F)
    res = p.solve()
    assert res.converged, res.status
    assert_contact_conditions(res, F, p.contact.gaps)
    c = res.counts()
    assert c["contact_nodes"] >= 5
    if F > 0:
        assert c["stick_nodes"] >= 1
    if 0 < F <= 2:
        assert c["slip_nodes"] >= 2


@pytest.mark.parametrize("law", ["frictionless", "tresca"])
def test_energy_decreases_every_cycle(law):
    p = hertz.hertz_problem("triangle", 6, 0.0)
    if law == "tresca":
        p = Problem(Body(p.hierarchy, p.material, [Dirichlet([2], (0.0, hertz.TOP_DISPLACEMENT))], contact_tags=[1]),
                    obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(30.0))
    res = p.solve()
    assert res.converged
    e = res.history["energy"]
    assert len(e) > 5
    # late cycles change the energy by ~(correction norm)^2 ~ 1e-22, below the round-off of
    # evaluating it (~1e-11 relative): allow that much
    assert np.all(np.diff(e) <= 1e-10 * np.abs(e).max()), np.diff(e).max()


def test_tresca_solution_conditions():
    """Tresca: |s_T| <= s everywhere, = s and opposite to the slip where the node slides, also off
    the obstacle (the bound is given)."""
    p = hertz.hertz_problem("quad", 5, 0.0)
    g = 5.0
    p = Problem(Body(p.hierarchy, p.material, [Dirichlet([2], (0.0, hertz.TOP_DISPLACEMENT))], contact_tags=[1]),
                obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(g))
    res = p.solve()
    s = res.contact_force
    bound = g * p.contact.measure
    uT = res.displacement[res.contact_nodes, 0]  # t = (1, 0) for n = (0, -1)
    assert np.all(np.abs(s[:, 1]) <= bound * (1 + 1e-9))
    moving = uT != 0
    np.testing.assert_allclose(s[moving, 1], -bound[moving] * np.sign(uT[moving]), rtol=1e-7)
    assert np.sum(moving) > 0 and np.sum(~moving) > 0


@pytest.mark.parametrize("cell", ["triangle", "quad"])
def test_cycle_counts_do_not_grow_with_level(cell):
    counts = {}
    for F in FRICTIONS:
        counts[F] = [hertz.hertz_problem(cell, L, F).solve().cycles for L in range(3, 8)]
    print(cell, counts)
    for F, c in counts.items():
        assert max(c) <= 30, (F, c)
        assert max(c[-2:]) <= max(c[:3]) + 4, (F, c)  # levels 6-7 against levels 3-5


def test_frictionless_hertz_matches_formulas():
    p = hertz.hertz_problem("triangle", 8, 0.0)
    res = p.solve()
    P = res.reaction[1]
    assert P > 0 and abs(res.reaction[0]) < 1e-8 * P
    a = hertz.halfwidth(P)
    p0 = hertz.peak_pressure(P)
    # the discrete half-width lies between the last active node and the first inactive one
    x = p.mesh.points[res.contact_nodes, 0]
    act = res.contact_state > 0
    inner = np.abs(x[act]).max()
    outer = np.abs(x[~act & (np.abs(x) > inner)]).min()
    assert inner <= a * 1.03 and outer >= a * 0.97, (inner, a, outer)
    assert abs(-res.normal_stress.min() - p0) < 0.03 * p0, (-res.normal_stress.min(), p0)
    # the pressure profile itself, inside the contact zone away from its edge
    inside = np.abs(x) < 0.8 * a
    np.testing.assert_allclose(-res.normal_stress[inside], hertz.pressure(x[inside], P), rtol=0.04)


def layer_problem(cell, s, depth, F, nx=8, ny=4, levels=3, H=0.5, W=1.0, mat=Material(100.0, 0.3)):
    """A layer of height H on the rigid plane y = 0; the top is displaced by (s, -depth), the
    sides are held to the exact linear field of the uniform state."""
    G, lam = mat.mu, mat.lam
    s_star = F * (lam + 2 * G) * depth / G
    slide = max(0.0, s - s_star)

    def exact(x):
        y = x[:, 1]
        ux = slide + (s - slide) * y / H
        uy = -depth * y / H
        return np.c_[ux, uy]

    h = MeshHierarchy.build(rectangle(nx, ny, lx=W, ly=H, cell=cell), levels)
    prob = Problem(Body(h, mat, [Dirichlet([2, 3, 4], exact)], contact_tags=[1]),
                   obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Coulomb(F) if F > 0 else Frictionless())
    return prob, exact, s_star, lam, G


@pytest.mark.parametrize("cell", ["triangle", "quad"])
@pytest.mark.parametrize("regime", ["stick", "slide"])
def test_sliding_layer_exact_solution(cell, regime):
    H, depth, F = 0.5, 0.01, 0.3
    _, _, s_star, lam, G = layer_problem(cell, 0.0, depth, F, H=H)
    s = 0.5 * s_star if regime == "stick" else 2.5 * s_star
    prob, exact, _, _, _ = layer_problem(cell, s, depth, F, H=H)
    res = prob.solve(tol=1e-13)
    assert res.converged
    np.testing.assert_allclose(res.displacement, exact(prob.mesh.points), atol=1e-11)
    p = (lam + 2 * G) * depth / H
    interior = np.abs(prob.mesh.points[res.contact_nodes, 0] - 0.5) < 0.49
    np.testing.assert_allclose(-res.normal_stress[interior], p, rtol=1e-9)
    shear = G * s / H if regime == "stick" else F * p
    # tangential stress on the body: opposite to the shear the top imposes
    np.testing.assert_allclose(-res.tangential_stress[interior, 0], shear, rtol=1e-9)
    states = res.contact_state[interior]
    assert np.all(states == (STICK if regime == "stick" else SLIP))


def test_small_friction_tends_to_frictionless_and_large_friction_sticks_the_centre():
    p0 = hertz.hertz_problem("triangle", 6, 0.0)
    r0 = p0.solve()
    diffs = []
    for F in (1e-2, 1e-3, 1e-4):
        r = hertz.hertz_problem("triangle", 6, F).solve()
        diffs.append(np.abs(r.displacement - r0.displacement).max())
    assert diffs[0] > diffs[1] > diffs[2] and diffs[2] < 1e-3 * np.abs(r0.displacement).max()
    big = hertz.hertz_problem("triangle", 6, 40.0).solve()
    x = big.mesh.points[big.contact_nodes, 0]
    st = big.contact_state
    centre = np.argmin(np.abs(x))
    assert st[centre] == STICK
    small = hertz.hertz_problem("triangle", 6, 0.4).solve()
    assert big.stick_halfwidth > small.stick_halfwidth > 0


def test_triangles_and_quads_agree_to_discretization_error():
    rt = hertz.hertz_problem("triangle", 7, 0.4).solve()
    rq = hertz.hertz_problem("quad", 7, 0.4).solve()
    Pt, Pq = rt.reaction[1], rq.reaction[1]
    assert abs(Pt - Pq) < 0.01 * Pt
    assert abs(rt.contact_halfwidth - rq.contact_halfwidth) < 0.06 * rt.contact_halfwidth


def test_incremental_coarse_update_equals_full_rebuild():
    """After a solve the coarse matrices were updated incrementally many times; a full Galerkin
    rebuild for the same truncation gives the same matrices (to round-off)."""
    from helpers import to_scipy

    p = hertz.hertz_problem("triangle", 6, 0.4)
    res = p.solve()
    assert res.rebuilds >= 3
    S = p.solver.core
    before = [to_scipy(_core.testing.coarse_matrix(S, l)) for l in range(S.num_levels - 1)]
    _core.testing.rebuild_coarse(S)
    after = [to_scipy(_core.testing.coarse_matrix(S, l)) for l in range(S.num_levels - 1)]
    for b, a in zip(before, after):
        assert abs(b - a).max() <= 1e-12 * abs(a).max()
