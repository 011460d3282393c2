"""Issue 15, "float32 coarse levels where the rate allows": under the process-wide switch
_core._float_coarse_values the coarse levels but the coarsest keep a float copy of their matrix
values (rounded once from the double Galerkin products and incremental updates), and their sweeps,
residuals and products read it, accumulating in double. The solution and contact state are those of
the double levels, one thread gives the bits of two, and the monotone cycles stay monotone."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.checks import contact_conditions
from contactmg.friction import Tresca
from contactmg.generators import rectangle
from contactmg.hertz import hertz_problem
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.obstacle import PlaneObstacle
from contactmg.problem import ContactProblem, Dirichlet
from contactmg.sphere import sphere_problem


@pytest.fixture
def switch():
    old = _core._float_coarse_values()
    yield lambda on: _core._float_coarse_values(on)
    _core._float_coarse_values(old)


def rel(a, b):
    return np.max(np.abs(a.displacement - b.displacement)) / np.max(np.abs(a.displacement))


def test_off_by_default():
    assert _core._float_coarse_values() is False


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 6, 0.4), lambda: hertz_problem("triangle", 6, 5.0),
                                  lambda: sphere_problem("hexahedron", 2, 0.4)], ids=["hertz-L6-F0.4", "hertz-L6-F5", "sphere-L2"])
@pytest.mark.parametrize("ordering", ["lexicographic", "coloured"])
def test_same_solution_and_contact_state(switch, make, ordering):
    res = {}
    for on in (False, True):
        switch(on)
        p = make()
        p.default_ordering = ordering
        res[on] = p.solve("nmg", ordering=ordering)
        assert res[on].converged
        assert contact_conditions(p, res[on])["max"] < 1e-8
    assert rel(res[False], res[True]) < 1e-9
    assert np.array_equal(res[False].node_state, res[True].node_state)
    assert abs(res[False].cycles - res[True].cycles) <= 1


def test_one_thread_gives_the_bits_of_two(switch):
    switch(True)
    res = []
    for t in (1, 2):
        p = hertz_problem("triangle", 7, 5.0)
        p.default_ordering = "coloured"
        res.append(p.solve("nmg", ordering="coloured", threads=t))
    assert np.array_equal(res[0].displacement, res[1].displacement)
    assert np.array_equal(res[0].history["correction_norm"], res[1].history["correction_norm"])


def test_the_copy_is_held_only_while_on(switch):
    p = hertz_problem("triangle", 6, 0.4)
    switch(False)
    p.solve("nmg")
    off = p.solver.memory_bytes()
    switch(True)
    a = p.solve("nmg")
    on = p.solver.memory_bytes()
    levels = p.solver.num_levels - 1
    floats = sum(4 * p.solver.coarse_matrix(l).data.size for l in range(1, levels))
    assert on - off == floats > 0
    switch(False)
    b = p.solve("nmg")
    assert p.solver.memory_bytes() == off
    assert rel(a, b) < 1e-9


def test_tresca_energy_still_decreases_every_cycle(switch):
    switch(True)
    h = MeshHierarchy.build(rectangle(4, 2, lx=2.0, ly=1.0, cell="triangle"), 6)
    p = ContactProblem(h, Material(100.0, 0.3), [Dirichlet([3], (0.05, -0.01))], contact_tags=[1],
                       obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(0.2))
    r = p.solve("nmg")
    assert r.converged and r.counts()["slip_nodes"] > 0
    e = np.asarray(r.history["energy"], float)
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())
    assert contact_conditions(p, r)["max"] < 1e-8
