"""Algorithm 2's cycles with the sliding nodes' Petrov-Galerkin coupling on level L-1
(0006-petrov-galerkin-coupling): SolverOptions.petrov_galerkin, solve(petrov_galerkin=True),
its default in resolve_options. On by default for Coulomb friction on 2D adaptive
hierarchies (with the post-smoothing's own omega, DEFAULT_OMEGA_POST_ADAPTIVE), off on uniform
ones and in 3D. With it on the solve reaches the same solution and passes the independent check,
the coupling is really used (in every cycle but the first), the top coarse level is symmetric
again after the solve, laws without an iterate-dependent bound ignore it, and the fallback refuses
a cycle whose correction grows."""
import contactmg as cm
import numpy as np
import pytest

from helpers import check_switch_refuses_bad_values
import scipy.sparse as sp

from contactmg.examples import hertz
from contactmg.examples import sphere
from contactmg.mesh.generators import HERTZ_TOP, hertz_half_disk
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.results.checks import contact_conditions
from contactmg.model.friction import Tresca
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem
from contactmg.solve.options import DEFAULT_OMEGA_POST_ADAPTIVE
from contactmg.model.problem import Body, Dirichlet, Problem
from contactmg import _core
from contactmg.solve.options import options_from, resolve_options



def same_solution(p, a, b, rtol=1e-8):
    ua, ub = np.asarray(a.displacement), np.asarray(b.displacement)
    assert np.abs(ua - ub).max() <= rtol * np.abs(ua).max()
    assert contact_conditions(p, b)["max"] <= 1e-8
    assert np.array_equal(a.node_state, b.node_state)


def test_default_by_hierarchy_and_bad_values(adaptive7):
    p = hertz_problem("triangle", 3, 0.4)
    assert p.default_options == cm.SolverOptions(method="nmg", tol=1e-11) and not resolve_options(p).petrov_galerkin  # uniform: off
    assert resolve_options(p).omega_post == resolve_options(p).omega  # no post-smoothing omega of its own
    r = p.solve()
    assert "petrov_galerkin" not in r.extra
    assert not np.any(r.history["petrov_galerkin"])
    # 2D adaptive, Coulomb: on, with the post-smoothing's own omega; the same bits as asking for both
    a = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True, hierarchy=adaptive7.truncated(5))
    assert resolve_options(a).petrov_galerkin and resolve_options(a).omega_post == DEFAULT_OMEGA_POST_ADAPTIVE["triangle"]
    d = a.solve(threads=1)
    assert d.extra["petrov_galerkin"]["cycles"] > 0
    fresh = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True, hierarchy=adaptive7.truncated(5))
    asked = fresh.solve(threads=1, petrov_galerkin=True, omega=resolve_options(fresh).omega,
                        omega_post=DEFAULT_OMEGA_POST_ADAPTIVE["triangle"])
    assert np.array_equal(np.asarray(d.displacement), np.asarray(asked.displacement))
    # an omega given to solve is the post-smoothing's too (no default post omega beside it)
    one = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True, hierarchy=adaptive7.truncated(5))
    w1 = one.solve(threads=1, omega=1.0)
    w2 = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True,
                       hierarchy=adaptive7.truncated(5)).solve(threads=1, omega=1.0, omega_post=1.0)
    assert np.array_equal(np.asarray(w1.displacement), np.asarray(w2.displacement))
    # frictionless: nothing to couple
    assert not resolve_options(hertz_problem("triangle", 5, 0.0, hierarchy=adaptive7.truncated(5))).petrov_galerkin
    check_switch_refuses_bad_values(p, "petrov_galerkin")
    with pytest.raises(ValueError, match="petrov_galerkin must be True or False"):
        p.solver.core.solve(None, {"petrov_galerkin": 1})  # the core refuses what is not a bool
    p.solve("tnnmg", petrov_galerkin=False)  # off is every method's
    from contactmg.solve.loadpath import LoadPath
    # a bad default is refused when made; a load path checks its options alike
    with pytest.raises(ValueError, match="petrov_galerkin must be True or False"):
        options_from(p.default_options).replace(petrov_galerkin="yes")
    with pytest.raises(ValueError, match="petrov_galerkin must be True or False"):
        LoadPath.proportional(p, 2).solve(petrov_galerkin="yes")


