"""The compiled long accumulator of the exact sums against the numpy reference and exact rational
arithmetic: the same integer T (sum = T * 2^_E_MIN) on data spanning the whole double range, the
correctly rounded result, independence of the order, the node dots of the cycle, and the errors of
bad input."""
import math
from fractions import Fraction

import numpy as np
import pytest

from contactmg import _core
from contactmg.distributed import exact_dot, exact_sum
from contactmg.distributed.exchange import (_E_MIN, _numpy_fixed_point_dot, _numpy_fixed_point_sum,
                                            local_fixed_point_dot, local_fixed_point_sum, local_node_dot, node_dots)

TINY = 5e-324                      # the smallest subnormal
BIG = np.finfo(float).max


def wide(rng, n, low=-1074, high=1023):
    """Random doubles of random sign with exponents spread over [low, high), some subnormal, some ±0."""
    x = rng.uniform(1, 2, n) * np.exp2(rng.integers(low, high, n).astype(float))
    x[rng.random(n) < 0.5] *= -1
    x[rng.random(n) < 0.05] = 0.0
    x[rng.random(n) < 0.05] = -0.0
    sub = rng.random(n) < 0.1
    x[sub] = rng.integers(-2**52, 2**52, int(sub.sum())) * TINY  # subnormals (and a few more ±0)
    return x


def exact(T):
    return Fraction(T) * Fraction(2) ** _E_MIN


def test_the_core_gives_the_reference_integer_over_the_whole_double_range():
    rng = np.random.default_rng(11)
    for n in (1, 7, 255, 256, 257, 3000, 50_000):
        x, y = wide(rng, n), wide(rng, n)
        assert local_fixed_point_sum(x) == _numpy_fixed_point_sum(x)
        # products from 2^-2148 to near 2^2048: beyond a double, exact as integers
        assert local_fixed_point_dot(x, y) == _numpy_fixed_point_dot(x, y)
    for low, high in ((-1074, -1000), (-30, 30), (900, 1023)):
        x, y = wide(rng, 2000, low, high), wide(rng, 2000, low, high)
        assert local_fixed_point_sum(x) == _numpy_fixed_point_sum(x)
        assert local_fixed_point_dot(x, y) == _numpy_fixed_point_dot(x, y)


def test_extreme_terms_are_exact():
    cases = [[TINY], [-TINY], [BIG], [-BIG], [BIG, BIG, -BIG], [1e300, 1.0, -1e300], [0.0, -0.0],
             [2.2250738585072014e-308, -2.225073858507201e-308], [-1.0] * 1000]
    for c in cases:
        x = np.array(c)
        T = local_fixed_point_sum(x)
        assert T == _numpy_fixed_point_sum(x)
        assert exact(T) == sum(map(Fraction, c))
    assert exact_sum(np.array([1e300, 1.0, -1e300])) == 1.0
    assert exact_sum(np.array([BIG, BIG, -BIG])) == BIG
    # the smallest and the largest products, and products that underflow or overflow a double
    for a, b in ((TINY, TINY), (-TINY, 0.5), (BIG, BIG), (-BIG, BIG), (1e-200, 1e-200), (1e200, -1e200),
                 (3e-310, 7e-5), (1.5, -0.0)):
        T = local_fixed_point_dot(np.array([a]), np.array([b]))
        assert T == _numpy_fixed_point_dot(np.array([a]), np.array([b]))
        assert exact(T) == Fraction(a) * Fraction(b)
    assert exact_dot(np.array([1e200, 1.0, -1e200]), np.array([1e100, 3.0, 1e100])) == 3.0


def test_carries_of_many_equal_full_mantissas():
    """Every term with the largest mantissa at one exponent: each chunk takes its largest load
    between carry propagations."""
    m = 2.0 - 2.0 ** -52
    for n in (255, 256, 257, 100_000):
        for e in (-1074, -60, 0, 1, 31, 32, 1000):
            x = np.full(n, math.ldexp(m, e) if e > -1074 else TINY)
            assert exact(local_fixed_point_sum(x)) == n * Fraction(float(x[0]))
            assert exact(local_fixed_point_sum(-x)) == -n * Fraction(float(x[0]))
        y = np.full(n, -m * 2.0 ** 500)
        assert exact(local_fixed_point_dot(y, y)) == n * Fraction(float(y[0])) ** 2
        assert exact(local_fixed_point_dot(y, -y)) == -n * Fraction(float(y[0])) ** 2


def test_sums_are_correctly_rounded():
    rng = np.random.default_rng(12)
    for scale in (1, 60, 1000):
        x = rng.standard_normal(5000) * np.exp2(rng.integers(-scale, min(scale, 1000), 5000).astype(float))
        x[1::2] = -x[0:-1:2] * (1 + 2.0 ** -40)                # heavy cancellation
        assert exact_sum(x) == math.fsum(x)
    x = wide(rng, 300, -600, 400)
    y = wide(rng, 300, -600, 400)
    want = sum(Fraction(a) * Fraction(b) for a, b in zip(x.tolist(), y.tolist()))
    assert exact(local_fixed_point_dot(x, y)) == want
    assert exact_dot(x, y) == float(want)


