"""Issue 15: the fine nonlinear sweep of a level stored by colours runs a range kernel (the plain
rows -- neither contact nodes nor rows with a special diagonal inverse -- in one loop with x
prefetched ahead, the other rows through the per-row path). It must give the per-row path's
result bit for bit: the same sums in the same order, for every law, in 2D and 3D, with and
without over-relaxation, on 1 and 2 threads."""
import contextlib

import numpy as np
import pytest

from contactmg import _core
from contactmg.friction import Tresca
from contactmg.hertz import hertz_problem
from contactmg.sphere import sphere_problem


@contextlib.contextmanager
def generic_sweeps(on: bool):
    old = _core._fine_sweep_generic(on)
    try:
        yield
    finally:
        _core._fine_sweep_generic(old)


def _solve(make, generic, **kw):
    p = make()  # fresh: a solver carries its coarse hierarchy from one solve to the next
    p.default_ordering = "coloured"
    assert p.solver.renumbered  # stored by colours: the kernel's case
    with generic_sweeps(generic):
        return p.solve("nmg", **kw)


def _hertz_with(friction, contact=True):
    """Hertz level 5 with another law (contact=False: linear elasticity, no contact rows)."""
    from contactmg import hertz as H
    from contactmg.material import Material
    from contactmg.hierarchy import MeshHierarchy
    from contactmg.problem import ContactProblem, Dirichlet
    from contactmg.obstacle import PlaneObstacle
    h = MeshHierarchy.build(H.hertz_half_disk("triangle"), 5, projector=H.hertz_projector(H.CENTER, H.RADIUS))
    kw = dict(contact_tags=[H.HERTZ_ARC], obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=friction) if contact else {}
    dirichlet = [Dirichlet([H.HERTZ_TOP], (0.0, H.TOP_DISPLACEMENT))]
    if not contact:  # hold the arc as well: a linear problem with a unique solution
        dirichlet.append(Dirichlet([H.HERTZ_ARC], (0.0, 0.0)))
    return ContactProblem(h, Material(H.E, H.NU), dirichlet, **kw)


CASES = {
    "coulomb-2d": lambda: hertz_problem("triangle", 6, 0.4),
    "frictionless-2d": lambda: hertz_problem("triangle", 5, 0.0),
    "coulomb-3d": lambda: sphere_problem(levels=2, friction=0.4),
}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("threads", [1, 2])
def test_range_kernel_equals_the_per_row_sweep_bit_for_bit(case, threads):
    make = CASES[case]
    kernel = _solve(make, False, threads=threads)
    generic = _solve(make, True, threads=threads)
    assert kernel.converged and generic.converged
    assert kernel.cycles == generic.cycles
    assert np.array_equal(kernel.displacement, generic.displacement)
    assert np.array_equal(kernel.history["correction_norm"], generic.history["correction_norm"])
    assert np.array_equal(kernel.history["energy"], generic.history["energy"])
    if case == "coulomb-2d":
        # the solve went through every kind of fine row: free, sticking and sliding contact nodes
        states = set(np.unique(kernel.node_state).tolist())
        assert len(states) >= 3, states


def test_range_kernel_without_over_relaxation():
    # omega = 1: the plain assignment branch of the kernel (the default on triangles is 1.3)
    make = CASES["coulomb-2d"]
    a = _solve(make, False, omega=1.0)
    b = _solve(make, True, omega=1.0)
    assert a.cycles == b.cycles and np.array_equal(a.displacement, b.displacement)


@pytest.mark.parametrize("law", ["tresca", "linear"])
def test_range_kernel_with_the_other_laws(law):
    make = (lambda: _hertz_with(Tresca(2.0))) if law == "tresca" else (lambda: _hertz_with(None, contact=False))
    a = _solve(make, False)
    b = _solve(make, True)
    assert make().law == law
    assert a.converged and a.cycles == b.cycles and np.array_equal(a.displacement, b.displacement)


@pytest.mark.parametrize("threads", [1, 2])
def test_sweeps_from_a_perturbed_solution_agree_bit_for_bit(threads):
    # single sweeps (omega = 1, the independent check's sweep) from a rough start: contact nodes
    # change state inside the sweep, so the kernel's hand-over to the nodal solve is exercised
    p = hertz_problem("triangle", 6, 0.4)
    p.default_ordering = "coloured"
    res = p.solve("nmg")
    rng = np.random.default_rng(7)
    u0 = res.displacement * (1 + 0.3 * rng.standard_normal(res.displacement.shape))
    S = p.solver
    a = S.smooth(u0, 3, ordering="coloured", threads=threads)
    with generic_sweeps(True):
        b = S.smooth(u0, 3, ordering="coloured", threads=threads)
    assert not np.array_equal(a, u0)
    assert np.array_equal(a, b)
    # and the kernel keeps the solution a fixed point (to round-off)
    u = S.smooth(res.displacement, 2, ordering="coloured", threads=threads)
    assert np.abs(u - res.displacement).max() <= 1e-9 * np.abs(res.displacement).max()


def test_the_switch_is_restored():
    assert _core._fine_sweep_generic() is False
    with generic_sweeps(True):
        assert _core._fine_sweep_generic() is True
    assert _core._fine_sweep_generic() is False
