"""Every colour of a level stored by colours in the level's locality order (cpp/mg/renumbering.hpp). What
goes in and out stays in the user's numbering, the result does not depend on the thread count, and
the coloured method converges as it does on the levels stored in the user's numbering."""
import numpy as np
import pytest

from contactmg.examples.cylinders import cylinders_problem
from contactmg.examples.hertz import hertz_problem
from contactmg import _core
from contactmg.solve.options import options_from


def _built(make, storage="coloured"):
    p = make()
    p.default_options = options_from(p.default_options).replace(ordering=storage)
    p.solver.core
    return p


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
    # against a solver that stores its levels in the user's numbering
    make = lambda: hertz_problem("triangle", 5, 0.4)
    user, new = _built(make, "lexicographic"), _built(make)
    So, Sn = user.solver.core, new.solver.core
    assert Sn.renumbered and not So.renumbered
    for get in [lambda S: _core.testing.fine_matrix(S)] + [lambda S, l=l: _core.testing.coarse_matrix(S, l) for l in range(So.num_levels - 1)]:
        Mo, Mn = get(So), get(Sn)
        assert np.array_equal(Mo.indptr, Mn.indptr) and np.array_equal(Mo.indices, Mn.indices)
        assert np.abs(Mo.data - Mn.data).max() <= 1e-13 * np.abs(Mo.data).max()
    a, b = user.solve("nmg", ordering="coloured"), new.solve("nmg", ordering="coloured")
    assert a.converged and b.converged and a.cycles == b.cycles
    scale = np.abs(a.displacement).max()
    assert np.abs(a.displacement - b.displacement).max() <= 1e-10 * scale
    assert np.array_equal(a.node_state, b.node_state)
    # u0 in the user's numbering: the solution itself is a fixed point of the locality-ordered cycle
    c = new.solve("nmg", ordering="coloured", u0=b.displacement)
    assert c.cycles <= 2 and np.abs(c.displacement - b.displacement).max() <= 1e-10 * scale


@pytest.mark.parametrize("level, F", [(4, 0.4), (6, 0.4), (6, 5.0), (7, 8.0)])
def test_locality_order_keeps_the_colouring(level, F):
    # only the order within a colour differs from the coloured sweep in the user's storage: the
    # same method, the same cycles, round-off apart
    make = lambda: hertz_problem("triangle", level, F)
    new = _built(make).solve("nmg", ordering="coloured")
    user = _built(make, "lexicographic").solve("nmg", ordering="coloured")  # coloured in the user's storage
    assert new.converged and user.converged and new.cycles == user.cycles
    scale = np.abs(new.displacement).max()
    assert np.abs(new.displacement - user.displacement).max() <= 1e-10 * scale
