"""Cycle-growth diagnosis: the barycentric prolongation at projected boundary nodes
(contactmg.mesh.hierarchy.boundary_interpolation), the monotone bound restriction through its negative
weights, and the level-independence of the linear multigrid rate on the adaptive Hertz levels."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.mesh.generators import HERTZ_TOP, hertz_half_disk, hertz_projector
from contactmg.mesh.generators_3d import ball_projector, half_ball
from contactmg.examples.hertz import hertz_adaptive_hierarchy
from contactmg.mesh.hierarchy import MeshHierarchy, boundary_interpolation
from contactmg.model.material import Material
from contactmg.model.problem import Body, Dirichlet, Problem
from contactmg.solve.options import with_cycle


def linear_field(points, seed):
    rng = np.random.default_rng(seed)
    d = points.shape[1]
    a, B = rng.standard_normal(d), rng.standard_normal((d, d))
    return a + points @ B.T


def check_linear_fields(h):
    """Every level pair: the barycentric P maps a linear field on the coarse nodes onto the same
    field on the fine nodes, the refinement weights do not at projected nodes."""
    moved_any = False
    for coarse, fine, t in zip(h.meshes, h.meshes[1:], h.transfers):
        tb = boundary_interpolation(coarse, fine.points, t)
        P, Pb = t.matrix(), tb.matrix()
        scale = np.abs(fine.points).max()
        for seed in range(3):
            u_c, u_f = linear_field(coarse.points, seed), linear_field(fine.points, seed)
            assert np.abs(Pb @ u_c - u_f).max() <= 1e-12 * scale * 10
            miss = np.abs(P @ u_c - u_f).max(axis=1)
            moved = np.flatnonzero(miss > 1e-9)
            moved_any = moved_any or len(moved) > 0
            # only rows of moved nodes differ, and they now differ from the midpoint rule
            changed = np.flatnonzero(np.abs(P - Pb).sum(axis=1).A.ravel() > 0)
            assert set(moved) <= set(changed)
        assert np.allclose(np.asarray(Pb.sum(axis=1)).ravel(), 1.0)  # constants (translations)
        # nested: the coarse nodes keep their numbers and are interpolated by themselves
        assert np.array_equal(Pb[:coarse.num_points].toarray(), np.eye(coarse.num_points))
    assert moved_any  # the test would see a prolongation that misses linear fields


def test_barycentric_prolongation_reproduces_linear_fields_on_the_adaptive_half_disk():
    check_linear_fields(hertz_adaptive_hierarchy(5, 0.4))


def test_barycentric_prolongation_reproduces_linear_fields_on_the_projected_ball():
    h = MeshHierarchy.build(half_ball("tetra", k=2, ring_layers=1), 2, projector=ball_projector())
    check_linear_fields(h)


def test_barycentric_prolongation_refuses_non_simplices():
    h = MeshHierarchy.build(hertz_half_disk("quad"), 2, projector=hertz_projector())
    with pytest.raises(ValueError, match="simplices"):
        boundary_interpolation(h.meshes[0], h.meshes[1].points, h.transfers[0])


def test_bound_restriction_keeps_corrections_feasible_through_negative_boundary_weights():
    """A projected node lies outside its coarse cell: one barycentric weight is negative. Any
    coarse correction inside the restricted bounds must still keep every fine dof inside its own."""
    h = MeshHierarchy.build(hertz_half_disk("triangle"), 3, projector=hertz_projector())
    coarse, fine, t = h.meshes[1], h.meshes[2], h.transfers[1]
    tb = boundary_interpolation(coarse, fine.points, t)
    assert tb.weight.min() < 0  # the case under test is present
    rng = np.random.default_rng(1)
    nf, nc = fine.num_points, coarse.num_points
    lo, hi = np.full((nf, 2), -np.inf), np.full((nf, 2), np.inf)
    nodes = np.unique(fine.facets)
    lo[nodes] = -rng.uniform(0, 1, (len(nodes), 2))
    hi[nodes] = rng.uniform(0, 1, (len(nodes), 2))
    hi[nodes[::3], 0] = 0.0  # some bounds tight on one side
    lc, hc = _core.testing.restrict_bounds_2D(nf, nc, tb.ptr, tb.parent, tb.weight, None, lo, hi)
    assert np.all(lc <= 0) and np.all(hc >= 0)
    Pb = tb.matrix()
    finite = np.isfinite(lc) & np.isfinite(hc)
    for k in range(200):
        c = np.where(rng.random((nc, 2)) < 0.5, lc, hc) if k % 2 else rng.uniform(np.where(finite, lc, -1), np.where(finite, hc, 1))
        c = np.clip(np.where(np.isfinite(c), c, rng.standard_normal((nc, 2))), lc, hc)
        w = Pb @ c
        assert np.all(w <= hi + 1e-12) and np.all(w >= lo - 1e-12)


def test_linear_rate_on_the_adaptive_hertz_levels_is_bounded_independently_of_the_level():
    """F(3,3) contraction of the linear multigrid with plain Gauss-Seidel (omega = 1; Dirichlet top,
    zero load, random start) on the adaptive levels 4-8: measured 0.10-0.28, rising towards the asymptotic rate of the smoother
    (0.30 at level 9, 0.34 at level 11, a rectangle's 0.32), not growing without bound."""
    h = hertz_adaptive_hierarchy(8, 0.4)
    rates = []
    for L in range(4, 9):
        q = with_cycle(Problem(Body(h.truncated(L), Material(2000.0, 0.28), [Dirichlet([HERTZ_TOP], (0.0, 0.0))])), "F")
        rng = np.random.default_rng(0)
        q.load = np.zeros_like(q.load)
        r = q.solve(u0=rng.standard_normal(q.load.shape), tol=1e-300, rtol=1e-300, max_cycles=12, omega=1.0)
        c = r.history["correction_norm"]
        rates.append(float(np.exp(np.mean(np.log(c[-5:] / c[-6:-1])))))
    assert max(rates) < 0.4, rates
    assert rates[-1] - rates[-3] < 0.1, rates  # levels 6 -> 8: at most a slow approach to the asymptote
