"""Every benchmark script runs in its quick mode and writes a stamped result file whose content
has the property the benchmark exists to show (on tiny levels)."""
import ast
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
FOLDERS = ("paper", "three_d", "methods", "performance", "model")
SCRIPTS = sorted(f"{d}/{p.stem}" for d in FOLDERS for p in (BENCHMARKS / d).glob("*.py"))
HISTORY = re.compile(r"\b(issue|stop|part|branch|perf|smooth)[ -]?\d+|docs/history", re.IGNORECASE)


# The deprecated aliases and modules fail a benchmark as they fail a test (pyproject.toml's
# filterwarnings, which a subprocess does not see): each message's start, as Python's -W matches it.
DEPRECATED = ",".join(f"error:contactmg.{name} is deprecated:DeprecationWarning" for name in
                      ("ContactProblem", "MultiBodyProblem", "TwoBodyProblem", "checks", "loadpath", "two_body"))


def run(args, tmp_path, timeout=300):
    env = dict(os.environ, MPLBACKEND="Agg")
    env["PYTHONWARNINGS"] = ",".join(w for w in (env.get("PYTHONWARNINGS"), DEPRECATED) if w)
    r = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=timeout, env=env,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    return r


def check_table1(res):
    assert res["levels"] == [2, 3] and len(res["frictions"]) == 2
    for fp_row, nmg_row, ok_row in zip(res["fixed_point_vcycles"], res["nmg_vcycles"], res["nmg_converged"]):
        assert all(ok_row)
        # Algorithm 1 spends more V-cycles (one solve per outer iteration) than Algorithm 2 cycles
        assert all(fp > nmg > 0 for fp, nmg in zip(fp_row, nmg_row))


def check_hertz_stresses(res):
    for kind in ("uniform", "adaptive"):
        rows = res[kind]["rows"]
        assert len(rows) == 3 and all(r["converged"] for r in rows)
        errors = [r["energy_error"] for r in rows]
        assert errors == sorted(errors, reverse=True) and errors[-1] < errors[0] / 2
        assert res[kind]["slope_vs_dofs"] < -0.3
        assert all(abs(r["peak_pressure"] / r["hertz_peak_pressure"] - 1) < 0.3 for r in rows)


def check_algorithm1_vs_2(res):
    assert [r["level"] for r in res["rows"]] == [3, 4]
    for r in res["rows"]:
        assert r["nmg_converged"] and r["fixed_point_converged"]
        assert r["relative_difference"] < 1e-8
        assert r["fixed_point_cycles"] > r["nmg_cycles"]


def check_sphere(res):
    rows = res["rows"]
    assert {(r["hierarchy"], r["cell"]) for r in rows} == {("uniform", "hexahedron"), ("uniform", "tetra"),
                                                           ("adaptive", "tetra")}
    for r in rows:
        assert all(r["converged"].values()) and r["dofs"] > 0 and r["peak_rss_mb"] > 0
        assert r["linear_cycles"] <= r["cycles"]["0.4"] + 2  # the contact state known: no harder than nmg


def check_cork(res):
    assert [r["level"] for r in res["rows"]] == [1, 2]
    for r in res["rows"]:
        assert r["F0.0"]["converged"] and r["F0.4"]["converged"]
        assert r["F0.4"]["push_force"] > r["F0.0"]["push_force"] > 0  # friction resists the push


def check_two_bodies(res):
    assert len(res["cylinders"]) == 8 and len(res["spheres"]) == 2
    for r in res["cylinders"]:
        assert r["nmg"] and r["tnnmg"] and r["linear"] > 0
        assert r["tnnmg"] <= r["nmg"]
    for r in res["spheres"]:
        assert all(r["converged"].values()) and max(r["violation"].values()) < 1e-8


def check_tnnmg_vs_nmg(res):
    assert {r["method"] for r in res} == {"nmg", "tnnmg", "tnnmg-cycle", "tnnmg-coarse"}
    for r in res:
        assert r["converged"] and r["violation"] < 1e-8
        assert r["method"] == "nmg" or r["agreement"] < 1e-7
    steps = lambda m: sum(r["cycles"] for r in res if r["method"] == m)  # noqa: E731
    assert steps("tnnmg") < steps("nmg")


