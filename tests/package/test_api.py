"""The Python API: solver options belong to the solve (no re-assembly to change the
cycle), the result carries its contact nodes and frames, frames are built in one Python place, and
results do not import the problem module."""
import ast

import numpy as np
import pytest

import contactmg as cm
from contactmg.examples import hertz
from contactmg.model.frames import contact_frames, to_canonical, to_local


@pytest.fixture(scope="module")
def problem():
    return hertz.hertz_problem("triangle", 5, 0.4)


def test_cycle_options_per_solve_without_reassembly(problem):
    load = problem.load
    f = problem.solve()
    # the core took the assembled matrix over (one fine matrix in memory); asked for, it
    # is assembled once more and kept
    A = problem.A
    v = problem.solve(cycle="V", nu1=2, nu2=1)
    assert problem.A is A and problem.load is load  # nothing re-assembled for another cycle
    assert v.extra["cycle_options"] == {"cycle": "V", "nu1": 2, "nu2": 1}
    assert f.extra["cycle_options"] == {"cycle": "F", "nu1": 3, "nu2": 3}
    # the same answer as a problem built with those options as its defaults, in as many cycles
    built = hertz.hertz_problem("triangle", 5, 0.4, cycle="V", nu1=2, nu2=1)
    ref = built.solve()
    assert (built.default_options.cycle, built.default_options.nu1, built.default_options.nu2) == ("V", 2, 1)
    assert v.converged and v.cycles == ref.cycles
    # (to round-off: a core solver that served another cycle before keeps its coarse matrices,
    # updated incrementally)
    np.testing.assert_allclose(v.displacement, ref.displacement, rtol=0, atol=1e-12 * np.abs(ref.displacement).max())
    # both cycles solve the same problem
    assert np.abs(v.displacement - f.displacement).max() < 1e-8 * np.abs(f.displacement).max()
    # one kept solver serves every cycle choice: asking again re-uses it
    core = problem.solver.core
    problem.solve(cycle="V", nu1=2, nu2=1)
    assert problem.solver.core is core
    again = problem.solve(cycle="V", nu1=2, nu2=1)
    assert again.cycles == v.cycles
    np.testing.assert_allclose(again.displacement, v.displacement, rtol=0, atol=1e-12 * np.abs(v.displacement).max())
    # the fixed-point and linear methods take the options too
    fp = problem.solve("fixed-point", cycle="W")
    assert fp.converged and fp.extra["cycle_options"]["cycle"] == "W"
    lin = problem.solve("linear", reference=f, cycle="V")
    assert lin.converged and lin.extra["cycle_options"]["cycle"] == "V"


@pytest.mark.parametrize("kw, match", [(dict(cycle="X"), "cycle must be"), (dict(nu1=-1), "nu1 must be"),
                                       (dict(nu1=0, nu2=0), "at least 1"), (dict(nu2=1.5), "nu2 must be")])
def test_cycle_options_are_checked_in_solve(problem, kw, match):
    with pytest.raises(ValueError, match=match):
        problem.solve(**kw)


def test_result_carries_contact_nodes_and_frames(problem):
    res = problem.solve()
    Q = res.contact_frames
    nc, d = len(res.contact_nodes), problem.mesh.dim
    assert Q.shape == (nc, d, d)
    np.testing.assert_allclose(np.einsum("cji,cjk->cik", Q, Q), np.broadcast_to(np.eye(d), (nc, d, d)), atol=1e-14)
    np.testing.assert_allclose(Q[:, :, 0], res.contact_normals)
    assert np.all(np.diff(res.contact_nodes) > 0)  # ascending node ids
    # the contact force is A u - f in those frames, and the reaction its canonical sum
    r = problem.A.matvec(res.displacement) - problem.load
    np.testing.assert_allclose(res.contact_force, to_local(Q, r[res.contact_nodes]),
                               atol=1e-9 * np.abs(res.contact_force).max())
    np.testing.assert_allclose(res.reaction, r[res.contact_nodes].sum(axis=0), atol=1e-9 * abs(res.reaction[1]))