@pytest.mark.parametrize("level, F", [(5, 0.4), (5, 2.0), (6, 1.0)])
def test_same_solution_with_the_coupling_in_use(level, F):
    p = hertz_problem("triangle", level, F, coulomb_at_zero=True)
    off = p.solve(threads=1)
    on = p.solve(threads=1, petrov_galerkin=True)
    assert off.converged and on.converged
    same_solution(p, off, on)
    pg = on.history["petrov_galerkin"]
    assert on.extra["petrov_galerkin"]["cycles"] == np.count_nonzero(pg) > 0  # the coupling was used
    assert set(np.unique(pg)) <= {0, 1}
    # in every cycle but the first (where nothing slides yet), state changes or not
    assert pg[0] == 0 and np.all(pg[1:] == 1)
    assert abs(on.cycles - off.cycles) <= 2
    # the solve leaves the top coarse level symmetric again: the coupling's term (F K_n entries) is gone
    top = _core.testing.coarse_matrix(p.solver.core, p.hierarchy.levels - 2)
    m = top_matrix(top)
    assert abs(m - m.T).max() <= 1e-12 * abs(m).max()
    _core.testing.rebuild_coarse(p.solver.core)
    assert abs(top_matrix(_core.testing.coarse_matrix(p.solver.core, p.hierarchy.levels - 2)) - m).max() <= 1e-11 * abs(m).max()


def top_matrix(A):
    return sp.bsr_matrix((np.asarray(A.data), np.asarray(A.indices), np.asarray(A.indptr)), shape=A.shape).tocsr()


@pytest.mark.parametrize("ordering", ["coloured", "lexicographic"])
def test_orderings_and_threads_agree(ordering):
    # the overlay is put into the top level as stored (by colours when coloured): the same solution,
    # and the same bits on 1 and 2 threads
    p = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True)
    off = p.solve(threads=1, ordering=ordering)
    one = p.solve(threads=1, ordering=ordering, petrov_galerkin=True)
    two = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True).solve(threads=2, ordering=ordering, petrov_galerkin=True)
    same_solution(p, off, one)
    assert one.extra["petrov_galerkin"]["cycles"] > 0
    fresh = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True).solve(threads=1, ordering=ordering, petrov_galerkin=True)
    assert np.array_equal(np.asarray(fresh.displacement), np.asarray(two.displacement))


def test_problem_default_and_linear_reference():
    p = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True)
    p.default_options = options_from(p.default_options).replace(petrov_galerkin=True)  # forced on a uniform hierarchy
    r = p.solve(threads=1)
    assert r.extra["petrov_galerkin"]["cycles"] > 0
    assert p.solve(threads=1, petrov_galerkin=False).extra.get("petrov_galerkin") is None
    lin = p.solve("linear", threads=1)  # its reference solve takes the problem's choice
    assert lin.converged
    p.solve("tnnmg", threads=1)  # the problem's default does not stop the other methods


def test_laws_without_an_iterate_dependent_bound_ignore_it():
    # frictionless (F = 0) and Tresca: no bound moves with r_n, so no coupling (bound_slope = 0)
    for make in (lambda: hertz_problem("triangle", 5, 0.0), lambda: tresca_problem(5)):
        a, b = make().solve(threads=1), make().solve(threads=1, petrov_galerkin=True)
        assert np.array_equal(np.asarray(a.displacement), np.asarray(b.displacement))
        assert not np.any(b.history["petrov_galerkin"]) and b.extra["petrov_galerkin"]["cycles"] == 0


def tresca_problem(level):
    h = MeshHierarchy.build(hertz_half_disk("triangle"), level, projector=hertz.hertz_projector())
    return Problem(Body(h, Material(hertz.E, hertz.NU), [Dirichlet([HERTZ_TOP], (0.0, hertz.TOP_DISPLACEMENT))],
                        contact_tags=[1]), obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(30.0))


