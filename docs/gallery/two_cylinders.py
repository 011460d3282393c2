"""Two elastic half cylinders pressed together with Coulomb friction F = 0.4, the lower one twice as
stiff (dual mortar coupling on non-matching meshes): the contact stresses on the interface and
the contact half-width against the two-body Hertz formula."""

import contactmg as cm
from contactmg.examples import cylinders

from _common import stress_figure


def main(argv=None):
    # cylinders_problem builds cm.Problem([upper, lower], pairs=[cm.ContactPair(0, 1, ...)], friction=...)
    problem = cylinders.cylinders_problem(levels=6, friction=0.4, E2=2 * cylinders.E)
    result = cm.Solver(problem, cm.SolverOptions(tol=1e-10)).solve()
    load = abs(float(result.reaction[1]))
    upper, lower = cm.Material(cylinders.E, cylinders.NU), cm.Material(2 * cylinders.E, cylinders.NU)
    a_hertz = cylinders.two_body_halfwidth(load, cylinders.RADIUS, cylinders.RADIUS, upper, lower)
    return stress_figure(result, a_hertz, "two_cylinders", argv, title="two cylinders, E2 = 2 E1, Coulomb F = 0.4")


if __name__ == "__main__":
    out = main()
    print(out["path"], "half-width", out["halfwidth"], "Hertz", out["hertz_halfwidth"])
