"""The stick/slip notebook executes and its numbers make sense."""
import json
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "stick_slip.ipynb"


def test_stick_slip_notebook_executes():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            assert out.get("output_type") != "error", out
    last = nb.cells[-1]["outputs"][0]["text"]
    summary = json.loads(last)
    frac = summary["stick_fraction"]
    # the stick zone grows with F and covers the whole contact zone for F = 8
    assert frac["0.08"] < frac["0.4"] < frac["2.0"] <= frac["8.0"] == pytest.approx(1.0, abs=0.1)
    conv = summary["convergence"]
    assert conv["fixed_point_cycles"] > 3 * conv["nmg_cycles"]
