"""Bandwidth references (cpp/base/bandwidth.hpp) and the cycle's byte model
(benchmarks/performance/threads.py). Not timed: the rates are only checked to be rates, the model's
visit counts against the coarse cycle's definition (mg/cycle.hpp)."""
import math

import pytest

from contactmg import _core


def coarse_visits(top: int, cycle: str) -> tuple:
    """How often a coarse correction (mg/cycle.hpp) smooths each coarse level 0 .. top (level 0 is
    solved instead) and forms its residual, restricts it and prolongates back (levels 1 .. top). A
    W- or F-cycle visits level top a second time from the fine level, and each visit of a level of a
    W/F-cycle visits the next coarser level twice (F: an F- then a V-cycle). The same count as the
    byte model of benchmarks/performance/threads.py."""
    smooth, resid = [0] * (top + 1), [0] * (top + 1)

    def visit(l, t):
        smooth[l] += 1
        if l == 0:
            return
        for v in range(1 if t == "V" else 2):
            resid[l] += 1
            visit(l - 1, "V" if (t == "F" and v == 1) else t)

    visit(top, cycle)
    if cycle != "V":
        visit(top, "V" if cycle == "F" else "W")
    return smooth, resid


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
