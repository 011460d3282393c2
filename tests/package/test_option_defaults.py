"""The solver's options have one set of names and defaults: the core's SolverOptions (its field
list, bindings/options.cpp) and the package's SolverOptions name the same fields, and where the
package gives a default of its own the core's is the same, so an option left out means the same in
both."""
import dataclasses

from contactmg import _core
from contactmg.solve.options import DEFAULT_ORDERING, PACKAGE_ONLY, SolverOptions


def test_the_core_and_the_package_name_the_same_fields():
    core = _core.solver_option_defaults()
    package = {f.name for f in dataclasses.fields(SolverOptions)}
    assert set(core) == package - set(PACKAGE_ONLY)


def test_every_default_the_package_gives_is_the_cores():
    core = _core.solver_option_defaults()
    given = SolverOptions()
    tol, rtol = given.stop
    assert (core["tol"], core["rtol"]) == (tol, rtol)
    assert core["ordering"] == DEFAULT_ORDERING
    for f in dataclasses.fields(SolverOptions):
        value = getattr(given, f.name)
        if f.name in PACKAGE_ONLY or f.name in ("tol", "rtol") or value is None:
            continue  # None: decided from the problem (resolve_options), or the core's own (linear, lines)
        assert core[f.name] == value and type(core[f.name]) is type(value), (f.name, core[f.name], value)


def test_a_solve_reports_every_field_it_took():
    import contactmg as cm

    h = cm.MeshHierarchy.build(cm.rectangle(2, 1, 2.0, 1.0), 2)
    p = cm.Problem(cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet(cm.RECT_TOP, (0.0, -0.01))],
                           contact_tags=[cm.RECT_BOTTOM]), obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)))
    raw = p.solver.core.solve(None, {})
    assert set(raw["options"]) == set(_core.solver_option_defaults())
