"""The serial solver in the hashed order (ordering="hashed") against the distributed solve on one
rank (SerialComm, in this process): the same colours on every level, the same cycle counts and the
same displacement to round-off (0030-distributed-cycle, "The measurement that decided it")."""
import numpy as np
import pytest

import contactmg
from contactmg import _core
from contactmg.distributed import SerialComm, colour_level
from contactmg.examples.distributed import hertz, sphere
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.model.friction import Frictionless
from contactmg.model.problem import Problem

from solve_checks import CASES, OPTIONS, solve_case

# the largest difference of the displacements, relative to max |u|, allowed between the two solves:
# the same sweeps in the same order, summed in other orders (assembly, Galerkin products, the
# coarsest solver)
RELATIVE = 1e-12


def serial_problem(example, levels, cell, friction):
    make = hertz_problem if example is hertz else sphere_problem
    p = make(cell, levels, 0.0)
    return p if isinstance(friction, Frictionless) else Problem(p.bodies[0], obstacle=p.obstacle, friction=friction)


@pytest.mark.parametrize("example, levels, cell", [(hertz, 3, "triangle"), (hertz, 3, "quad"), (sphere, 2, "tetra"),
                                                   (sphere, 2, "hexahedron")])
@pytest.mark.parametrize("storage", ["hashed", "coloured"])
def test_hashed_colours_are_the_distributed_colours(example, levels, cell, storage):
    """Every level's colours (fine, coarse and coarsest) of the serial hashed sweeps are colour_level's
    for the same nodes, whether the levels are stored by the hashed colours or the coloured ones."""
    comm = SerialComm()
    dist = example(levels, cell, None, comm)
    solver = contactmg.Solver(serial_problem(example, levels, cell, Frictionless()), OPTIONS.replace(method="nmg", ordering=storage))
    assert list(solver.core.level_sizes) == [len(lev.gid) for lev in dist.hierarchy.levels]
    for l, lev in enumerate(dist.hierarchy.levels):
        got = _core.testing.level_colours(solver.core, l, "hashed")
        want = colour_level(lev, comm)
        assert np.array_equal(got[lev.gid], want), f"level {l}: {np.count_nonzero(got[lev.gid] != want)} nodes differ"
    # the greedy colouring in node order is another one
    fine = len(dist.hierarchy.levels) - 1
    assert not np.array_equal(_core.testing.level_colours(solver.core, fine, "coloured"),
                              _core.testing.level_colours(solver.core, fine, "hashed"))


@pytest.mark.parametrize("name", sorted(CASES))
def test_hashed_serial_solve_is_the_distributed_solve(name):
    example, levels, cell, friction, _, _ = CASES[name]
    got = solve_case(name, SerialComm())
    ref = contactmg.Solver(serial_problem(example, levels, cell, friction), OPTIONS.replace(method="nmg", ordering="hashed")).solve()
    assert got["converged"] and ref.converged
    assert got["cycles"] == ref.cycles
    # the coarse rebuilds of the solve, counted alike (the set-up's build in neither)
    assert got["rebuilds"] == ref.rebuilds
    u = ref.displacement
    assert np.abs(got["u"] - u).max() <= RELATIVE * np.abs(u).max()