def check_work_precision(res):
    rows = res["rows"]
    assert {r["method"] for r in rows} == {"nmg", "tnnmg", "fixed-point", "linear"}
    for r in rows:
        assert r["final_error"] < 1e-8 and len(r["error"]) == len(r["time"]) == r["cycles"]
    for L in (3, 4):
        by = {r["method"]: r for r in rows if r["level"] == L}
        assert by["fixed-point"]["cycles"] > by["nmg"]["cycles"]


def check_robustness(res):
    assert len(res["scenes"]) == 14 and len(res["coulomb"]) == 8
    for r in res["scenes"] + res["coulomb"]:
        assert r["verified"] and r["finite"], r
    held = res["held"]
    assert {r["scene"].split(",")[0] for r in held} == {"sideways block", "plate on cylinder",
                                                        "plate on cylinder F 0.3", "whole plate", "falling block",
                                                        "thin plate", "lone mesh 2D", "lone mesh 3D"}
    for r in held:
        if r["scene"].startswith("whole plate"):
            # rocking held by the friction of one or two nodes: not yet solved at every level, but a
            # "converged" is always a balanced answer
            assert not r["converged"] or (r["balance"] < 1e-8 and r["violation"] < 1e-6), r
            continue
        # every other scene converges in at most 30 cycles, its forces balancing the load
        assert r["converged"] and r["cycles"] <= 30 and r["balance"] < 1e-8 and r["violation"] < 1e-6, r


def check_linear_multigrid(res):
    assert len(res["2d"]) == 6 and len(res["3d"]) == 12
    for r in res["2d"]:
        assert 0 < r["V33"]["rate"] < r["V11"]["rate"] < 1
    for r in res["3d"]:
        assert 0 < r["V33"]["rate"] < 1
        assert r.get("min_dihedral", 1) > 0 and r.get("min_scaled_jacobian", 1) > 0


def check_cycle_options(res):
    assert set(res["variants"]) >= {"default", "no_petrov_galerkin", "no_upwind", "projected_on", "projected_off"}
    for row in res["rows"]:
        for name, v in row["variants"].items():
            assert v["verified"], (row["case"], row["F"], name)
            assert v["difference"] < 1e-6


def check_load_path(res):
    steps = res["steps"]
    assert len(steps) == 6 and all(s["cycles"] > 0 for s in steps)
    # warm starts never cost more cycles than cold ones in total
    assert sum(s["cycles"] for s in steps) <= sum(s["cold_cycles"] for s in steps)
    assert steps[-1]["contact_halfwidth"] > 0


def check_cycle_time(res):
    rows = res["rows"]
    assert {r["cell"] for r in rows} == {"triangle", "quad"}
    for r in rows:
        assert r["converged"] and r["seconds_per_cycle"] > 0 and r["peak_rss_mb"] > 0
    tri = [r["dofs"] for r in rows if r["cell"] == "triangle"]
    assert all(b > 3 * a for a, b in zip(tri, tri[1:]))


def check_threads(res):
    rows = res["rows"]
    assert {(r["ordering"], r["threads"]) for r in rows} == {("coloured", 1), ("coloured", 2), ("lexicographic", 1)}
    for r in rows:
        assert r["converged"] and r["seconds_per_cycle"] > 0 and r["cycle_bytes"] > 0
    for c in res["counts"]:
        assert abs(c["coloured"] - c["lexicographic"]) <= 2
    assert res["stream_gbs"]["numpy_read_1"] > 0


def check_exact_sums(res):
    rows = res["rows"]
    assert {(r["kind"], r["n"]) for r in rows} == {(k, n) for k in ("sum", "dot") for n in (10_000, 100_000)}
    for r in rows:
        assert r["same"] and r["core_s"] > 0 and r["numpy_reference_s"] > 0
    # the compiled accumulator beats the numpy reference on the larger size (by ~25x and ~70x)
    assert all(r["speedup"] > 3 for r in rows if r["n"] == 100_000)


