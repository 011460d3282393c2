"""Issue 15: every colour of a level stored by colours in the level's locality order (renumbering.hpp), and
the coarse sweeps' range kernel (mg/level_smoothers.hpp). What goes in and out stays in the user's
numbering, the result does not depend on the thread count, the kernel gives the per-row path's bits,
and the coloured method stays as fast to converge as before."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.cylinders import cylinders_problem
from contactmg.hertz import hertz_problem
from contactmg.sphere import sphere_problem


class _switch:
    def __init__(self, fn, on):
        self.fn, self.on = fn, on

    def __enter__(self):
        self.old = self.fn(self.on)

    def __exit__(self, *exc):
        self.fn(self.old)


def _built(make, locality=True, storage="coloured"):
    # the setting is read when the core solver is built
    with _switch(_core._locality_order, locality):
        p = make()
        p.default_ordering = storage
        p.solver
    return p


def _solve(make, generic, **kw):
    p = _built(make)
    with _switch(_core._level_sweep_generic, generic):
        return p.solve(kw.pop("method", "nmg"), ordering="coloured", **kw)


CASES = {
    "hertz-L6": lambda: hertz_problem("triangle", 6, 0.4),
    "hertz-L5-F5": lambda: hertz_problem("triangle", 5, 5.0),
    "sphere-hex-L2": lambda: sphere_problem(levels=2, friction=0.4),
    "sphere-tetra-L2": lambda: sphere_problem(cell="tetra", levels=2, friction=0.4),
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("threads", [1, 2])
def test_coarse_range_kernel_equals_the_per_row_sweep_bit_for_bit(case, threads):
    # whole solves: every coarse level's projected and plain sweeps, bounded rows included
    a = _solve(CASES[case], True, threads=threads)
    b = _solve(CASES[case], False, threads=threads)
    assert a.converged and b.converged and a.cycles == b.cycles
    assert np.array_equal(a.displacement, b.displacement)
    assert np.array_equal(a.history["correction_norm"], b.history["correction_norm"])


def test_coarse_range_kernel_in_tnnmg_bit_for_bit():
    make = lambda: hertz_problem("triangle", 5, 0.4)
    a = _solve(make, True, method="tnnmg", threads=2)
    b = _solve(make, False, method="tnnmg", threads=2)
    assert a.converged and a.cycles == b.cycles and np.array_equal(a.displacement, b.displacement)


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 6, 0.4), lambda: cylinders_problem(levels=4, friction=0.4)],
                         ids=["hertz-L6", "two-bodies-L4"])
def test_locality_order_two_threads_give_the_one_thread_result_bit_for_bit(make):
    # two bodies: two components of the block graph, a wavefront each
    r1 = _built(make).solve("nmg", threads=1)
    r2 = _built(make).solve("nmg", threads=2)
    assert r1.converged and r1.cycles == r2.cycles
    assert np.array_equal(r1.displacement, r2.displacement)
    assert np.array_equal(r1.history["correction_norm"], r2.history["correction_norm"])


def test_locality_order_keeps_the_users_numbering():
    make = lambda: hertz_problem("triangle", 5, 0.4)
    old, new = _built(make, False), _built(make, True)
    So, Sn = old.solver, new.solver
    for get in [lambda S: S.fine_matrix()] + [lambda S, l=l: S.coarse_matrix(l) for l in range(So.num_levels - 1)]:
        Mo, Mn = get(So), get(Sn)
        assert np.array_equal(Mo.indptr, Mn.indptr) and np.array_equal(Mo.indices, Mn.indices)
        assert np.abs(Mo.data - Mn.data).max() <= 1e-13 * np.abs(Mo.data).max()
    a, b = old.solve("nmg", ordering="coloured"), new.solve("nmg", ordering="coloured")
    assert a.converged and b.converged and a.cycles == b.cycles
    scale = np.abs(a.displacement).max()
    assert np.abs(a.displacement - b.displacement).max() <= 1e-10 * scale
    assert np.array_equal(a.node_state, b.node_state)
    # u0 in the user's numbering: the solution itself is a fixed point of the locality-ordered cycle
    c = new.solve("nmg", ordering="coloured", u0=b.displacement)
    assert c.cycles <= 2 and np.abs(c.displacement - b.displacement).max() <= 1e-10 * scale


@pytest.mark.parametrize("level, F", [(4, 0.4), (6, 0.4), (6, 5.0), (7, 8.0)])
def test_locality_order_keeps_the_colouring(level, F):
    # only the order within a colour changes: the same method, the same cycles, round-off apart
    make = lambda: hertz_problem("triangle", level, F)
    old = _built(make, False).solve("nmg", ordering="coloured")
    new = _built(make, True).solve("nmg", ordering="coloured")
    user = _built(make, True, "lexicographic").solve("nmg", ordering="coloured")  # coloured in the user's storage
    assert old.converged and new.converged and old.cycles == new.cycles == user.cycles
    scale = np.abs(old.displacement).max()
    assert np.abs(new.displacement - old.displacement).max() <= 1e-10 * scale
    assert np.abs(new.displacement - user.displacement).max() <= 1e-10 * scale


def test_the_switches_are_restored():
    assert _core._locality_order() is True and _core._level_sweep_generic() is False
