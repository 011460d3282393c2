"""The fine level's kernels of a distributed cycle and its Anderson mixing, on one process: the step
norm from one pass over the matrix (A (u - old) written or added on the owned rows, and the exact
node sum of (u - old) . A (u - old)), and the serial step's Anderson mixing with node sums
(bind_anderson.cpp) against the textbook iterates, the same bits when its nodes are summed on two
ranks (two threads here, a barrier for the collective) as on one."""
import math
import threading
from fractions import Fraction

import numpy as np
import pytest

from contactmg import _core
from contactmg.distributed import SerialComm
from contactmg.distributed.exchange import _E_MIN, exact_totals
from contactmg.examples.distributed import hertz, sphere
from contactmg.model.friction import Coulomb

from anderson_reference import affine_map, apply, textbook


@pytest.mark.parametrize("example, cell", [(hertz, "triangle"), (sphere, "tetra")])
def test_difference_product_is_the_product_and_its_node_sum(example, cell):
    problem = example(2, cell, Coulomb(0.4), SerialComm())
    fine = problem.fine
    n, d = len(fine.level.gid), fine.d
    rng = np.random.default_rng(3)
    u, old = rng.standard_normal((n, d)), rng.standard_normal((n, d))
    rows = (rng.random(n) < 0.7).astype(np.uint8)  # as owned rows
    keep = rows.astype(bool)
    want = fine.core.multiply(u - old, 1)
    out = np.full((n, d), 7.0)
    total = fine.core.difference_product(u, old, out, rows)
    assert np.array_equal(out[keep], want[keep]) and np.all(out[~keep] == 7.0)  # the other rows untouched
    values = ((u - old) * want).sum(axis=1)[keep]
    assert Fraction(total) * Fraction(2) ** _E_MIN == sum(Fraction(v) for v in values)
    assert exact_totals([total])[0] == math.fsum(values)
    # add: A u kept current as u moves
    Au = fine.core.multiply(old, 1)
    fine.core.difference_product(u, old, Au, rows, add=True)
    assert np.allclose(Au[keep], fine.core.multiply(u, 1)[keep], rtol=0, atol=1e-12 * np.abs(want).max())
    with pytest.raises(ValueError, match="out has"):
        fine.core.difference_product(u, old, np.zeros((n - 1, d)), rows)
    with pytest.raises(ValueError, match="iterate is no longer finite"):
        bad = u.copy()
        bad[np.flatnonzero(keep)[0], 0] = np.nan
        fine.core.difference_product(bad, old, out, rows)


@pytest.mark.parametrize("example, cell", [(hertz, "triangle"), (sphere, "hexahedron")])
def test_the_fine_residual_formed_in_the_restriction_is_the_residual_pass(example, cell):
    """restrict_fine_residual (f - A u formed in the restriction's pass where not known) against
    restrict_residual of a residual pass: the same bits, with and without the mask."""
    problem = example(2, cell, Coulomb(0.4), SerialComm())
    fine = problem.fine
    n, d = len(fine.level.gid), fine.d
    rng = np.random.default_rng(8)
    u = rng.standard_normal((n, d))
    f = fine.core.load
    every = np.arange(n, dtype=np.int64)
    full = fine.core.residual(u, every)
    known = (rng.random(n) < 0.3).astype(np.uint8)
    r = np.where(known[:, None] > 0, full, 1e300)  # only the known rows are read
    from contactmg.distributed.cycle import DistributedMonotoneStep
    from contactmg.distributed.problem import resolve
    from contactmg.solve.options import SolverOptions
    step = DistributedMonotoneStep(problem.comm, fine, problem.hierarchy, resolve(SolverOptions(), problem.hierarchy.cell_type))
    T = step.coarse.fine_transfer
    mask = (rng.random(n * d) < 0.8).astype(np.uint8)
    for m in (None, mask):
        want = T.restrict_residual(full, m)
        got = T.restrict_fine_residual(fine.core.matrix, u, f, r, known, m)
        assert np.array_equal(got, want)
    with pytest.raises(ValueError, match="known has shape"):
        T.restrict_fine_residual(fine.core.matrix, u, f, r, known[:-1])


def run_node_anderson(M, c, x0, steps, width, flags, refuse_every, combine):
    """The iterates x <- mix(M x + c) of NodeAnderson (the nodes of `flags` summed here)."""
    A = _core.NodeAnderson(flags, width, combine)
    x, calls, out, mixed = x0.reshape(-1, width).copy(), [0], [], []

    def admit(y, plain):
        calls[0] += 1
        return refuse_every <= 0 or calls[0] % refuse_every != 0

    for _ in range(steps):
        gx = apply(M, x.ravel(), c).reshape(-1, width)
        mixed.append(A.step(x, gx, admit))
        x = gx
        out.append(x.ravel().copy())
    assert A.memory_bytes() > 0
    return np.array(out), np.array(mixed)


@pytest.mark.parametrize("refuse_every", [0, 3])
def test_node_anderson_gives_the_textbook_iterates(refuse_every):
    M, c, x0 = affine_map(40, 50, 1)
    nodes = len(c) // 2
    xs, mixed = run_node_anderson(M, c, x0, 9, 2, np.ones(nodes, np.uint8), refuse_every, exact_totals)
    ref, ref_mixed = textbook(M, c, x0, 9, refuse_every)
    assert mixed.tolist() == ref_mixed.tolist() and mixed.sum() >= 4
    assert np.abs(xs - ref).max() <= 1e-9 * np.abs(ref).max()


def test_node_anderson_on_two_ranks_is_bitwise_one_rank():
    """Each 'rank' sums its own nodes (alternate blocks of them); the combine of both is their
    integers added, as the allgather does: every iterate is one rank's, bit for bit."""
    M, c, x0 = affine_map(30, 40, 5)
    width, nodes = 3, len(c) // 3
    one, one_mixed = run_node_anderson(M, c, x0, 8, width, np.ones(nodes, np.uint8), 0, exact_totals)
    mine = (np.arange(nodes) // 7 % 2).astype(np.uint8)
    barrier, posted, results = threading.Barrier(2), [None, None], [None, None]

    def rank(r, flags):
        def combine(totals):
            posted[r] = list(totals)
            barrier.wait()
            total = [a + b for a, b in zip(*posted)]
            barrier.wait()  # both have read before the next sums are posted
            return exact_totals(total)
        results[r] = run_node_anderson(M, c, x0, 8, width, flags, 0, combine)

    threads = [threading.Thread(target=rank, args=(0, mine)), threading.Thread(target=rank, args=(1, 1 - mine))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    for xs, mixed in results:
        assert np.array_equal(xs, one) and np.array_equal(mixed, one_mixed)
    assert one_mixed.sum() >= 4


def test_node_anderson_refuses_bad_input():
    with pytest.raises(ValueError, match="width must be >= 1"):
        _core.NodeAnderson(np.ones(3, np.uint8), 0, exact_totals)
    A = _core.NodeAnderson(np.ones(3, np.uint8), 2, exact_totals)
    with pytest.raises(ValueError, match="3 nodes of 2 entries"):
        A.step(np.zeros((2, 2)), np.zeros((2, 2)), lambda y, p: True)
