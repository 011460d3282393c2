"""Load paths on the Hertz benchmark with the incremental Coulomb law: one cold solve (the
problem's single step from u = 0) against a path of --normal-steps equal increments of the normal
loading followed by --shear-steps increments of a tangential move of the top by --shear
(Cattaneo-Mindlin), every step warm-started from the previous one; with --cold the same path
again with every step started from u = 0 (the cycles the warm start saves). Per step: load
parameter, cycles (warm, cold), stick and contact half-widths, slip nodes, seconds; and the path's
time against the cold single solve (a 20-step path should cost less than 20 cold solves).

    python benchmarks/methods/load_path.py [--level 8] [--normal-steps 10] [--shear-steps 10]
        [--shear 0.002] [--cold] [--quick] [--json PATH]
"""
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg.mesh.generators import HERTZ_TOP  # noqa: E402
from contactmg.examples.hertz import TOP_DISPLACEMENT, hertz_problem  # noqa: E402
from contactmg.solve.loadpath import two_phase_path  # noqa: E402


def main():
    ap = parser(__doc__)
    ap.add_argument("--level", type=int, default=8)
    ap.add_argument("--friction", type=float, default=0.4)
    ap.add_argument("--normal-steps", type=int, default=10)
    ap.add_argument("--shear-steps", type=int, default=10)
    ap.add_argument("--shear", type=float, default=0.002)
    ap.add_argument("--tol", type=float, default=1e-11)
    ap.add_argument("--cold", action="store_true", help="also solve every step from u = 0")
    a = ap.parse_args()
    if a.quick:
        a.level, a.normal_steps, a.shear_steps, a.cold = 3, 3, 3, True
    t0 = time.perf_counter()
    p = hertz_problem("triangle", a.level, a.friction)
    p.solver.core
    setup = time.perf_counter() - t0
    single = p.solve(tol=a.tol)
    print(f"level {a.level}: {2 * p.mesh.num_points} dofs, setup {setup:.2f} s; cold single solve {single.cycles} cycles "
          f"{single.solve_seconds:.2f} s (load average {os.getloadavg()[0]:.1f})")
    path = two_phase_path(p, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), a.normal_steps, (a.shear, 0.0), a.shear_steps)
    warm = path.solve(tol=a.tol)
    cold = path.solve(tol=a.tol, warm_start=False) if a.cold else None
    rows = warm.summary()
    for k, row in enumerate(rows):
        row["cold_cycles"] = cold.steps[k].cycles if cold else None
    print(f"{'step':>4} {'t':>6} {'cycles':>6} {'cold':>5} {'stick hw':>9} {'contact hw':>10} {'slip':>5} {'seconds':>8}")
    for row in rows:
        print(f"{row['step']:4d} {row['parameter']:6.3f} {row['cycles']:6d} {str(row['cold_cycles'] or '-'):>5} "
              f"{row['stick_halfwidth']:9.5f} {row['contact_halfwidth']:10.5f} {row['slip_nodes']:5d} "
              f"{row['solve_seconds'] + row['build_seconds']:8.2f}")
    ratio = warm.seconds / single.solve_seconds
    print(f"path of {len(rows)} steps: {sum(warm.cycles)} cycles, {warm.seconds:.2f} s = {ratio:.2f} cold single solves "
          f"(target < {len(rows)}); builds {sum(r['build_seconds'] for r in rows):.2f} s"
          + (f"; cold steps {sum(cold.cycles)} cycles, {cold.seconds:.2f} s" if cold else ""))
    write_result(__file__, a, {"level": a.level, "dofs": 2 * p.mesh.num_points, "friction": a.friction,
                               "setup_seconds": setup, "single_cycles": single.cycles,
                               "single_seconds": single.solve_seconds, "path_seconds": warm.seconds,
                               "path_over_single": ratio, "steps": rows,
                               "cold_path_seconds": cold.seconds if cold else None,
                               "load_average": os.getloadavg()[0]})


if __name__ == "__main__":
    main()