def test_3d_coulomb_same_solution():
    # the d = 3 template: sliding nodes' Hessian blocks update the levels every cycle, the overlay
    # with them. It was refused in 3D while a second solve with it gave run-to-run different bits and
    # once (in CI) another solution: the coarsest solver's low-rank update wrote out of bounds
    # (mg/coarsest_solver.hpp), and a solve began from the levels the one before had left.
    h = sphere.sphere_adaptive_hierarchy(3, friction=0.4)
    for F in (0.1, 0.4):
        p = sphere.sphere_problem("tetra", 3, F, hierarchy=h)
        off = p.solve(threads=1)
        on = p.solve(threads=1, petrov_galerkin=True)
        assert off.converged and on.converged
        same_solution(p, off, on, rtol=1e-9)
        assert on.extra["petrov_galerkin"]["cycles"] > 0
        assert abs(on.cycles - off.cycles) <= 2
        # the same bits as a fresh problem's solve with it, and again after it
        fresh = sphere.sphere_problem("tetra", 3, F, hierarchy=h).solve(threads=1, petrov_galerkin=True)
        assert np.array_equal(np.asarray(fresh.displacement), np.asarray(on.displacement))
        assert np.array_equal(np.asarray(p.solve(threads=1, petrov_galerkin=True).displacement), np.asarray(on.displacement))


@pytest.fixture(scope="module")
def adaptive7():
    return hertz_adaptive_hierarchy(7, 0.4)


def test_fallback_refuses_a_growing_cycle(adaptive7):
    # adaptive level 7 at F = 8: two isolated sliding nodes at the contact edge, where the coupling's
    # oblique coarse correction amplifies their mode (0006-petrov-galerkin-coupling: two-grid
    # 1.94 against 0.64); a cycle with it grows and is refused
    p = hertz_problem("triangle", 7, 8.0, coulomb_at_zero=True, hierarchy=adaptive7)
    off = p.solve(threads=1, petrov_galerkin=False)
    on = p.solve(threads=1, petrov_galerkin=True)
    pg = on.history["petrov_galerkin"]
    k = on.extra["petrov_galerkin"]["fallback_cycle"]
    assert k is not None and pg[k - 1] == 2
    assert not np.any(pg[k:])  # off for the rest of the solve
    c = on.history["correction_norm"]
    assert c[k - 1] >= c[:k - 1].min()  # what the test refused
    # refused: the energy after that cycle is the one before it (the iterate went back), to the
    # round-off of A u, which the cycles update and the refusal forms anew (1.4e-13 relative here)
    e = on.history["energy"]
    assert e[k - 1] == pytest.approx(e[k - 2], rel=1e-12, abs=0)
    assert on.converged
    same_solution(p, off, on)
    assert on.cycles <= off.cycles + 2


def test_fallback_judges_cycles_with_a_state_change(adaptive7):
    # adaptive level 7 at F = 20: the first coupled cycle (the second) also changes the contact state
    # and does not shrink the correction. Before, such a cycle was not judged (the Anderson
    # restart test returned first); now it is refused like any other: the iterate goes back (the
    # energy is the cycle before's), the cycle reports the smallest step before it (a refused step
    # that grew by 1e10 read as divergence), and the solve goes on without the coupling.
    p = hertz_problem("triangle", 7, 20.0, coulomb_at_zero=True, hierarchy=adaptive7)
    r = p.solve(threads=1)
    assert r.converged, r.status
    assert contact_conditions(p, r)["max"] <= 1e-8
    pg, h = np.asarray(r.history["petrov_galerkin"]), r.history
    k = int(np.nonzero(pg == 2)[0][0])
    assert h["rebuilt"][k] and not np.any(pg[k + 1:])
    assert h["energy"][k] == h["energy"][k - 1]
    assert h["correction_norm"][k] == min(h["correction_norm"][:k])
    assert r.extra["petrov_galerkin"]["fallback_cycle"] == k + 1
