"""The lead's "fine vector of page faults every cycle": a solver keeps the fine vectors of
its cycles (r, u_old and the Anderson history of settled Coulomb cycles) across solves, so a later
solve on the same solver first-touches no new fine pages inside its cycles (a fresh step per solve
allocated 8 fine vectors again: the Anderson slots' 6 in the cycles where the history fills, whose
first touch cost up to 0.5 s of system time a cycle at level 9 on this project's VM). Not a timed
test: it counts the process's minor page faults between the first and the last cycle's report."""
import resource

import numpy as np
import pytest

from contactmg.examples.hertz import hertz_problem
from contactmg.solve.options import options_from


def minor_faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def faults_in_cycles(p, ordering):
    seen = []
    r = p.solve("nmg", ordering=ordering, threads=1, progress=lambda rec: seen.append(minor_faults()))
    assert r.converged and r.cycles >= 8
    return seen[-1] - seen[0], r


@pytest.mark.parametrize("ordering", ["coloured", "lexicographic"])
def test_a_second_solve_touches_no_new_fine_vector_in_its_cycles(ordering):
    # level 7: a fine vector (1.19 MB) is above the core's mmap threshold (1 MiB), so a fine vector
    # allocated in a cycle is new pages, never a reused piece of the heap
    p = hertz_problem("triangle", 7, 0.4)
    p.default_options = options_from(p.default_options).replace(ordering=ordering)
    pages = p.mesh.num_points * 2 * 8 / resource.getpagesize()  # one fine vector
    first = p.solve("nmg", ordering=ordering, threads=1)
    assert first.converged
    faults, r = faults_in_cycles(p, ordering)
    # the Anderson history fills in these cycles (F = 0.4 slides)
    assert faults < 0.25 * pages, (faults, pages)
    # a later solve starts from the coarse levels as built, like the first: its bits
    assert np.array_equal(r.displacement, first.displacement)
    # the measure sees the fresh workspace of the old way: its 6 Anderson vectors in the cycles
    p.solver.core.keep_workspace(False)
    try:
        fresh, _ = faults_in_cycles(p, ordering)
    finally:
        p.solver.core.keep_workspace(True)
    assert fresh > 4 * pages, (fresh, pages)


@pytest.mark.parametrize("ordering", ["coloured", "lexicographic"])
def test_a_first_solve_touches_no_new_fine_vector_in_its_cycles(ordering):
    # a kept workspace takes its Anderson slots before the first cycle of the first solve: the
    # cycles where the history fills (F = 0.4 slides) touch no new fine page either
    p = hertz_problem("triangle", 7, 0.4)
    p.default_options = options_from(p.default_options).replace(ordering=ordering)
    p.solver.core
    pages = p.mesh.num_points * 2 * 8 / resource.getpagesize()
    faults, r = faults_in_cycles(p, ordering)
    assert faults < 0.25 * pages, (faults, pages)


def test_a_kept_workspace_changes_no_bit():
    # the same sequence of solves on two problems, one keeping its workspace, one not: the same bits
    out = {}
    for keep in (True, False):
        p = hertz_problem("triangle", 5, 5.0)
        p.solver.core.keep_workspace(keep)
        out[keep] = [p.solve("nmg", threads=t) for t in (1, 2, 1)]
    for a, b in zip(out[True], out[False]):
        assert a.cycles == b.cycles
        assert np.array_equal(a.displacement, b.displacement)
        assert np.array_equal(a.history["correction_norm"], b.history["correction_norm"])


def test_a_solver_made_for_one_solve_keeps_no_workspace():
    # release_hierarchy (the command line's single solves): the step's vectors go before the result
    # is written, as before, so the peak of a single solve stays where it was
    kept, once = hertz_problem("triangle", 6, 0.4), hertz_problem("triangle", 6, 0.4)
    once.default_options = options_from(once.default_options).replace(release_hierarchy=True)
    a, b = kept.solve("nmg", threads=1), once.solve("nmg", threads=1)
    assert np.array_equal(a.displacement, b.displacement)
    vector = kept.mesh.num_points * 2 * 8
    assert kept.solver.core.memory_bytes() - once.solver.core.memory_bytes() >= 5 * vector
