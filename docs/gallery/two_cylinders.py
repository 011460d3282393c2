"""Two elastic half cylinders pressed together with Coulomb friction F = 0.4, the lower one twice as
stiff (dual mortar coupling on non-matching meshes): the contact stresses on the interface and
the contact half-width against the two-body Hertz formula."""
import matplotlib.pyplot as plt

import contactmg as cm
from contactmg.examples import cylinders
from contactmg.results import plots

from _common import out_dir


def main(argv=None):
    # cylinders_problem builds cm.Problem([upper, lower], pairs=[cm.ContactPair(0, 1, ...)], friction=...)
    problem = cylinders.cylinders_problem(levels=6, friction=0.4, E2=2 * cylinders.E)
    result = cm.Solver(problem, cm.SolverOptions(tol=1e-10)).solve()
    load = abs(float(result.reaction[1]))
    upper, lower = cm.Material(cylinders.E, cylinders.NU), cm.Material(2 * cylinders.E, cylinders.NU)
    a_hertz = cylinders.two_body_halfwidth(load, cylinders.RADIUS, cylinders.RADIUS, upper, lower)
    fig, ax = plt.subplots(figsize=(7, 4))
    plots.plot_boundary_stress(result, ax=ax, margin=1.5)
    ax.axvline(-a_hertz, color="k", ls=":", lw=1, label="Hertz half-width")
    ax.axvline(a_hertz, color="k", ls=":", lw=1)
    ax.set_title("two cylinders, E2 = 2 E1, Coulomb F = 0.4")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path = out_dir(argv) / "two_cylinders.png"
    fig.savefig(path, dpi=110)
    return {"figure": fig, "path": path, "result": result, "hertz_halfwidth": a_hertz,
            "halfwidth": result.halfwidth()}


if __name__ == "__main__":
    out = main()
    print(out["path"], "half-width", out["halfwidth"], "Hertz", out["hertz_halfwidth"])
