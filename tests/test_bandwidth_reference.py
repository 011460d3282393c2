"""Issue 15's bandwidth references (cpp/bandwidth.hpp) and the cycle's byte model
(benchmarks/parallel_bandwidth.py). Not timed: the rates are only checked to be rates, the model's
visit counts against the coarse cycle's definition (mg/cycle.hpp)."""
import math
import sys
from pathlib import Path

import pytest

from contactmg import _core

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from parallel_bandwidth import coarse_visits  # noqa: E402


@pytest.mark.parametrize("threads", [1, 2])
def test_reference_kernels_give_rates(threads):
    for streams in (1, 2, 4, 8):
        g = _core.testing.stream_read(1_000_003, 2, threads, streams)  # n not a multiple of the pieces
        assert math.isfinite(g) and g > 0
    for dim in (2, 3):
        g = _core.testing.stream_read_blocks(100_000, 2, threads, dim)
        assert math.isfinite(g) and g > 0
    assert _core.testing.stream_triad(1_000_000, 2, threads) > 0


def test_reference_kernels_refuse_bad_input():
    with pytest.raises(ValueError, match="streams"):
        _core.testing.stream_read(1_000_000, 1, 1, 3)
    with pytest.raises(ValueError, match="dim"):
        _core.testing.stream_read_blocks(1_000_000, 1, 1, 4)
    with pytest.raises(ValueError):
        _core.testing.stream_read(10, 1, 1, 1)


def test_coarse_visits_follow_the_cycle():
    # V: every level once, one residual on every level above the coarsest
    assert coarse_visits(4, "V") == ([1] * 5, [0, 1, 1, 1, 1])
    # W: two visits of level top from the fine level, each level's visit visits the next twice
    s, r = coarse_visits(4, "W")
    assert s == [2 ** (4 - l + 1) for l in range(5)]
    assert r == [0] + [2 * v for v in s[1:]]
    # F: an F- then a V-cycle from the fine level, and from every F visit: level l smoothed
    # top - l + 2 times (the stop-23 model took top - l + 1), residuals on l: top - l + 3
    s, r = coarse_visits(7, "F")
    assert s == [7 - l + 2 for l in range(8)]
    assert r == [0] + [7 - l + 3 for l in range(1, 8)]
