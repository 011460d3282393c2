"""Coloured Gauss-Seidel sweeps on threads. The result does not depend on the thread
count (bit for bit), the coloured order solves the same problem as the lexicographic one in about
as many cycles, and the fine matrix is held once (the core takes the assembled one over)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg import _core
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.solve.options import options_from


def fresh_solve(make, storage=None, **kw):
    # a fresh problem per solve: a solver carries its coarse hierarchy (incrementally updated)
    # from one solve to the next, so only fresh solvers are comparable bit for bit. storage: the
    # ordering the core solver is built for (coloured: its levels stored by colours)
    p = make()
    if storage is not None:
        p.default_options = options_from(p.default_options).replace(ordering=storage)
    return p.solve("nmg", **kw)


@pytest.mark.parametrize("ordering, storage", [("coloured", "coloured"), ("coloured", "lexicographic"),
                                               ("lexicographic", "lexicographic")])
def test_two_threads_give_the_one_thread_result_bit_for_bit_2d(ordering, storage):
    # level 6: 18,721 nodes, above the sizes where loops, colours and the restriction go parallel
    make = lambda: hertz_problem("triangle", 6, 0.4)
    r1 = fresh_solve(make, storage, threads=1, ordering=ordering)
    r2 = fresh_solve(make, storage, threads=2, ordering=ordering)
    assert r1.converged and r2.converged
    assert r1.cycles == r2.cycles
    assert np.array_equal(r1.displacement, r2.displacement)
    assert np.array_equal(r1.history["correction_norm"], r2.history["correction_norm"])
    assert r2.extra["threads"] == (2 if _core.openmp() else 1)


def test_two_threads_give_the_one_thread_result_bit_for_bit_3d():
    make = lambda: sphere_problem(levels=3, friction=0.4)
    r1 = fresh_solve(make, threads=1, ordering="coloured")
    r2 = fresh_solve(make, threads=2, ordering="coloured")
    assert r1.converged and r2.converged
    assert np.array_equal(r1.displacement, r2.displacement)


@pytest.mark.parametrize("levels", [4, 6])
def test_coloured_order_solves_the_same_problem_in_about_as_many_cycles(levels):
    make = lambda: hertz_problem("triangle", levels, 0.4)
    lex = fresh_solve(make, ordering="lexicographic")
    col = fresh_solve(make, ordering="coloured")
    assert lex.converged and col.converged
    assert col.extra["ordering"] == "coloured" and lex.extra["ordering"] == "lexicographic"
    assert col.cycles <= lex.cycles + 2
    # both stop at ||correction||_A <= 1e-11: the solutions agree to far below the discretization
    scale = np.abs(lex.displacement).max()
    assert np.abs(col.displacement - lex.displacement).max() <= 1e-8 * scale
    assert np.array_equal(col.node_state, lex.node_state)


def test_coloured_sweeps_lower_the_energy_and_keep_the_solution():
    p = hertz_problem("triangle", 6, 0.4)
    res = p.solve("nmg", ordering="lexicographic")
    S = p.solver.core
    # a solution is a fixed point of the coloured nonlinear sweep too (every nodal rule keeps it)
    u = _core.testing.smooth(S, res.displacement, 2, ordering="coloured", threads=2)
    assert np.abs(u - res.displacement).max() <= 1e-9 * np.abs(res.displacement).max()
    # from zero, coloured sweeps on 1 and 2 threads agree bit for bit
    z = np.zeros_like(res.displacement)
    assert np.array_equal(_core.testing.smooth(S, z, 3, ordering="coloured", threads=1), _core.testing.smooth(S, z, 3, ordering="coloured", threads=2))
    assert _core.testing.num_colours(S) >= 3  # a triangle mesh couples the three nodes of a cell


def _pair(make):
    """The same problem with a solver in the user's order and one stored by colours."""
    user, by_colours = make(), make()
    user.default_options = options_from(user.default_options).replace(ordering="lexicographic")
    by_colours.default_options = options_from(by_colours.default_options).replace(ordering="coloured")
    assert not user.solver.core.renumbered and by_colours.solver.core.renumbered
    return user, by_colours


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 5, 0.4), lambda: sphere_problem(levels=2, friction=0.4)],
                         ids=["hertz-2d", "sphere-3d"])
def test_storage_by_colours_is_the_coloured_method_in_the_users_numbering(make):
    # Renumbering by colours keeps every colour of the greedy colouring (greedy in colour-major
    # order gives each row its colour again), so the sweeps are the same; only the order of the
    # sums within a row changes: the same cycles, the solution to round-off, in the user's numbering.
    user, by_colours = _pair(make)
    a = user.solve("nmg", ordering="coloured")
    b = by_colours.solve("nmg", ordering="coloured")
    assert a.converged and b.converged and a.cycles == b.cycles
    scale = np.abs(a.displacement).max()
    assert np.abs(a.displacement - b.displacement).max() <= 1e-12 * scale
    assert np.array_equal(a.node_state, b.node_state)
    # the histories agree to the round-off of the sums, measured against the first correction (the
    # Anderson mixing of settled Coulomb cycles amplifies it: 1.2e-15 absolute at a correction of 1.7e-8)
    cn = a.history["correction_norm"]
    np.testing.assert_allclose(cn[:8], b.history["correction_norm"][:8], rtol=1e-8, atol=1e-12 * cn[0])
    np.testing.assert_allclose(b.contact_force, a.contact_force, atol=1e-9 * np.abs(a.contact_force).max())
    # the matrices handed out are in the user's numbering: the same pattern, the same values
    Su, Sc = user.solver.core, by_colours.solver.core
    for get in [lambda S: _core.testing.fine_matrix(S)] + [lambda S, l=l: _core.testing.coarse_matrix(S, l) for l in range(Su.num_levels - 1)]:
        Mu, Mc = get(Su), get(Sc)
        assert np.array_equal(Mu.indptr, Mc.indptr) and np.array_equal(Mu.indices, Mc.indices)
        assert np.abs(Mu.data - Mc.data).max() <= 1e-13 * np.abs(Mu.data).max()
    # the lexicographic order on a solver stored by colours still visits the user's order
    c = by_colours.solve("nmg", ordering="lexicographic")
    d = user.solve("nmg", ordering="lexicographic")
    assert c.cycles == d.cycles and np.abs(c.displacement - d.displacement).max() <= 1e-12 * scale


