"""Work against precision: the algebraic error ||u^k - u*||_A / ||u*||_A after each cycle against
elapsed seconds, for Algorithm 2 (nmg), TNNMG, Algorithm 1 (fixed point) and the linear reference
(the contact state known in advance), on several levels of the Hertz benchmark (triangles,
F = 0.4). u* is an nmg solve run to round-off (60 cycles); the error evaluation is kept out of the
timings. Per run: cycles, seconds, and the seconds to reach relative errors 1e-6 and 1e-10.

    python benchmarks/methods/work_precision.py [--levels 5 6 7 8] [--friction 0.4]
        [--plot out/work_precision.png] [--quick] [--json PATH]
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

from contactmg.examples import hertz  # noqa: E402

METHODS = ("nmg", "tnnmg", "fixed-point", "linear")


def plot(rows, path, friction):
    """Error against seconds, one colour per method and one line style per level."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 5))
    ax = fig.add_subplot(1, 1, 1)
    colors = dict(zip(METHODS, ("tab:red", "tab:purple", "tab:blue", "tab:green")))
    levels = sorted({r["level"] for r in rows})
    for r in rows:
        ax.loglog(r["time"], r["error"], ["-", "--", ":", "-."][levels.index(r["level"]) % 4], color=colors[r["method"]],
                  label=f"{r['method']}, level {r['level']}")
    ax.set_xlabel("seconds")
    ax.set_ylabel(r"$\|u^k-u^*\|_A / \|u^*\|_A$")
    ax.set_title(f"work against precision, Hertz F = {friction:g}")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)


def main():
    ap = parser(__doc__)
    ap.add_argument("--levels", type=int, nargs="+", default=[5, 6, 7, 8])
    ap.add_argument("--friction", type=float, default=0.4)
    ap.add_argument("--cell", default="triangle", choices=["triangle", "quad"])
    ap.add_argument("--plot", default=None, help="PNG of the curves")
    a = ap.parse_args()
    if a.quick:
        a.levels = [3, 4]
    rows = []
    print(f"{'lvl':>3} {'dofs':>9} {'method':>12} {'cycles':>6} {'seconds':>8} {'s to 1e-6':>10} {'s to 1e-10':>11} "
          f"{'final error':>11}")
    for L in a.levels:
        p = hertz.hertz_problem(a.cell, L, a.friction, coulomb_at_zero=True)
        u_star = p.solve(tol=1e-300, max_cycles=60).displacement
        norm = float(np.sqrt(u_star.ravel() @ p.A.matvec(u_star).ravel()))
        nmg = p.solve(error_reference=u_star)
        runs = {"nmg": nmg, "tnnmg": p.solve("tnnmg", error_reference=u_star),
                "fixed-point": p.solve("fixed-point", error_reference=u_star),
                "linear": p.solve("linear", reference=nmg, error_reference=u_star)}
        for name, r in runs.items():
            e = np.asarray(r.history["error"]) / norm
            t = np.asarray(r.history["seconds"])
            reach = lambda level: float(t[np.argmax(e <= level)]) if np.any(e <= level) else None  # noqa: E731
            row = {"level": L, "dofs": 2 * p.mesh.num_points, "method": name, "cycles": r.cycles,
                   "seconds": r.solve_seconds, "seconds_to_1e-6": reach(1e-6), "seconds_to_1e-10": reach(1e-10),
                   "final_error": float(e[-1]), "error": e.tolist(), "time": t.tolist()}
            rows.append(row)
            fmt = lambda v: f"{v:.3f}" if v is not None else "-"  # noqa: E731
            print(f"{L:3d} {row['dofs']:9d} {name:>12} {r.cycles:6d} {r.solve_seconds:8.3f} "
                  f"{fmt(row['seconds_to_1e-6']):>10} {fmt(row['seconds_to_1e-10']):>11} {row['final_error']:11.2e}",
                  flush=True)
    if a.plot:
        plot(rows, a.plot, a.friction)
    write_result(__file__, a, {"friction": a.friction, "cell": a.cell, "rows": rows})


if __name__ == "__main__":
    main()
