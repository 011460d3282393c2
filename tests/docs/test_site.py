"""The documentation site builds in strict mode (broken links, unparsable docstrings and missing
pages fail it) and its API pages document the public classes."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytest.importorskip("mkdocs")
pytest.importorskip("mkdocstrings")
pytest.importorskip("material")


def test_site_builds_strict_with_the_api_pages(tmp_path):
    site = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
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
    records = list((ROOT / "docs" / "dev" / "decisions").glob("0*.md"))
    assert len(records) >= 18
    assert len(list((site / "dev" / "decisions").glob("0*/index.html"))) == len(records)  # every record built
