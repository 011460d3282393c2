"""Memory: what a solve keeps in Python. Refined meshes and transfers hold 32-bit ids; a
problem that releases its hierarchy once the core solver is built solves to the same bits, and its
results, VTU output and contact check need nothing of what was released; the released levels come
back identical when asked for; the accounting by owner adds up. (The figures themselves come from
benchmarks/performance/memory.py: no timed or sized test here.)"""
import json
import subprocess
import sys

import meshio
import numpy as np
import pytest

from contactmg.results.checks import VIOLATION_TOL, contact_conditions
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem, hertz_problem_on
from contactmg.examples.sphere import sphere_problem
from contactmg.solve.options import options_from
from contactmg.solve.solver import memory_report


def released(make):
    p = make()
    p.default_options = options_from(p.default_options).replace(release_hierarchy=True)
    return p


def test_refined_meshes_and_transfers_hold_32_bit_ids():
    h = hertz_problem("triangle", 4, 0.4).hierarchy
    for m in h.meshes[1:]:
        assert m.cells.dtype == np.int32 and m.facets.dtype == np.int32
    for t in h.transfers:
        assert t.ptr.dtype == np.int32 and t.parent.dtype == np.int32 and t.weight.dtype == np.float64
    # the scipy view of a transfer still works on them
    P = h.transfers[-1].matrix()
    assert np.allclose(P @ np.ones(P.shape[1]), 1.0)


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 5, 0.4), lambda: hertz_problem("quad", 4, 0.4),
                                  lambda: sphere_problem("tetra", 2, 0.4)])
def test_a_released_hierarchy_solves_to_the_same_bits(make):
    keep = make().solve("nmg", threads=1)
    p = released(make)
    got = p.solve("nmg", threads=1)
    assert p.hierarchy.released
    assert got.cycles == keep.cycles
    assert np.array_equal(got.displacement, keep.displacement)
    assert np.array_equal(got.contact_force, keep.contact_force)
    assert np.array_equal(got.node_state, keep.node_state)
    assert got.mesh is p.mesh is p.hierarchy.finest


def test_results_output_and_check_need_nothing_released(tmp_path):
    p = released(lambda: hertz_problem("triangle", 5, 0.4))
    r = p.solve("nmg")
    assert p.hierarchy.released
    levels = p.hierarchy.levels
    assert p.solver.memory_bytes()["problem_vectors"] < p.mesh.num_points * p.mesh.dim * 8  # load and Dirichlet values dropped
    path = tmp_path / "out.vtu"
    r.write_vtu(path)
    c = contact_conditions(p, r)
    counts, width, reaction = r.counts(), r.contact_halfwidth, r.reaction
    # none of it made the coarse levels again
    assert p.hierarchy.released and p.hierarchy.levels == levels
    assert p.hierarchy.memory_bytes()["transfers"] == 0
    back = meshio.read(path)
    assert np.array_equal(back.point_data["displacement"][:, :2], r.displacement)  # VTU pads 2D vectors
    assert np.array_equal(back.cells_dict["triangle"], p.mesh.cells)
    assert counts["contact_nodes"] > 0 and width > 0 and reaction[1] > 0
    assert c["max"] < VIOLATION_TOL
    # the check made the load and the Dirichlet values again: the same bits as a fresh problem's
    fresh = hertz_problem("triangle", 5, 0.4)
    assert np.array_equal(p.load, fresh.load) and np.array_equal(p.fixed_values, fresh.fixed_values)
    # a second solve runs on the kept core solver: still released
    again = p.solve("nmg", threads=1)
    assert p.hierarchy.released and again.converged


def test_released_levels_come_back_identical():
    keep = hertz_problem("triangle", 5, 0.4).hierarchy
    p = released(lambda: hertz_problem("triangle", 5, 0.4))
    p.solver.core
    h = p.hierarchy
    assert h.released and h.levels == keep.levels and h.finest is p.mesh
    for a, b in zip(h.meshes, keep.meshes):
        assert np.array_equal(a.points, b.points) and np.array_equal(a.cells, b.cells)
        assert np.array_equal(a.facets, b.facets) and np.array_equal(a.facet_tags, b.facet_tags)
    for a, b in zip(h.transfers, keep.transfers):
        assert np.array_equal(a.ptr, b.ptr) and np.array_equal(a.parent, b.parent) and np.array_equal(a.weight, b.weight)
    assert not h.released and h.meshes[-1] is p.mesh
    # what needs the transfers (a second core solver: the linear reference) works on the levels made again
    lin = p.solve("linear")
    assert lin.converged


