"""The coarse correction: where its work runs (two threads, the small levels and colours on one)
does not change a bit of the result, and the coarsest solve kept current by a low-rank correction
of one factorization (mg/coarsest_solver.hpp) solves the problem."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg import _core
from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.solve.options import options_from


def fresh_solve(make, **kw):
    # a fresh problem per solve: a solver carries its coarse hierarchy from one solve to the next
    p = make()
    p.default_options = options_from(p.default_options).replace(ordering=kw.get("ordering", "coloured"))
    return p, p.solve("nmg", **kw)


def same_bits(a, b):
    assert a.converged and b.converged
    assert a.cycles == b.cycles
    assert np.array_equal(a.displacement, b.displacement)
    assert np.array_equal(a.history["correction_norm"], b.history["correction_norm"])


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 5, 0.4),
                                  lambda: sphere_problem(levels=2, friction=0.4)], ids=["hertz-2d-L5", "sphere-3d-L2"])
def test_the_parallel_paths_change_no_bit(make):
    # two threads (the coloured sweeps of the large levels on both, the small ones on one) against one
    _, all2 = fresh_solve(make, threads=2, ordering="coloured")
    _, all1 = fresh_solve(make, threads=1, ordering="coloured")
    same_bits(all2, all1)
    if _core.openmp():
        assert all2.extra["threads"] == 2


def coarsest_factorizations_of(make, **kw):
    p, r = fresh_solve(make, **kw)
    return p, r, _core.testing.coarsest_factorizations(p.solver.core)


@pytest.mark.parametrize("levels", [2, 3])
def test_low_rank_coarsest_updates_solve_the_problem(levels):
    # the 3D sphere at F = 0.4: sliding nodes whose friction Hessian changes in every cycle, so the
    # coarse levels are updated in every cycle, and the coarsest solve follows them by low-rank
    # corrections of one factorization far more often than by new ones
    make = lambda: sphere_problem(cell="tetra", levels=levels, friction=0.4)
    p, low, n_low = coarsest_factorizations_of(make, threads=1)
    assert low.converged
    assert low.rebuilds >= low.cycles - 1 > 0
    assert n_low < low.rebuilds / 2
    assert contact_conditions(p, low)["max"] < VIOLATION_TOL


def test_low_rank_coarsest_updates_are_thread_independent():
    make = lambda: sphere_problem(cell="tetra", levels=2, friction=0.4)
    _, r1 = fresh_solve(make, threads=1)
    _, r2 = fresh_solve(make, threads=2)
    same_bits(r1, r2)


CORK_PATH = ("import sys; from contactmg.cli.main import main; "
             "from contactmg.model.problem import Problem; "
             "Problem.rotated_frames = (lambda self: False) if {bounded} else Problem.rotated_frames; "
             "sys.argv = ['contactmg', 'cork', '--levels', '2', '--steps', '2', '--json', '-', '-q']; main()")


def test_cork_load_path_with_low_rank_updates():
    # the cork's load path has nodes that have just begun to slide (friction Hessian entries of
    # 1e12 beside 1e2 on the coarsest level), the hardest case for the low-rank correction: every
    # step converges, with the projected coarse correction (the cork's default) and the bounded one,
    # and both end at push forces that grow with the push
    for bounded in (False, True):
        p = subprocess.run([sys.executable, "-c", CORK_PATH.format(bounded=bounded)], capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0, p.stderr
        out = json.loads(p.stdout)
        assert all(s["converged"] for s in out["steps"])
        force = [s["push_force"] for s in out["steps"]]
        assert 0 < force[0] < force[1]