def check_mpi_scaling(res):
    rows = res["rows"]
    strong = [r for r in rows if r["kind"] == "strong"]
    assert [r["ranks"] for r in strong] == [1, 2]
    # the same displacement bit for bit and the same cycles on every rank count, converged
    assert all(r["bitwise_as_one_rank"] for r in strong)
    assert len({r["cycles"] for r in strong}) == 1
    # the serial solver's cycles within one (another colour order)
    assert all(abs(r["threads_cycles"] - r["cycles"]) <= 1 for r in strong)
    assert all(0 < r["bytes_per_owned_dof"] < 5000 for r in rows)
    # one rank exchanges nothing; two ranks exchange after the colours of their sweeps
    assert strong[0]["exchanges_per_cycle"] == 0 and strong[1]["exchanges_per_cycle"] > 0
    assert strong[0]["whole_levels"] == 0
    assert res["bandwidth"]["read_gb_s_1"] > 0


def check_memory(res):
    for r in res["rows"]:
        assert r["converged"]
        assert r["peak_rss_bytes"] > r["owners"]["fine_matrix"] > 0
        peaks = [s["peak"] for s in r["stages"].values()]
        assert peaks == sorted(peaks)
        assert r["cli_peak_rss_bytes"] > 0


def check_skip_work(res):
    scenes = res["laws"]["scenes"]
    assert all(s["converged"] for s in scenes.values())
    assert scenes["cannot touch (gap 1.0)"]["rebuilds"] == 0 and scenes["no contact boundary"]["rebuilds"] == 0
    assert res["outputs"]["plot_seconds"] > 0
    local = {(r["hierarchy"], r["local"]): r for r in res["local"]}
    for (name, is_local), r in local.items():
        if is_local:  # local smoothing touches fewer rows and needs the same cycles
            full = local[(name, False)]
            assert r["smoothed_rows_per_fine_node"] < full["smoothed_rows_per_fine_node"]
            assert abs(r["cycles"] - full["cycles"]) <= 1


def check_engineering_models(res):
    # every model solves and is checked: equilibrium and the contact conditions
    assert len(res) == 8
    for r in res:
        assert r["converged"] and r["balance"] < 1e-9 and r["conditions"] < 1e-6, r
    # the same model in three systems of units takes the same cycles (the default stop is relative)
    units = [r["cycles"][0] for r in res if r["model"].startswith("rounded block in")]
    assert len(units) == 3 and max(units) - min(units) <= 2


def check_cad_refinement(res):
    geometry, contact = res["geometry"], res["contact"]
    assert {r["model"] for r in geometry} == {"fillet cylinder", "torus"}
    # every new boundary node lies on its CAD surface or curve
    assert all(r["distance"] < 1e-10 for r in geometry)
    for model in ("fillet cylinder", "torus"):
        rows = [r for r in geometry if r["model"] == model and r["coarse mesh"] == "Netgen"]
        caps = [r for r in geometry if r["model"] == model and r["coarse mesh"] == "gmsh"]
        assert rows[0]["caps"] == 0 and caps[0]["caps"] > 0
        # the optimized coarse mesh keeps its quality, the relaxation never lowers it, and gmsh's
        # mesh with caps degrades faster
        assert min(r["min quality"] for r in rows) >= 0.5 * rows[0]["min quality"]
        assert all(r["min quality"] >= r["without relaxation"] for r in rows + caps)
        assert caps[-1]["min quality"] / caps[0]["min quality"] < rows[-1]["min quality"] / rows[0]["min quality"]
    assert all(r["converged"] for r in contact) and len(contact) >= 2
    # level 1 is the same mesh; refined, the faceted body answers differently
    assert contact[0]["force cad"] == contact[0]["force faceted"]
    assert abs(contact[-1]["force cad"] - contact[-1]["force faceted"]) > 0.05 * contact[-1]["force cad"]


def check_one_mesh(res):
    fam = res["families"]
    assert {r["family"] for r in fam} == {"hertz", "sphere"}
    for r in fam:  # every coarse space finds the geometric hierarchy's answer
        assert r["converged"] and r["difference"] < 1e-8, r
    for r in fam:
        if r["space"] == "coarsening":  # the default from one mesh: close to the geometric cycles
            geo = next(g for g in fam if g["family"] == r["family"] and g["size"] == r["size"] and g["space"] == "geometric")
            assert r["cycles"] <= min(30, geo["cycles"] + 3), r
    assert [r["asked"] for r in res["fillet"]] == ["default", "nmg", "tnnmg"]
    assert all(r["converged"] and r["cycles"] <= 30 and r["levels"] >= 2 for r in res["fillet"])
    # with no option given every stress case converges, on every coarse space
    for r in res["stress"]:
        assert r["converged"] and r["difference"] < 1e-6, r
        if r["asked"] == "default":
            assert r["cycles"] <= 30, r


