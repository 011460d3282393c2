"""Truncated nonsmooth Newton multigrid (method="tnnmg"): agreement with Algorithm 2,
the independent contact check, the decrease of the frozen-bound energy by every correction and
line search, monotone energy for the convex laws, 3D, and the command line."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg.examples import hertz
from contactmg.examples import sphere
from contactmg.results.checks import contact_conditions
from contactmg.model.friction import Tresca
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.model.problem import Body, Dirichlet, Problem
from contactmg.solve.options import with_cycle


def rel_diff(a, b):
    return np.abs(a.displacement - b.displacement).max() / np.abs(a.displacement).max()


@pytest.fixture(scope="module")
def hertz_problems():
    return {(cell, F): hertz.hertz_problem(cell, 5 if cell == "triangle" else 4, F)
            for cell in ("triangle", "quad") for F in (0.0, 0.4, 5.0, 40.0)}


@pytest.mark.parametrize("cell", ["triangle", "quad"])
@pytest.mark.parametrize("F", [0.0, 0.4, 5.0, 40.0])
def test_tnnmg_agrees_with_algorithm2_and_passes_the_contact_check(hertz_problems, cell, F):
    p = hertz_problems[cell, F]
    a, b = p.solve("nmg"), p.solve("tnnmg")
    assert a.converged and b.converged, (a.status, b.status)
    assert b.method == "tnnmg"
    assert rel_diff(a, b) < 1e-8
    assert contact_conditions(p, b)["max"] < 1e-8
    # both cycles are multigrid cycles of the same cost order: counts of the same size
    assert b.cycles <= a.cycles + 5


@pytest.mark.parametrize("F", [0.4, 5.0, 40.0])
def test_every_tnnmg_correction_decreases_the_frozen_bound_energy(hertz_problems, F):
    """For Coulomb the correction and line search minimize the Tresca energy with the bound frozen
    at the smoothed iterate; its decrease (computed from the vectors before and after) is >= 0 up to
    round-off in every step, and the step lengths are positive and finite."""
    p = hertz_problems["triangle", F]
    r = p.solve("tnnmg")
    assert r.converged
    h = r.history
    scale = np.abs(h["energy"]).max()
    assert np.all(h["frozen_decrease"] >= -1e-12 * scale)
    # early steps make real progress
    assert h["frozen_decrease"][0] > 1e-6 * scale
    assert np.all(np.isfinite(h["step_size"])) and np.all(h["step_size"] > 0)
    # Algorithm 2 records no line search
    assert np.all(np.isnan(p.solve("nmg", max_cycles=3).history["step_size"]))


def tresca_layer():
    from contactmg.mesh.generators import rectangle
    from contactmg.mesh.hierarchy import MeshHierarchy
    h = MeshHierarchy.build(rectangle(4, 2, lx=2.0, ly=1.0, cell="triangle"), 4)
    # the absolute stop 1e-11 of the Hertz problems here: the agreement with nmg is measured to 1e-8
    return with_cycle(Problem(Body(h, Material(100.0, 0.3), [Dirichlet([3], (0.05, -0.01))], contact_tags=[1]),
                              obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Tresca(0.2)))


def test_tresca_energy_decreases_every_step_and_matches_nmg():
    """Tresca is convex and its bound is fixed: the frozen-bound energy is the energy, so every
    TNNMG step (sweeps, correction, line search, sweeps) lowers the recorded energy."""
    p = tresca_layer()
    a, b = p.solve("nmg"), p.solve("tnnmg")
    assert a.converged and b.converged
    assert b.counts()["slip_nodes"] > 0  # the line search meets friction kinks
    e = b.history["energy"]
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())
    assert rel_diff(a, b) < 1e-8
    assert contact_conditions(p, b)["max"] < 1e-8


def test_tnnmg_in_3d_agrees_with_algorithm2():
    p = sphere.sphere_problem("hexahedron", 1, 0.4)
    a, b = p.solve("nmg"), p.solve("tnnmg")
    assert a.converged and b.converged
    assert rel_diff(a, b) < 1e-8
    assert contact_conditions(p, b)["max"] < 1e-8


def test_cli_method_tnnmg():
    r = subprocess.run([sys.executable, "-m", "contactmg", "hertz", "--levels", "4", "--method", "tnnmg", "--json", "-",
                        "-q"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["method"] == "tnnmg" and d["converged"] and 5 <= d["cycles"] <= 30


def test_core_refuses_an_unknown_method_or_option(hertz_problems):
    """One method per solve, named by the options' method; anything else is refused by name."""
    with pytest.raises(ValueError, match=r"method: unknown method 'tnnmg\+fixed-point'"):
        hertz_problems["triangle", 0.4].solver.core.solve(None, {"method": "tnnmg+fixed-point"})
    with pytest.raises(ValueError, match="unknown option 'tnnmg'"):
        hertz_problems["triangle", 0.4].solver.core.solve(None, {"tnnmg": True})


def test_tnnmg_refuses_a_slip_origin():
    """TNNMG's line search measures friction on u_T, not on a load step's slip increment: a core
    solver that carries a slip origin must refuse it instead of answering for the wrong energy."""
    from contactmg.examples.hertz import hertz_problem

    p = hertz_problem("triangle", 3, 0.4)
    s = p.solver.new_core()
    s.set_slip_origin(np.zeros((p.mesh.num_points, 2)))
    with pytest.raises(ValueError, match="slip origin"):
        s.solve(None, {"method": "tnnmg"})
    s.set_slip_origin(None)
    assert s.solve(None, {"method": "tnnmg"})["converged"]
