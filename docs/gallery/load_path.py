"""A load path: the Hertz disk pushed down in five equal steps with Coulomb friction F = 0.4, every
step solved on one solver from the previous step's displacement. The contact and stick half-widths
and the cycles per step."""
import matplotlib.pyplot as plt
import numpy as np

import contactmg as cm

from _common import hertz_problem, out_dir


def main(argv=None):
    problem = hertz_problem(levels=6, friction=cm.Coulomb(0.4))
    path = cm.LoadPath.proportional(problem, steps=5).solve("nmg", cm.SolverOptions(tol=1e-10))
    t = np.array(path.parameters)
    contact = np.array([r.halfwidth() for r in path.steps])
    stick = np.array([r.halfwidth((1,)) for r in path.steps])
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(9, 3.6))
    ax.plot(t, contact, "o-", label="contact half-width")
    ax.plot(t, stick, "s-", label="stick half-width")
    ax.set_xlabel("load parameter t (top displacement = t x 0.005)")
    ax.set_ylabel("half-width")
    ax.legend(fontsize=8)
    ax2.bar(t, path.cycles, width=0.12)
    ax2.set_xlabel("load parameter t")
    ax2.set_ylabel("multigrid cycles")
    fig.suptitle("Hertz load path, Coulomb F = 0.4, level 6")
    fig.tight_layout()
    out = out_dir(argv) / "load_path.png"
    fig.savefig(out, dpi=110)
    return {"figure": fig, "path": out, "result": path, "contact": contact, "stick": stick}


if __name__ == "__main__":
    print(main()["path"])
