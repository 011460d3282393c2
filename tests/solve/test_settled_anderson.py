"""The Anderson mixing of settled cycles (cpp/steps/settled_anderson.hpp) keeps its history in
kDepth slots of two vectors, the new pair formed over the last iterate and the last iterate over
the oldest pair. The iterates must be those of the textbook layout, computed here
independently with numpy: history lists of dx, dg, the oldest dropped at depth 3, a restart when
the mixed step did not lower |G(x) - x|, a refused candidate leaving G(x)."""
import numpy as np
import pytest

from contactmg import _core

DEPTH = 3


def apply(M, x, c):
    """diag(M, M, ...) x + c, as the core's test hook applies it"""
    return (x.reshape(-1, M.shape[0]) @ M.T).ravel() + c


def textbook(M, c, x0, steps, refuse_every=0):
    dx, dg = [], []
    last = None
    accelerated, last_gnorm, calls = False, 0.0, 0
    x = x0.copy()
    out, mixed = [], []
    for _ in range(steps):
        gx = apply(M, x, c)
        g = gx - x
        gnorm = g @ g
        if last is not None and accelerated and not gnorm < last_gnorm:
            dx, dg, last = [], [], None
        if last is not None:
            if len(dx) == DEPTH:
                dx.pop(0), dg.pop(0)
            dx.append(x - last[0])
            dg.append(g - last[1])
        last, last_gnorm, accelerated = (x.copy(), g.copy()), gnorm, False
        if dx and gnorm != 0:
            G = np.array(dg)
            gamma = np.linalg.lstsq(G @ G.T, G @ g, rcond=None)[0]
            cand = gx - sum(gm * (a + b) for gm, a, b in zip(gamma, dx, dg))
            calls += 1
            if refuse_every <= 0 or calls % refuse_every != 0:
                gx, accelerated = cand, True
        x = gx
        out.append(x.copy())
        mixed.append(accelerated)
    return np.array(out), np.array(mixed)


def affine_map(m, reps, seed):
    """a symmetric contraction on blocks of m entries (spectrum in [0.18, 0.9]), repeated reps times"""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((m, m)))
    M = Q @ np.diag(0.9 * rng.uniform(0.2, 1.0, m)) @ Q.T
    return M, rng.standard_normal(m * reps), rng.standard_normal(m * reps)


@pytest.mark.parametrize("refuse_every", [0, 3])
@pytest.mark.parametrize("reps", [1, 400])  # one chunk of the fixed-chunk sums, and several
def test_slot_storage_gives_the_textbook_iterates(reps, refuse_every):
    M, c, x0 = affine_map(40, reps, 1)
    steps = 9
    xs, mixed = _core.testing.anderson_iterates(M, c, x0, steps, refuse_every)
    ref, ref_mixed = textbook(M, c, x0, steps, refuse_every)
    assert mixed.astype(bool).tolist() == ref_mixed.tolist()
    assert mixed.sum() >= 4  # the history was full (depth 3) and its slots rotated
    assert np.abs(xs - ref).max() <= 1e-9 * np.abs(ref).max()


def test_two_threads_mix_bit_for_bit():
    M, c, x0 = affine_map(40, 600, 2)  # 24,000 entries: several chunks of the sums
    a, ma = _core.testing.anderson_iterates(M, c, x0, 8, 0, threads=1)
    b, mb = _core.testing.anderson_iterates(M, c, x0, 8, 0, threads=2)
    assert np.array_equal(a, b) and np.array_equal(ma, mb)