@pytest.mark.parametrize("d", [2, 3])
def test_frames_are_right_handed_orthonormal_with_the_normal_first(d):
    rng = np.random.default_rng(7)
    n = rng.standard_normal((50, d))
    n[0] = np.eye(d)[0]
    n[1] = -np.eye(d)[d - 1]
    Q = contact_frames(n)
    unit = n / np.linalg.norm(n, axis=1)[:, None]
    np.testing.assert_allclose(Q[:, :, 0], unit, atol=1e-15)
    np.testing.assert_allclose(np.einsum("cji,cjk->cik", Q, Q), np.broadcast_to(np.eye(d), Q.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(Q), 1.0, atol=1e-14)
    v = rng.standard_normal((50, d))
    np.testing.assert_allclose(to_canonical(Q, to_local(Q, v)), v, atol=1e-14)


def _imports(module) -> set:
    """The package modules `module` imports anywhere in its source (functions included)."""
    tree = ast.parse(open(module.__file__).read())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and (node.level or node.module.startswith("contactmg.")):
            out.add(node.module.split(".")[-1])
    return out


def test_results_checks_and_frames_do_not_import_the_problem():
    from contactmg.results import checks
    from contactmg.model import frames
    from contactmg.results import result as results

    for module in (results, checks, frames):
        assert "problem" not in _imports(module), module.__name__
    assert "frames" in _imports(results) and "frames" in _imports(checks)


def test_constructor_cycle_keywords_are_still_defaults():
    p = hertz.hertz_problem("triangle", 4, 0.4, cycle="W", nu1=1, nu2=2)
    res = p.solve()
    assert res.extra["cycle_options"] == {"cycle": "W", "nu1": 1, "nu2": 2}
    assert p.setup_seconds > 0 and res.setup_seconds == pytest.approx(p.setup_seconds + p.solver.build_seconds)
    assert not hasattr(cm, "layer")  # the alias of rectangle is gone


def test_progress_is_called_after_every_cycle(problem):
    seen = []
    res = problem.solve(cycle="V", progress=seen.append)
    assert [r["cycle"] for r in seen] == list(res.history["cycle"])
    np.testing.assert_array_equal([r["correction_norm"] for r in seen], res.history["correction_norm"])

    def stop(record):
        if record["cycle"] >= 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        problem.solve(progress=stop)
    assert problem.solve().converged  # the solver is usable after a stopped solve


def test_progress_must_be_callable(problem):
    with pytest.raises(ValueError, match="progress must be a callable"):
        problem.solve(progress="print")


def test_the_moved_modules_import_with_a_deprecation_warning():
    """contactmg.checks, contactmg.loadpath and contactmg.two_body (moved into the layers) still
    import, warn once that they are deprecated, and hold the very objects of their new places. In a
    fresh interpreter: a module imported before does not run (nor warn) again."""
    import subprocess
    import sys

    code = """
import warnings
warnings.simplefilter("always")
old = {"checks": ["VIOLATION_TOL", "contact_conditions"],
       "loadpath": ["PATH_METHODS", "LoadPath", "PathResult", "StepData", "two_phase_path"],
       "two_body": ["Body", "ContactPair", "MultiBodyProblem", "TwoBodyProblem"]}
new = {"checks": "contactmg.results.checks", "loadpath": "contactmg.solve.loadpath",
       "two_body": "contactmg.model.problem contactmg.solve.contact_problem"}
import contactmg, importlib
for name, names in old.items():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mod = importlib.import_module("contactmg." + name)
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert len(deprecations) == 1, (name, [str(w.message) for w in caught])
    assert "contactmg." + name + " is deprecated" in str(deprecations[0].message)
    homes = [importlib.import_module(m) for m in new[name].split()]
    for n in names:
        assert any(getattr(h, n, None) is getattr(mod, n) for h in homes), (name, n)
from contactmg.two_body import Body, ContactPair  # the old spelling of the two-body imports
from contactmg.loadpath import LoadPath
assert Body is contactmg.Body and ContactPair is contactmg.ContactPair and LoadPath is contactmg.LoadPath
print("ok")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