def test_adaptive_hierarchies_are_kept():
    h = hertz_adaptive_hierarchy(3, 0.4)
    p = hertz_problem_on(h, 0.4)
    p.default_options = options_from(p.default_options).replace(release_hierarchy=True)
    assert not h.can_release()
    assert p.solve("nmg").converged
    assert not h.released and len(h.transfers) == h.levels - 1


def test_memory_accounting_adds_up():
    p = hertz_problem("triangle", 5, 0.4)
    before = memory_report(p)
    assert before["core"] == 0 and before["python_matrix"] > 0
    p.default_options = options_from(p.default_options).replace(release_hierarchy=True)
    p.solve("nmg")
    after = p.solver.memory_bytes()
    for m in (before, after):
        assert m["total"] == sum(v for k, v in m.items() if k != "total")
    # the core took the matrix over, the coarse meshes, the transfers, the load and the Dirichlet
    # values are gone, the finest mesh stays
    assert after["python_matrix"] == 0 and after["transfers"] == 0 and after["core"] == p.solver.core.memory_bytes()
    assert before["problem_vectors"] - after["problem_vectors"] == 2 * 8 * p.mesh.num_points * p.mesh.dim
    fine = p.mesh
    assert after["mesh_hierarchy"] == sum(a.nbytes for a in (fine.points, fine.cells, fine.facets, fine.facet_tags))
    assert after["mesh_hierarchy"] < before["mesh_hierarchy"]


