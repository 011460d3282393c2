"""Hertz contact with Coulomb friction F = 0.4: the boundary stresses with the stick and slip zones
(the paper's Figure 2, middle), and the contact half-width against Hertz's formula."""

import contactmg as cm
from contactmg.examples import hertz

from _common import hertz_problem, stress_figure


def main(argv=None):
    problem = hertz_problem(levels=7, friction=cm.Coulomb(0.4))
    result = cm.Solver(problem, cm.SolverOptions(tol=1e-10)).solve()
    load = abs(float(result.reaction[1]))
    a_hertz = hertz.halfwidth(load)
    return stress_figure(result, a_hertz, "hertz_stresses", argv)


if __name__ == "__main__":
    out = main()
    print(out["path"], "half-width", out["halfwidth"], "Hertz", out["hertz_halfwidth"])
