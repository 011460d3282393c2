"""The documentation site builds in strict mode (broken links, unparsable docstrings and missing
pages fail it), its API pages document the public classes, and the benchmark pages are generated
from the recorded results."""
import importlib.util
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytest.importorskip("mkdocs")
pytest.importorskip("mkdocstrings")
pytest.importorskip("material")


def _generator():
    spec = importlib.util.spec_from_file_location("gen_benchmark_pages", ROOT / "docs" / "gen_benchmark_pages.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_benchmark_pages_show_every_recorded_result(tmp_path):
    pages = _generator().generate(ROOT / "benchmarks" / "results", tmp_path)
    text = {p.name: p.read_text() for p in pages}
    files = sorted((ROOT / "benchmarks" / "results").glob("*/*.json"))
    assert files, "no recorded benchmark results"
    for f in files:
        data = json.loads(f.read_text())
        page = text[f"{f.parent.name}.md"]
        assert f"## {data['benchmark']}" in page
        assert str(data["commit"])[:12] in page and data["date"] in page  # the stamp of the measurement
        assert str(data["machine"]["cores"]) + " cores" in page
    # a table of the Table 1 benchmark: one row per friction coefficient, one column per level
    table1 = json.loads((ROOT / "benchmarks/results/paper/table1.json").read_text())["results"]
    assert "#### fixed_point_vcycles" in text["paper.md"]
    assert text["paper.md"].count("\n| " + str(len(table1["frictions"])) + " | ") >= 1



def test_site_builds_strict_with_the_api_pages(tmp_path):
    import contactmg
    if not hasattr(contactmg, "Solver"):
        pytest.skip("contactmg.Solver is not there yet (the API pages document it)")
    site = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    api = {name: (site / "api" / name / "index.html").read_text() for name in ("mesh", "model", "results", "solve")}
    for name in ("Mesh", "MeshHierarchy"):
        assert f'id="contactmg.mesh' in api["mesh"] and name in api["mesh"]
    for name in ("Problem", "Body", "ContactPair", "Dirichlet", "Material", "Coulomb", "Tresca", "PlaneObstacle"):
        assert name in api["model"], name
    assert "ContactResult" in api["results"]
    for name in ("SolverOptions", "resolve_options", "Solver", "LoadPath", "adaptive_hierarchy"):
        assert f'id="contactmg.solve.' in api["solve"] and name in api["solve"], name
    # the guide's options table and the theory's math made it into the site
    assert "projected_coarse_correction" in (site / "guide" / "solver-options" / "index.html").read_text()
    assert "arithmatex" in (site / "theory" / "problem" / "index.html").read_text()
    assert (site / "changelog" / "index.html").read_text().count("0.2.0") >= 1
    assert len(list((site / "dev" / "decisions").glob("0*/index.html"))) == 18
