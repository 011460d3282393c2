"""The default stop does not depend on the model's units: the same model in m and Pa, mm and MPa,
mm and Pa takes the same cycles, in one solve and on every step of a load path."""
import numpy as np
import pytest

import contactmg as cm
from contactmg.results.checks import contact_conditions
from contactmg.solve.options import DEFAULT_RTOL

# (length unit in m, stress unit in Pa)
UNITS = {"m, Pa": (1.0, 1.0), "mm, MPa": (1e-3, 1e6), "mm, Pa": (1e-3, 1.0)}


def _disk(length, stress, levels=5, friction=0.3):
    """A steel half disk of radius 40 mm pressed 0.1 mm onto a rigid plane, in the given units."""
    mesh = cm.hertz_half_disk(center=(0.0, 0.04 / length), radius=0.04 / length)
    h = cm.MeshHierarchy.build(mesh, levels, projector=cm.CircleProjector((0.0, 0.04 / length), 0.04 / length,
                                                                          [cm.HERTZ_ARC]))
    body = cm.Body(h, cm.Material(210e9 / stress, 0.3), [cm.Dirichlet(cm.HERTZ_TOP, (0.0, -1e-4 / length))],
                   contact_tags=cm.HERTZ_ARC)
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(friction))


def test_same_cycles_in_any_units():
    cycles, u = {}, {}
    for name, (length, stress) in UNITS.items():
        p = _disk(length, stress)
        res = p.solve()
        assert res.converged, (name, res.status)
        assert res.options["rtol"] == DEFAULT_RTOL and res.options["tol"] == 0.0
        assert contact_conditions(p, res)["max"] < 1e-6
        cycles[name], u[name] = res.cycles, res.displacement * length
    assert max(cycles.values()) - min(cycles.values()) <= 2, cycles
    for name in UNITS:
        assert np.abs(u[name] - u["m, Pa"]).max() <= 1e-8 * np.abs(u["m, Pa"]).max()


def test_a_load_path_stops_alike_in_any_units():
    counts = {}
    for name, (length, stress) in UNITS.items():
        path = cm.LoadPath.proportional(_disk(length, stress, levels=4), 3)
        out = path.solve()
        assert out.converged, name
        counts[name] = out.cycles
    for name in UNITS:
        assert np.all(np.abs(np.subtract(counts[name], counts["m, Pa"])) <= 2), counts


def test_tol_or_rtol_alone_is_the_one_stop():
    o = cm.SolverOptions()
    assert o.stop == (0.0, DEFAULT_RTOL)
    assert cm.SolverOptions(tol=1e-11).stop == (1e-11, 0.0)
    assert cm.SolverOptions(rtol=1e-6).stop == (0.0, 1e-6)
    # changing one turns the other off: a relative options object made absolute stays absolute
    assert cm.SolverOptions(rtol=1e-6).replace(tol=1e-9).stop == (1e-9, 0.0)
    assert cm.SolverOptions(tol=1e-9, rtol=1e-6).stop == (1e-9, 1e-6)
    with pytest.raises(ValueError, match="one of tol and rtol must be positive"):
        cm.SolverOptions(tol=0.0)


def test_a_warm_start_at_the_solution_stops_at_once():
    """Relative to the iterate's own energy norm too, not only to the first correction: a solve
    that starts at its answer (a load step that changes nothing) stops after one cycle."""
    p = _disk(1e-3, 1e6, levels=4)
    first = p.solve()
    again = p.solve(u0=first.displacement)
    assert again.converged and again.cycles == 1