def check_two_body_verification(res):
    every = [r for key in ("roller", "rings", "shells", "hemispheres", "stack", "coarse_alone") for r in res[key]["rows"]]
    assert all(r["converged"] and r["conditions"] < 1e-6 for r in every), [r for r in every if not r["converged"]]
    # no nonmortar node without a condition: symmetry planes keep theirs, curved meshes cover each other
    assert all(r["held"] == 0 and r["uncovered"] == 0 for r in every if r.get("held") is not None)
    roller = res["roller"]["rows"]
    for r in roller:
        if r["model"] == "half":  # the half model is the full one (it was 35 % off at the symmetry node)
            assert abs(r["half/full-1"]) < 0.005, r
        assert r["cycles"] <= 25, r
    assert all(abs(r["peak/p0-1"]) < 0.02 for r in roller if r["friction"] == 0), roller
    for r in res["rings"]["rows"]:  # two meshes of one circle touch everywhere, the pressure near Lame's
        n, total = (int(v) for v in r["in_contact"].split("/"))
        assert n == total and abs(r["q0/q-1"]) < 0.01, r
    stack = res["stack"]["rows"]
    assert all(r["balance_max"] < 1e-8 for r in stack) and any(r["hierarchies"] == "coarsened" for r in stack)
    assert all(r["cycles"] <= 40 for r in res["coarse_alone"]["rows"])


CHECKS = {"paper/table1": check_table1, "paper/hertz_stresses": check_hertz_stresses,
          "paper/algorithm1_vs_2": check_algorithm1_vs_2, "three_d/sphere": check_sphere, "three_d/cork": check_cork,
          "three_d/two_bodies": check_two_bodies, "methods/tnnmg_vs_nmg": check_tnnmg_vs_nmg,
          "methods/work_precision": check_work_precision, "methods/robustness": check_robustness,
          "methods/linear_multigrid": check_linear_multigrid, "methods/cycle_options": check_cycle_options,
          "methods/load_path": check_load_path, "performance/cycle_time": check_cycle_time,
          "performance/threads": check_threads, "performance/memory": check_memory,
          "performance/skip_work": check_skip_work,
          "performance/exact_sums": check_exact_sums,
          "performance/mpi_scaling": check_mpi_scaling, "model/engineering_models": check_engineering_models,
          "model/cad_refinement": check_cad_refinement, "model/one_mesh": check_one_mesh,
          "model/two_body_verification": check_two_body_verification}


def test_every_script_is_checked_and_documented():
    assert set(SCRIPTS) == set(CHECKS)
    assert len(SCRIPTS) + 1 <= 23  # with run_all.py
    for name in SCRIPTS + ["run_all", "_common", "two_body_scenes"]:
        doc = ast.get_docstring(ast.parse((BENCHMARKS / f"{name}.py").read_text()))
        assert doc and "python benchmarks/" in doc or name in ("_common", "two_body_scenes"), name
        assert not HISTORY.search(doc), (name, HISTORY.search(doc).group(0))


@pytest.mark.parametrize("name", SCRIPTS)
def test_quick(name, tmp_path):
    out = tmp_path / "result.json"
    r = run([str(BENCHMARKS / f"{name}.py"), "--quick", "--json", str(out)], tmp_path)
    assert r.stdout.strip()
    data = json.loads(out.read_text())
    assert data["benchmark"] == name and data["mode"] == "quick"
    assert data["commit"] and data["date"] and data["machine"]["cores"] >= 1
    CHECKS[name](data["results"])


def test_run_all_runs_the_selected_scripts(tmp_path):
    r = run([str(BENCHMARKS / "run_all.py"), "--quick", "--out", str(tmp_path / "o"), "--only", "methods/load_path"],
            tmp_path)
    assert "methods/load_path: exit status 0" in r.stdout
    assert json.loads((tmp_path / "o" / "methods" / "load_path.json").read_text())["mode"] == "quick"
