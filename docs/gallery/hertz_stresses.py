"""Hertz contact with Coulomb friction F = 0.4: the boundary stresses with the stick and slip zones
(the paper's Figure 2, middle), and the contact half-width against Hertz's formula."""
import matplotlib.pyplot as plt

import contactmg as cm
from contactmg.examples import hertz
from contactmg.results import plots

from _common import hertz_problem, out_dir


def main(argv=None):
    problem = hertz_problem(levels=7, friction=cm.Coulomb(0.4))
    result = cm.Solver(problem, cm.SolverOptions(tol=1e-10)).solve()
    load = abs(float(result.reaction[1]))
    a_hertz = hertz.halfwidth(load)
    fig, ax = plt.subplots(figsize=(7, 4))
    plots.plot_boundary_stress(result, ax=ax, margin=1.5)
    ax.axvline(-a_hertz, color="k", ls=":", lw=1, label="Hertz half-width")
    ax.axvline(a_hertz, color="k", ls=":", lw=1)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path = out_dir(argv) / "hertz_stresses.png"
    fig.savefig(path, dpi=110)
    return {"figure": fig, "path": path, "result": result, "hertz_halfwidth": a_hertz,
            "halfwidth": result.halfwidth()}


if __name__ == "__main__":
    out = main()
    print(out["path"], "half-width", out["halfwidth"], "Hertz", out["hertz_halfwidth"])
