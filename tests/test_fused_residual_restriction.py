"""Issue 15, cutting passes: every level's residual is restricted as it is formed, without a
residual vector (mg/transfer.hpp restrict_level_residual; the fine level's in the monotone step,
its contact rows formed first for the linearization). Switched off (_core._fused_residual_restriction),
the cycles form the vector and restrict it as before. The two must give the same bits: the same
rows, sums and order -- on 1 and 2 threads, with the parallel paths of small levels switched on,
for Coulomb (friction gradient added at sliding rows), Tresca (Algorithm 1), 3D and float coarse values."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.hertz import hertz_problem
from contactmg.sphere import sphere_problem


@pytest.fixture
def fused():
    old = _core._fused_residual_restriction()
    yield _core._fused_residual_restriction
    _core._fused_residual_restriction(old)


def solve_both(make, fused, method="nmg", **kw):
    out = []
    for on in (True, False):
        fused(on)
        p = make()  # a fresh problem: a solver carries its coarse hierarchy from one solve to the next
        p.default_ordering = kw.get("ordering", "coloured")
        out.append(p.solve(method, **kw))
    return out


def assert_same(a, b):
    assert a.cycles == b.cycles
    assert np.array_equal(a.displacement, b.displacement)
    assert np.array_equal(a.history["correction_norm"], b.history["correction_norm"])


@pytest.mark.parametrize("ordering", ["coloured", "lexicographic"])
@pytest.mark.parametrize("threads", [1, 2])
def test_fused_equals_unfused_coulomb(fused, ordering, threads):
    a, b = solve_both(lambda: hertz_problem("triangle", 5, 0.4), fused, ordering=ordering, threads=threads)
    assert a.converged and np.any(a.node_state == 2)  # sliding rows: the friction gradient enters r
    assert_same(a, b)


def test_fused_equals_unfused_on_the_parallel_paths(fused):
    old = _core.parallel_grains()
    _core.set_parallel_grains(1, 1)  # every level and colour on both threads
    try:
        a, b = solve_both(lambda: hertz_problem("quad", 4, 0.4), fused, threads=2)
    finally:
        _core.set_parallel_grains(*old)
    assert_same(a, b)


def test_fused_equals_unfused_fixed_point_3d_and_float(fused):
    assert_same(*solve_both(lambda: hertz_problem("triangle", 5, 0.4), fused, method="fixed-point", threads=1))
    assert_same(*solve_both(lambda: sphere_problem("tetra", levels=2, friction=0.4), fused, threads=2))
    old = _core._float_coarse_values(True)
    try:
        assert_same(*solve_both(lambda: hertz_problem("triangle", 5, 0.4), fused, threads=2))
    finally:
        _core._float_coarse_values(old)