def test_the_command_line_parser_does_not_load_scipy():
    # scipy (for the two-body commands) cost a `contactmg hertz` process 32 MiB at level 9
    code = "import sys; from contactmg.cli import main as cli; cli._parser(); print(json.dumps('scipy' in sys.modules))"
    out = subprocess.run([sys.executable, "-c", "import json; " + code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) is False


def test_the_command_line_releases_for_a_single_solve(tmp_path, monkeypatch):
    from contactmg.cli import main as cli
    from contactmg.examples import hertz

    made = []
    real = hertz.hertz_problem

    def spy(*a, **kw):
        made.append(real(*a, **kw))
        return made[-1]

    monkeypatch.setattr(hertz, "hertz_problem", spy)
    out = tmp_path / "r.json"
    assert cli.main(["hertz", "--levels", "4", "--json", str(out), "--vtu", str(tmp_path / "r.vtu"), "-q"]) == 0
    assert made[-1].hierarchy.released
    rep = json.loads(out.read_text())
    assert rep["converged"] and rep["hierarchy"] == "uniform"
    # a load path builds a core solver per step: it keeps its hierarchy
    assert cli.main(["hertz", "--levels", "3", "--steps", "2", "--json", str(out), "-q"]) == 0
    assert not made[-1].hierarchy.released


def test_hierarchies_pickle_and_old_pickles_load():
    import pickle

    from contactmg.mesh.hierarchy import MeshHierarchy

    p = released(lambda: hertz_problem("triangle", 3, 0.4))
    p.solver.core
    h = pickle.loads(pickle.dumps(p.hierarchy))
    assert h.released and h.levels == 3
    assert np.array_equal(h.meshes[1].cells, hertz_problem("triangle", 3, 0.4).hierarchy.meshes[1].cells)
    # the state of the former dataclass (public meshes / transfers)
    old = MeshHierarchy.__new__(MeshHierarchy)
    k = hertz_problem("triangle", 3, 0.4).hierarchy
    old.__setstate__({"meshes": k.meshes, "transfers": k.transfers, "build_seconds": 1.0, "kind": "uniform",
                      "estimated_error": []})
    assert old.levels == 3 and old.finest is k.finest and not old.released and not old.can_release()


@pytest.mark.parametrize("make", [lambda: hertz_problem("triangle", 4, 0.4), lambda: hertz_problem("quad", 3, 0.4),
                                  lambda: sphere_problem("tetra", 2, 0.4), lambda: sphere_problem("hexahedron", 2, 0.4)])
def test_the_stiffness_pattern_is_every_pair_of_nodes_sharing_a_cell(make):
    # the core builds it row by row from the cells around each node (no list of every cell's k^2 pairs)
    p = make()
    m = p.mesh
    k = m.cells.shape[1]
    cells = m.cells.astype(np.int64)
    i, j = np.repeat(cells, k, axis=1).ravel(), np.tile(cells, (1, k)).ravel()
    key = np.unique(i * m.num_points + j)
    rows, cols = key // m.num_points, key % m.num_points
    A = p.A
    indptr, indices = np.asarray(A.indptr), np.asarray(A.indices)
    assert np.array_equal(indptr, np.r_[0, np.cumsum(np.bincount(rows, minlength=m.num_points))])
    assert np.array_equal(indices, cols)


def test_the_estimators_edge_keys_do_not_overflow_with_32_bit_ids():
    """Refined meshes hold int32 ids; the estimator's edge keys i * n + j must still be exact past
    n = 46,341 nodes (the adaptive Hertz level 11 has 232k): every pair is found at its own edge."""
    from contactmg.solve.adaptivity import _edge_ids
    n = 300_000
    rng = np.random.default_rng(3)
    a = rng.integers(0, n, 2000)
    b = rng.integers(0, n, 2000)
    keep = a != b
    pairs = np.stack([a[keep], b[keep]], axis=1).astype(np.int32)
    edges = np.unique(np.sort(pairs, axis=1), axis=0).astype(np.int32)
    idx = _edge_ids(edges, pairs[:, ::-1], n)
    np.testing.assert_array_equal(edges[idx], np.sort(pairs, axis=1))


_PEAK = """
import json, sys
from contactmg.examples.hertz import hertz_problem
from contactmg.mesh.hierarchy import estimate_memory_bytes
from contactmg.examples.sphere import sphere_problem
cell, levels = sys.argv[1], int(sys.argv[2])
p = (sphere_problem(cell, levels, 0.4) if cell in ("tetra", "hexahedron") else hertz_problem(cell, levels, 0.4))
r = p.solve("nmg")
coarse = p.hierarchy.meshes[0]
# VmHWM, the high-water mark of this process's own address space: ru_maxrss keeps the parent's
# peak across fork and exec (the pytest process, hundreds of MB into the suite)
hwm = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps(dict(converged=bool(r.converged), peak=hwm * 1024,
                      estimate=estimate_memory_bytes(coarse, p.hierarchy.levels))))
"""


@pytest.mark.parametrize("cell, levels", [("triangle", 7), ("quad", 6), ("tetra", 3), ("hexahedron", 3)])
def test_the_memory_estimate_covers_the_peak_of_a_solve(cell, levels):
    """MeshHierarchy.build refuses a run whose estimate does not fit before allocating anything:
    the estimate must cover the whole process's peak of a solve that keeps its hierarchy (in a
    fresh interpreter, so nothing of this one counts)."""
    out = subprocess.run([sys.executable, "-c", _PEAK, cell, str(levels)], capture_output=True, text=True, check=True)
    got = json.loads(out.stdout)
    assert got["converged"]
    assert got["peak"] <= got["estimate"], got


def test_cli_peak_memory_is_its_own_not_its_parents():
    """peak_rss_mb is the command's own peak: started from a process that holds 400 MB it reports
    what the same command reports from a small one (ru_maxrss reported the parent's 400 MB)."""
    cmd = [sys.executable, "-m", "contactmg", "hertz", "--levels", "3", "--json", "-", "-q"]
    small = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)["peak_rss_mb"]
    parent = ("import json, subprocess, sys, numpy as np; big = np.ones(50_000_000); "
              f"print(subprocess.run({cmd!r}, capture_output=True, text=True, check=True).stdout)")
    out = subprocess.run([sys.executable, "-c", parent], capture_output=True, text=True, check=True).stdout
    got = json.loads(out)["peak_rss_mb"]
    assert got < small + 50 < 400, (got, small)
