"""Seconds of the exact sums' local accumulation: the compiled long accumulator
(contactmg._core.exact_sum_limbs / exact_dot_limbs, what exact_sum and exact_dot use) against the
numpy reference of the same integer and against the rounded np.sum / np.dot, on standard normal
vectors, one core. Each time is the best of several runs; `same` says the core's integer is the
reference's.

    python benchmarks/performance/exact_sums.py [--sizes 100000 1000000] [--repeat 5] [--quick] [--json PATH]
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg import _core  # noqa: E402
from contactmg.distributed.exchange import _numpy_fixed_point_dot, _numpy_fixed_point_sum  # noqa: E402


def best(f, repeat):
    """(the fastest of `repeat` calls of f in seconds, f's value)."""
    t = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        v = f()
        t = min(t, time.perf_counter() - t0)
    return t, v


def main():
    ap = parser(__doc__)
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    sizes, repeat = ([10_000, 100_000], 2) if a.quick else (a.sizes, a.repeat)
    rng = np.random.default_rng(1)
    rows = []
    for n in sizes:
        x, y = rng.standard_normal(n), rng.standard_normal(n)
        for kind, ref, core, plain in (
                ("sum", lambda: _numpy_fixed_point_sum(x), lambda: _core.exact_sum_limbs(x), lambda: np.sum(x)),
                ("dot", lambda: _numpy_fixed_point_dot(x, y), lambda: _core.exact_dot_limbs(x, y), lambda: np.dot(x, y))):
            t_ref, v_ref = best(ref, max(1, min(repeat, 3)))
            t_core, v_core = best(core, repeat)
            t_plain, _ = best(plain, repeat)
            rows.append({"kind": kind, "n": n, "numpy_reference_s": t_ref, "core_s": t_core, "numpy_rounded_s": t_plain,
                         "core_ns_per_term": 1e9 * t_core / n, "speedup": t_ref / t_core, "same": v_ref == v_core})
    print(f"{'kind':>4} {'n':>9} {'numpy ref s':>12} {'core s':>10} {'np.sum/dot s':>13} {'core ns/term':>13} {'speedup':>8}")
    for r in rows:
        print(f"{r['kind']:>4} {r['n']:>9} {r['numpy_reference_s']:>12.4f} {r['core_s']:>10.5f} {r['numpy_rounded_s']:>13.6f} "
              f"{r['core_ns_per_term']:>13.2f} {r['speedup']:>8.0f}" + ("" if r["same"] else "  DIFFERENT INTEGER"))
    write_result(__file__, a, {"rows": rows})
    return 0 if all(r["same"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
