"""The fine nonlinear sweep of a level stored by colours runs a range kernel (the plain
rows -- neither contact nodes nor rows with a special diagonal inverse -- in one loop with x
prefetched ahead, the other rows through the per-row path). It must give the per-row path's
result bit for bit: the same sums in the same order, for every law, in 2D and 3D, with and
without over-relaxation, on 1 and 2 threads (ContactSolver.smooth with per_row=True takes the
per-row path)."""
import numpy as np
import pytest

from contactmg.model.friction import Tresca
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg import _core
from contactmg.solve.options import options_from, resolve_options


def _solve(make, **kw):
    p = make()
    p.default_options = options_from(p.default_options).replace(ordering="coloured")
    assert p.solver.core.renumbered  # stored by colours: the kernel's case
    return p, p.solve("nmg", **kw)


def _kernel_and_per_row(p, res, threads, omega):
    """Three sweeps from a rough start by the range kernel and by the per-row path: contact nodes
    change state inside the sweeps, so the kernel's hand-over to the nodal solve is exercised."""
    rng = np.random.default_rng(7)
    u0 = res.displacement * (1 + 0.3 * rng.standard_normal(res.displacement.shape))
    a = _core.testing.smooth(p.solver.core, u0, 3, ordering="coloured", threads=threads, omega=omega)
    b = _core.testing.smooth(p.solver.core, u0, 3, ordering="coloured", threads=threads, omega=omega, per_row=True)
    assert not np.array_equal(a, u0)
    return a, b


def _hertz_with(friction, contact=True):
    """Hertz level 5 with another law (contact=False: linear elasticity, no contact rows)."""
    from contactmg.examples import hertz as H
    from contactmg.model.material import Material
    from contactmg.mesh.hierarchy import MeshHierarchy
    from contactmg.model.problem import Body, Dirichlet, Problem
    from contactmg.model.obstacle import PlaneObstacle
    h = MeshHierarchy.build(H.hertz_half_disk("triangle"), 5, projector=H.hertz_projector(H.CENTER, H.RADIUS))
    dirichlet = [Dirichlet([H.HERTZ_TOP], (0.0, H.TOP_DISPLACEMENT))]
    if not contact:  # hold the arc as well: a linear problem with a unique solution
        dirichlet.append(Dirichlet([H.HERTZ_ARC], (0.0, 0.0)))
        return Problem(Body(h, Material(H.E, H.NU), dirichlet))
    return Problem(Body(h, Material(H.E, H.NU), dirichlet, contact_tags=[H.HERTZ_ARC]),
                   obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=friction)


CASES = {
    "coulomb-2d": lambda: hertz_problem("triangle", 6, 0.4),
    "frictionless-2d": lambda: hertz_problem("triangle", 5, 0.0),
    "coulomb-3d": lambda: sphere_problem(levels=2, friction=0.4),
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("threads", [1, 2])
def test_range_kernel_equals_the_per_row_sweep_bit_for_bit(case, threads):
    p, res = _solve(CASES[case], threads=threads)
    assert res.converged
    a, b = _kernel_and_per_row(p, res, threads, resolve_options(p).omega)
    assert np.array_equal(a, b)
    if case == "coulomb-2d":
        # the solve went through every kind of fine row: free, sticking and sliding contact nodes
        states = set(np.unique(res.node_state).tolist())
        assert len(states) >= 3, states


def test_range_kernel_without_over_relaxation():
    # omega = 1: the plain assignment branch of the kernel (the default on triangles is 1.3)
    p, res = _solve(CASES["coulomb-2d"], omega=1.0)
    assert res.converged
    a, b = _kernel_and_per_row(p, res, 1, 1.0)
    assert np.array_equal(a, b)


@pytest.mark.parametrize("law", ["tresca", "linear"])
def test_range_kernel_with_the_other_laws(law):
    make = (lambda: _hertz_with(Tresca(2.0))) if law == "tresca" else (lambda: _hertz_with(None, contact=False))
    p, res = _solve(make)
    assert p.law == law and res.converged
    for omega in (1.0, resolve_options(p).omega):
        a, b = _kernel_and_per_row(p, res, 1, omega)
        assert np.array_equal(a, b)


@pytest.mark.parametrize("threads", [1, 2])
def test_sweeps_from_a_perturbed_solution_agree_bit_for_bit(threads):
    p, res = _solve(lambda: hertz_problem("triangle", 6, 0.4))
    a, b = _kernel_and_per_row(p, res, threads, 1.0)
    assert np.array_equal(a, b)
    # and the kernel keeps the solution a fixed point (to round-off)
    u = _core.testing.smooth(p.solver.core, res.displacement, 2, ordering="coloured", threads=threads)
    assert np.abs(u - res.displacement).max() <= 1e-9 * np.abs(res.displacement).max()