def test_inputs_in_the_users_numbering_on_a_solver_stored_by_colours():
    # u0, the error reference, the sweep check and the rows to smooth of a coarse level: all in the
    # user's numbering, whatever the storage. Frictionless: the Anderson mixing of settled Coulomb
    # cycles (steps/settled_anderson.hpp) magnifies the round-off of the two storage orders in the
    # intermediate iterates (same cycles and solution to 1e-14, error histories within a few per cent)
    user, by_colours = _pair(lambda: hertz_problem("triangle", 5, 0.0))
    ref = user.solve("nmg", ordering="coloured")
    rng = np.random.default_rng(1)
    u0 = ref.displacement * (1 + 0.01 * rng.standard_normal(ref.displacement.shape))
    a = user.solve("nmg", ordering="coloured", u0=u0, error_reference=ref.displacement)
    b = by_colours.solve("nmg", ordering="coloured", u0=u0, error_reference=ref.displacement)
    assert a.cycles == b.cycles and a.cycles < ref.cycles
    np.testing.assert_allclose(b.history["error"][:4], a.history["error"][:4], rtol=1e-6)
    for S in (user.solver.core, by_colours.solver.core):
        assert np.abs(_core.testing.smooth(S, ref.displacement, 2, ordering="coloured") - ref.displacement).max() <= 1e-9 * np.abs(ref.displacement).max()
    top = user.solver.core.num_levels - 2
    n_top = _core.testing.coarse_matrix(user.solver.core, top).shape[0] // 2
    rows = np.arange(0, n_top, 2, dtype=np.int64)
    for S in (user.solver.core, by_colours.solver.core):
        S.set_rows_to_smooth(top, rows)
    a = user.solve("nmg", ordering="coloured")
    b = by_colours.solve("nmg", ordering="coloured")
    assert a.converged and b.converged and a.cycles == b.cycles
    assert np.abs(a.displacement - b.displacement).max() <= 1e-11 * np.abs(a.displacement).max()
    with pytest.raises(ValueError, match="outside"):
        by_colours.solver.core.set_rows_to_smooth(top, np.array([n_top], np.int64))


def test_the_core_takes_the_matrix_over_and_A_is_assembled_again_on_demand():
    p = hertz_problem("triangle", 4, 0.4)
    x = np.random.default_rng(0).standard_normal((p.mesh.num_points, 2))
    before = p.A.matvec(x)
    p.solve("nmg")
    after = p.A.matvec(x)  # the core took the first one; this one is assembled anew
    assert np.array_equal(before, after)


@pytest.mark.parametrize("kw, word", [({"threads": -1}, "threads"), ({"threads": 1.5}, "threads"),
                                      ({"threads": True}, "threads"), ({"ordering": "zigzag"}, "ordering")])
def test_bad_thread_options_are_refused(kw, word):
    p = hertz_problem("triangle", 3, 0.4)
    with pytest.raises(ValueError, match=word):
        p.solve("nmg", **kw)


def run(*args):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=120)


def test_cli_threads_and_ordering():
    r = run("hertz", "--levels", "4", "--threads", "2", "--ordering", "coloured", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["converged"] and out["ordering"] == "coloured"
    assert out["threads"] == (2 if _core.openmp() else 1)
    bad = run("hertz", "--levels", "4", "--threads", "-1")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "--threads" in bad.stderr.strip().splitlines()[-1]


def test_coloured_sweeps_lower_the_energy_frictionless():
    # frictionless contact minimizes 1/2 u.Au - f.u over the feasible set: each exact nodal
    # minimization lowers it, in any order (after the first sweep has put the Dirichlet values)
    p = hertz_problem("triangle", 6, 0.0)
    S, A, f = p.solver.core, p.A, p.load
    energy = lambda v: 0.5 * float(np.sum(v * A.matvec(v))) - float(np.sum(f * v))
    u = _core.testing.smooth(S, np.zeros((p.mesh.num_points, 2)), 1, ordering="coloured", threads=2)
    e = [energy(u)]
    for _ in range(4):
        u = _core.testing.smooth(S, u, 1, ordering="coloured", threads=2)
        e.append(energy(u))
    assert all(b <= a + 1e-12 * abs(a) for a, b in zip(e, e[1:]))
    assert e[-1] < e[0]
    sol = p.solve("nmg", ordering="coloured")
    assert sol.converged and energy(sol.displacement) <= e[-1]
