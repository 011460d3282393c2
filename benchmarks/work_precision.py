"""Work against precision: the algebraic error ||u^k - u*||_A / ||u*||_A after each cycle against
elapsed seconds, for nmg (Algorithm 2), fixed-point (Algorithm 1) and the linear reference, on
several levels (Hertz, triangles, F = 0.4). u* is an nmg solve run to round-off (60 cycles). The
error evaluation is kept out of the timings.

    python benchmarks/work_precision.py [--levels 5 6 7] [--out out]
"""
import argparse
import json
import os

import numpy as np

from contactmg import hertz


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, nargs="+", default=[5, 6, 7, 8])
    ap.add_argument("--friction", type=float, default=0.4)
    ap.add_argument("--cell", default="triangle")
    ap.add_argument("--out", default="out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    colors = {"nmg": "tab:red", "fixed-point": "tab:blue", "linear": "tab:green"}
    styles = ["-", "--", ":", "-."]
    print(f"{'lvl':>3} {'dofs':>9} {'method':>12} {'cycles':>6} {'seconds':>8} {'err@1e-6 s':>10} {'err@1e-10 s':>11} {'final rel err':>13}")
    for k, L in enumerate(a.levels):
        p = hertz.hertz_problem(a.cell, L, a.friction)
        ref = p.solve(tol=1e-300, max_cycles=60)
        u_star = ref.displacement
        norm = float(np.sqrt(u_star.ravel() @ p.A.matvec(u_star).ravel()))
        nmg = p.solve(error_reference=u_star)
        runs = {"nmg": nmg, "fixed-point": p.solve("fixed-point", error_reference=u_star),
                "linear": p.solve("linear", reference=nmg, error_reference=u_star)}
        for name, r in runs.items():
            e = r.history["error"] / norm
            t = r.history["seconds"]
            reach = lambda level: float(t[np.argmax(e <= level)]) if np.any(e <= level) else None  # noqa: E731
            row = {"level": L, "dofs": 2 * p.mesh.num_points, "method": name, "cycles": r.cycles,
                   "seconds": r.solve_seconds, "seconds_to_1e-6": reach(1e-6), "seconds_to_1e-10": reach(1e-10),
                   "final_error": float(e[-1]), "error": e.tolist(), "time": t.tolist()}
            rows.append(row)
            fmt = lambda v: f"{v:.3f}" if v is not None else "-"  # noqa: E731
            print(f"{L:3d} {row['dofs']:9d} {name:>12} {r.cycles:6d} {r.solve_seconds:8.3f} {fmt(row['seconds_to_1e-6']):>10} "
                  f"{fmt(row['seconds_to_1e-10']):>11} {row['final_error']:13.2e}", flush=True)
            ax.loglog(t, e, styles[k % 4], color=colors[name], label=f"{name}, level {L}")
    ax.set_xlabel("seconds")
    ax.set_ylabel(r"$\|u^k-u^*\|_A / \|u^*\|_A$")
    ax.set_title(f"work against precision, Hertz F = {a.friction}")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "work_precision.png"), dpi=130)
    with open(os.path.join(a.out, "work_precision.json"), "w") as fh:
        json.dump(rows, fh)


if __name__ == "__main__":
    main()
