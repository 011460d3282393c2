"""The Anderson mixing of settled cycles (cpp/steps/settled_anderson.hpp) keeps its history in
kDepth slots of two vectors, the new pair formed over the last iterate and the last iterate over
the oldest pair. The iterates must be those of the textbook layout, computed here
independently with numpy: history lists of dx, dg, the oldest dropped at depth 3, a restart when
the mixed step did not lower |G(x) - x|, a refused candidate leaving G(x)."""
import numpy as np
import pytest

from contactmg import _core

from anderson_reference import affine_map, textbook


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
