"""Local smoothing on adaptive hierarchies, thinned hierarchies, Algorithm 1's
stop when it does not contract, and the adaptive Table 1 (parallel runs, CLI default)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem, hertz_problem_on
from contactmg.examples.table1 import table1
from contactmg.solve.options import options_from, resolve_options


@pytest.fixture(scope="module")
def graded():
    """A strongly graded Hertz hierarchy: theta = 0.2 adds about 30 % nodes per level."""
    return hertz_adaptive_hierarchy(14, 0.4, theta=0.2)


@pytest.fixture(scope="module")
def paper6():
    return hertz_adaptive_hierarchy(6, 0.4)


def energy_norm(p, v):
    return float(np.sqrt(v.ravel() @ p.A.matvec(v).ravel()))


def test_local_smoothing_is_on_for_adaptive_hierarchies_and_reaches_the_same_solution(graded):
    full = hertz_problem_on(graded, 0.4)
    full.default_options = options_from(full.default_options).replace(local_smoothing=False)
    local = hertz_problem_on(graded, 0.4)
    assert resolve_options(local).local_smoothing and not resolve_options(full, full.default_options).local_smoothing
    assert not resolve_options(hertz_problem("triangle", 3, 0.4)).local_smoothing  # uniform: every node changes
    rf, rl = full.solve(), local.solve()
    assert rf.converged and rl.converged
    assert contact_conditions(local, rl)["max"] < VIOLATION_TOL
    # the same discrete solution (both stop at ||u^{k+1} - u^k||_A <= 1e-11)
    diff = energy_norm(local, rl.displacement - rf.displacement) / energy_norm(local, rf.displacement)
    assert diff < 1e-7
    # the smoother really skipped rows: the iterates differ, yet the count stays about the same
    assert rl.history["correction_norm"].tolist() != rf.history["correction_norm"].tolist()
    assert rl.cycles <= rf.cycles + 3
    # and on this graded hierarchy it skips most coarse rows
    changed = sum(len(graded.changed_nodes(k)) for k in range(1, graded.levels - 1))
    every = sum(m.num_points for m in graded.meshes[1:-1])
    assert changed < 0.75 * every


def test_thinned_hierarchy_composes_the_transfers_and_grows_geometrically(graded):
    t = graded.thinned(2.0)
    assert t.meshes[0] is graded.meshes[0] and t.finest is graded.finest
    n = [m.num_points for m in t.meshes]
    assert all(b >= 2.0 * a for a, b in zip(n[:-2], n[1:-1]))  # the last level is kept whatever it grew
    assert t.levels < graded.levels
    # nested: each composed transfer is the product of the skipped ones (computed densely here)
    # and interpolates constants exactly
    kept = [next(k for k, g in enumerate(graded.meshes) if g is m) for m in t.meshes]
    for (a, b), tr in zip(zip(kept[:-1], kept[1:]), t.transfers):
        dense = np.eye(graded.meshes[a].num_points)
        for k in range(a, b):
            dense = graded.transfers[k].matrix().toarray() @ dense
        assert np.allclose(tr.matrix().toarray(), dense, atol=1e-14)
        assert np.allclose(tr.matrix().sum(axis=1), 1.0)
    # the same finest problem: the same solution, with a bounded cycle count
    r_all = hertz_problem_on(graded, 0.4).solve()
    p_thin = hertz_problem_on(t, 0.4)
    r_thin = p_thin.solve()
    assert r_thin.converged and r_thin.cycles <= 40
    diff = energy_norm(p_thin, r_thin.displacement - r_all.displacement) / energy_norm(p_thin, r_all.displacement)
    assert diff < 1e-7
    with pytest.raises(ValueError, match="min_growth"):
        graded.thinned(0.5)


def test_algorithm1_equals_algorithm2_on_a_small_adaptive_hierarchy(paper6):
    for F in (0.4, 1.0):
        p = hertz_problem_on(paper6, F, coulomb_at_zero=True)
        fp, nm = p.solve("fixed-point", fixed_point_stall_window=5), p.solve("nmg")
        assert fp.converged and nm.converged
        changes = fp.extra["outer_changes"]
        assert len(changes) == fp.outer_iterations and changes[-1] <= 1e-9
        diff = energy_norm(p, fp.displacement - nm.displacement) / energy_norm(p, nm.displacement)
        assert diff < 1e-6
        assert np.array_equal(fp.contact_state, nm.contact_state)


def test_fixed_point_stall_window_stops_only_a_change_that_did_not_fall(paper6):
    p = hertz_problem_on(paper6, 0.4, coulomb_at_zero=True)
    plain = p.solve("fixed-point")
    windowed = p.solve("fixed-point", fixed_point_stall_window=3)
    # a contracting iteration is not cut short
    assert windowed.converged and windowed.outer_iterations == plain.outer_iterations
    c = np.array(plain.extra["outer_changes"])
    assert np.all(c[3:] < c[:-3])
    # a large coefficient on a finer graded level: whatever the outcome, it is consistent with the rule
    h = hertz_adaptive_hierarchy(7, 0.4)
    q = hertz_problem_on(h, 8.0, coulomb_at_zero=True)
    w = 2
    r = q.solve("fixed-point", fixed_point_stall_window=w, fixed_point_max=60)
    ch = r.extra["outer_changes"]
    if r.converged:
        assert ch[-1] <= 1e-9
        assert all(ch[k] < ch[k - w] for k in range(w, len(ch)))
    else:
        assert "did not fall" in r.status or "60 outer" in r.status
        if "did not fall" in r.status:
            assert ch[-1] >= ch[-1 - w]
            assert all(ch[k] < ch[k - w] for k in range(w, len(ch) - 1))
    with pytest.raises(ValueError, match="fixed_point_stall_window"):
        p.solve("fixed-point", fixed_point_stall_window=-1)


def test_table1_in_two_processes_counts_as_in_one(paper6):
    kw = dict(levels=[4, 6], frictions=[0.4, 2.0], progress=False, hierarchy=paper6, fixed_point_stall_window=5)
    one, two = table1(jobs=1, **kw), table1(jobs=2, **kw)
    for k in ("dofs", "nodes", "fixed_point_iterations", "fixed_point_vcycles", "nmg_vcycles", "nmg_converged"):
        assert one[k] == two[k], k
    assert one["dofs"] == [2 * paper6.meshes[3].num_points, 2 * paper6.meshes[5].num_points]


def run(*args):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=600)


def test_cli_table1_is_adaptive_by_default_for_triangles():
    r = run("table1", "--levels", "3", "--frictions", "0.4", "--json", "-", "-q", "--jobs", "1")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["hierarchy"] == "adaptive" and len(d["estimated_error"]) == 1
    assert d["fixed_point_stall_window"] > 0
    q = run("table1", "--cell", "quad", "--levels", "2", "--frictions", "0.4", "--json", "-", "-q", "--jobs", "1")
    assert q.returncode == 0, q.stderr
    assert json.loads(q.stdout)["hierarchy"] == "uniform"
    bad = run("table1", "--cell", "quad", "--hierarchy", "adaptive", "--levels", "2")
    assert bad.returncode == 2 and "triangles" in bad.stderr.strip().splitlines()[-1]
    bad = run("table1", "--jobs", "0")
    assert bad.returncode == 2 and "--jobs" in bad.stderr.strip().splitlines()[-1]