def test_the_integer_does_not_depend_on_the_order():
    rng = np.random.default_rng(13)
    x, y = wide(rng, 5000), wide(rng, 5000)
    s, d = local_fixed_point_sum(x), local_fixed_point_dot(x, y)
    for _ in range(3):
        p = rng.permutation(len(x))
        assert local_fixed_point_sum(x[p]) == s
        assert local_fixed_point_dot(x[p], y[p]) == d
        assert local_fixed_point_dot(y[p], x[p]) == d
    # split into pieces (as over ranks) and added as integers: the same T
    assert sum(local_fixed_point_sum(part) for part in np.array_split(x, 7)) == s
    assert local_fixed_point_sum(x.reshape(50, 100)) == s
    assert local_fixed_point_sum(np.zeros(0)) == 0 and local_fixed_point_dot(np.zeros(0), np.zeros(0)) == 0


def test_bad_input_is_refused_with_a_clear_message():
    with pytest.raises(ValueError, match=r"the array has a non-finite entry \(nan at index 2\)"):
        local_fixed_point_sum(np.array([1.0, 2.0, np.nan]))
    with pytest.raises(ValueError, match=r"the array has a non-finite entry \(-inf at index 0\)"):
        _core.exact_sum_limbs(np.array([-np.inf]))
    with pytest.raises(ValueError, match=r"the second array has a non-finite entry \(inf at index 1\)"):
        local_fixed_point_dot(np.ones(3), np.array([0.0, np.inf, 1.0]))
    with pytest.raises(ValueError, match=r"the first array has a non-finite entry \(nan"):
        exact_dot(np.array([np.nan]), np.array([0.0]))
    with pytest.raises(ValueError, match=r"one length.*\(2,\) and \(3,\)"):
        exact_dot(np.ones(2), np.ones(3))
    with pytest.raises(ValueError, match="one length"):
        _core.exact_dot_limbs(np.ones((2, 3)), np.ones(6))


def test_a_dot_over_flagged_rows_is_the_dot_of_those_rows():
    rng = np.random.default_rng(14)
    x, y = wide(rng, 3000, -40, 40).reshape(-1, 3), wide(rng, 3000, -40, 40).reshape(-1, 3)
    rows = (rng.random(1000) < 0.7).astype(np.uint8)
    keep = rows.astype(bool)
    assert local_fixed_point_dot(x, y, rows) == _numpy_fixed_point_dot(x[keep], y[keep])
    assert exact_dot(x, y, rows=rows) == exact_dot(x[keep], y[keep])
    with pytest.raises(ValueError, match="one flag per row"):
        local_fixed_point_dot(x, y, rows[:-1])


@pytest.mark.parametrize("width", [1, 2, 3])
def test_a_node_dot_sums_the_node_values_exactly(width):
    """node_dots: each flagged node's products summed left to right in double (numpy's
    (x * y).sum(axis=1)), those values summed exactly (math.fsum), whatever the split into ranks."""
    rng = np.random.default_rng(20 + width)
    n = 2000
    x, y = wide(rng, n * width, -60, 60).reshape(n, width), wide(rng, n * width, -60, 60).reshape(n, width)
    rows = (rng.random(n) < 0.6).astype(np.uint8)
    values = (x * y).sum(axis=1)[rows.astype(bool)]
    assert exact(local_node_dot(x, y, rows)) == sum(Fraction(v) for v in values)
    assert node_dots([(x, y)], rows=rows)[0] == math.fsum(values)
    # the flagged nodes in two parts (as on two ranks): the same integer
    part = np.zeros(n, np.uint8)
    part[: n // 3] = 1
    assert local_node_dot(x, y, rows & part) + local_node_dot(x, y, rows & (1 - part)) == local_node_dot(x, y, rows)
    # an integer combination of node dots is rounded once: x.y - 2 y.x = -x.y
    assert node_dots([[(1, x, y), (-2, y, x)]], rows=rows)[0] == -math.fsum(values)


def test_a_node_dot_refuses_bad_input():
    with pytest.raises(ValueError, match=r"product at node 1 is not finite \(nan\)"):
        local_node_dot(np.array([[1.0, 2.0], [np.nan, 0.0]]), np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"product at node 0 is not finite \(inf\)"):
        local_node_dot(np.array([[1e300, 0.0]]), np.array([[1e300, 1.0]]))
    with pytest.raises(ValueError, match=r"one shape \(nodes, components\)"):
        _core.exact_node_dot_limbs(np.ones((2, 3)), np.ones((3, 2)))
    with pytest.raises(ValueError, match="one flag per node"):
        local_node_dot(np.ones((4, 2)), np.ones((4, 2)), np.ones(3, np.uint8))
