"""A load step without a rebuild: ContactSolver.set_load and set_fixed_values change the right-hand
side of a built core solver (the Dirichlet values eliminated into it, in the contact frames, in the
solver's storage order), and a later solve is the one of a solver built with the new data, bit for
bit."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.mesh.generators import HERTZ_TOP
from contactmg.examples.hertz import TOP_DISPLACEMENT, hertz_problem
from contactmg.solve.loadpath import two_phase_path
from contactmg.examples.sphere import sphere_problem

HISTORY = ("cycle", "correction_norm", "energy", "active", "stick", "slip", "rebuilt")


def same_solve(a, b):
    assert np.array_equal(a["u"], b["u"])
    assert a["cycles"] == b["cycles"] and a["converged"] == b["converged"]
    for key in HISTORY:
        assert np.array_equal(a["history"][key], b["history"][key]), key
    for key in ("contact_force", "friction_bound", "state"):
        assert np.array_equal(a[key], b[key]), key


def other_data(p, seed):
    """A load and Dirichlet values unlike the problem's (the same fixed components)."""
    rng = np.random.default_rng(seed)
    load = p.load * 1.5 + 1e-3 * rng.standard_normal(p.load.shape) * np.abs(p.load).max()
    values = np.where(p.fixed != 0, p.fixed_values * 0.7, rng.standard_normal(p.fixed_values.shape))
    return load, values


@pytest.mark.parametrize("make, method", [
    (lambda: hertz_problem("triangle", 4, 0.4), "nmg"),
    (lambda: hertz_problem("quad", 3, 2.0), "fixed-point"),
    (lambda: hertz_problem("triangle", 4, 0.4), "tnnmg"),
    (lambda: sphere_problem("tetra", 2, 0.4), "nmg"),
])
def test_set_load_and_fixed_values_give_a_fresh_solvers_bits(make, method):
    p = make()
    opts = {"method": method, "threads": 1}
    kept = p.solver.new_core()
    kept.solve(None, opts)  # a solve of the old data first: nothing of it may remain
    load, values = other_data(p, 1)
    kept.set_load(load)
    kept.set_fixed_values(values)
    got = kept.solve(None, opts)
    fresh = p.solver.new_core(load=load, fixed_values=values).solve(None, opts)
    assert fresh["converged"], fresh["status"]
    same_solve(got, fresh)
    # and back to the problem's own data: the problem's own solve
    kept.set_load(p.load)
    kept.set_fixed_values(p.fixed_values)
    same_solve(kept.solve(None, opts), p.solver.new_core().solve(None, opts))


def test_the_steps_of_a_load_path_reuse_one_solver_bit_for_bit():
    """Each step's data (load and prescribed displacement of a path) set on one solver, with the
    previous step's slip origin and start: the steps of solvers built per step."""
    p = hertz_problem("triangle", 4, 0.4)
    path = two_phase_path(p, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), 2, (0.002, 0.0), 2)
    kept = p.solver.new_core()
    previous = None
    for k in range(len(path)):
        data = path.step_data(k)
        fresh = p.solver.new_core(load=data.load, fixed_values=data.fixed_values)
        kept.set_load(data.load)
        kept.set_fixed_values(data.fixed_values)
        for s in (fresh, kept):
            s.set_slip_origin(previous)
        a, b = kept.solve(previous, {"threads": 1}), fresh.solve(previous, {"threads": 1})
        same_solve(a, b)
        previous = a["u"]


def test_frame_values_stay_and_the_shape_is_checked():
    """A solver with components fixed in the contact frames (the known-state linear reference):
    new canonical values leave the frame values alone; wrong shapes and non-finite values are refused."""
    p = hertz_problem("triangle", 3, 0.4)
    c = p.contact
    nc = len(c.nodes)
    frame_fixed = np.zeros((nc, 2), np.uint8)
    frame_values = np.zeros((nc, 2))
    frame_fixed[: nc // 2, 0] = 1
    frame_values[: nc // 2, 0] = c.gaps[: nc // 2]
    args = (p.fixed, p.fixed_values, c.nodes, c.normals, c.gaps, p.coefficients, "linear",
            [t.as_tuple() for t in p.hierarchy.transfers], {"cycle": "F", "ordering": "coloured"})
    load, values = other_data(p, 2)
    kept = _core.ContactSolver2D(p.A, p.load, *args, frame_fixed=frame_fixed, frame_values=frame_values)
    kept.set_load(load)
    kept.set_fixed_values(values)
    built = _core.ContactSolver2D(p.A, load, args[0], values, *args[2:], frame_fixed=frame_fixed, frame_values=frame_values)
    same_solve(kept.solve(), built.solve())
    with pytest.raises(ValueError, match="shape"):
        kept.set_load(load[:-1])
    with pytest.raises(ValueError, match="shape"):
        kept.set_fixed_values(values[:, :1])
    bad = values.copy()
    bad[np.nonzero(p.fixed)[0][0], np.nonzero(p.fixed)[1][0]] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        kept.set_fixed_values(bad)
    with pytest.raises(ValueError, match="non-finite"):
        kept.set_load(np.full_like(load, np.inf))
