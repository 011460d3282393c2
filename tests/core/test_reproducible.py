"""solve() is a function of the problem and its options: the same bits in every solve on one
problem, and in separate processes.

Two causes broke it. (1) A solve began from the coarse levels the solve before had left: built for
its last truncation and changed by incremental updates, whose round-off differs from a full
build, and the coarsest solver's low-rank state with them; now a solve starts from the levels as
the solver built them (ContactSolver::restore_coarse). (2) The low-rank update of the coarsest
solver (mg/coarsest_solver.hpp, 3D only: 2D coarsest levels are below its size limit) took the
changed rows but not the changed columns of S - S0, which is not exactly symmetric; an entry in a
column outside them was written before its capacitance matrix's storage (heap corruption): second
solves on the 3D sphere differed from run to run, now and then the process crashed."""
import hashlib
import os
import subprocess
import sys

import numpy as np
import pytest

from contactmg import _core
from contactmg.examples import sphere
from contactmg.results.checks import contact_conditions
from contactmg.examples.hertz import hertz_problem


def digest(r):
    return hashlib.sha1(np.ascontiguousarray(np.asarray(r.displacement)).tobytes()).hexdigest()


def same_bits(a, b):
    assert np.array_equal(np.asarray(a.displacement), np.asarray(b.displacement))
    assert np.array_equal(a.node_state, b.node_state)
    assert a.cycles == b.cycles
    assert np.array_equal(a.history["correction_norm"], b.history["correction_norm"])


@pytest.fixture(scope="module")
def sphere3():
    return sphere.sphere_adaptive_hierarchy(3, friction=0.4)


def test_hertz_2d_solves_repeat_bit_for_bit():
    p = hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True)
    first = p.solve(threads=1)
    assert first.converged
    for _ in range(2):
        same_bits(first, p.solve(threads=1))
    on = p.solve(threads=1, petrov_galerkin=True)
    assert on.extra["petrov_galerkin"]["cycles"] > 0
    same_bits(on, p.solve(threads=1, petrov_galerkin=True))
    # a fresh problem's solve with it: the same bits as one after solves without it
    same_bits(on, hertz_problem("triangle", 5, 2.0, coulomb_at_zero=True).solve(threads=1, petrov_galerkin=True))
    same_bits(first, p.solve(threads=1))  # and back: the overlay left nothing behind


def test_other_methods_repeat_bit_for_bit():
    p = hertz_problem("triangle", 4, 0.4, coulomb_at_zero=True)
    for method in ("tnnmg", "fixed-point", "nmg"):
        a = p.solve(method, threads=1)
        same_bits(a, p.solve(method, threads=1))


def test_sphere_3d_solves_repeat_bit_for_bit(sphere3):
    p = sphere.sphere_problem("tetra", 3, 0.4, hierarchy=sphere3)
    first = p.solve(threads=1)
    assert first.converged and contact_conditions(p, first)["max"] <= 1e-8
    for _ in range(3):  # the third and fourth solves differed from the second as well
        same_bits(first, p.solve(threads=1))
    # the independent check's sweeps leave the next solve as it was
    _core.testing.smooth(p.solver.core, np.asarray(first.displacement), 2)
    same_bits(first, p.solve(threads=1))
    fresh = sphere.sphere_problem("tetra", 3, 0.4, hierarchy=sphere3).solve(threads=1)
    same_bits(first, fresh)


# Several solves on one problem, then their hashes: run in separate processes, whose heap layouts
# differ (ASLR, the hash seed), the same script printed other hashes from the second solve on.
SCRIPT = """
import hashlib, numpy as np
from contactmg.examples import sphere
p = sphere.sphere_problem("tetra", 3, 0.4, hierarchy=sphere.sphere_adaptive_hierarchy(3, friction=0.4))
out = []
for kw in ({}, {}, {"petrov_galerkin": {pg}}, {}):
    r = p.solve(threads=1, **kw)
    out.append(hashlib.sha1(np.ascontiguousarray(np.asarray(r.displacement)).tobytes()).hexdigest())
print(" ".join(out))
"""


def run_script(seed, pg):
    env = dict(os.environ, PYTHONHASHSEED=str(seed), OMP_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-c", SCRIPT.replace("{pg}", str(pg))], capture_output=True, text=True, timeout=120,
                       env=env)
    assert r.returncode == 0, r.stderr
    return r.stdout.split()


def test_separate_processes_give_the_same_hashes():
    runs = [run_script(seed, True) for seed in (3, 7, 11)]
    assert runs[0] == runs[1] == runs[2]
    a = runs[0]
    assert a[0] == a[1] == a[3]  # every default solve the first one's bits, before and after the coupling's


def test_coarsest_low_rank_update_takes_the_changed_columns():
    # S - S0 with an entry (5, 9) whose row 9 is unchanged (Galerkin matrices are symmetric to
    # round-off only): the correction's rows must include 9, else M(pos[5], pos[9] = -1) is written
    # outside its storage and the correction misses the entry (the solve then fell back to a new
    # factorization of the lower triangle, which does not hold it either)
    n = 400
    S0 = 4 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)  # 400 rows allow a low-rank correction
    S = S0.copy()
    S[5, 9] += 1e-3
    S[20, 20] += 0.5
    b = np.linspace(1.0, 2.0, n)
    x, rank, factorizations = _core.testing.coarsest_update_solve(S0, S, b)
    assert rank == 3 and factorizations == 1
    assert np.abs(S @ x - b).max() <= 1e-13 * np.abs(b).max()
