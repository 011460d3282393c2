"""The stick/slip notebook executes, shows its figures and its numbers make sense."""
import json
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOK = Path(__file__).resolve().parents[2] / "notebooks" / "stick_slip.ipynb"


def _kernel_name():
    """The notebook's kernel if it is installed, else the running interpreter's own ipykernel
    (jupyter_client always offers it as "python3" when ipykernel is importable)."""
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    ksm = KernelSpecManager()
    try:
        ksm.get_kernel_spec("python3")
        return "python3"
    except NoSuchKernel:  # pragma: no cover - depends on the machine
        pytest.skip("no python3 Jupyter kernel: run `python -m ipykernel install --user`")


# the cells that draw: the stresses for four F, the tangential stress over the levels, the
# correction histories, Figure 1
PLOTTING_CELLS = 4


def test_stick_slip_notebook_executes(monkeypatch):
    # a non-interactive backend in the environment (as on a test machine) must not hide the
    # figures: the notebook selects the inline backend itself
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name=_kernel_name(),
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            assert out.get("output_type") != "error", out
    # every cell that creates a figure shows it as a picture, one picture per figure
    drawing = [c for c in nb.cells if c.cell_type == "code" and ("plt.subplots" in c.source or "plot_" in c.source)
               and "import" not in c.source]
    assert len(drawing) == PLOTTING_CELLS
    for cell in drawing:
        pngs = [o for o in cell.outputs if o.get("output_type") == "display_data" and "image/png" in o.get("data", {})]
        assert len(pngs) == 1, cell.source[:80]
        assert len(pngs[0]["data"]["image/png"]) > 10000  # a picture, not an empty canvas
    assert not any("matplotlib.use(" in c.source for c in nb.cells if c.cell_type == "code")
    last = [o for o in nb.cells[-1]["outputs"] if o.get("name") == "stdout"][0]["text"]
    summary = json.loads(last)

    # the stick zone grows with F and covers the whole contact zone for F = 8; none for F = 0.08
    frac = summary["stick_fraction"]
    assert frac["0.08"] < frac["0.4"] < frac["2.0"] <= frac["8.0"]
    assert frac["8.0"] == pytest.approx(1.0) and frac["0.4"] < 0.6
    # every solve shown is a solution (independent residual check) and friction raises the load a little
    loads = [summary[f"F={F}"]["load"] for F in ("0.08", "0.4", "2.0", "8.0")]
    assert all(summary[f"F={F}"]["violation"] < 1e-8 for F in ("0.08", "0.4", "2.0", "8.0"))
    assert loads == sorted(loads) and loads[-1] < 1.05 * loads[0]
    # the half-widths settle with the level
    a = [summary[f"level={L}"]["contact_halfwidth"] for L in (4, 5, 6, 7)]
    assert max(a) - min(a) < 0.25 * a[-1]

    # Algorithm 1 reaches Algorithm 2's solution at several times its V-cycles
    conv = summary["convergence"]
    assert conv["relative_difference"] < 1e-8
    assert conv["fixed_point_cycles"] > 3 * conv["nmg_cycles"]
    # over the levels: nmg V-cycles stay flat, Algorithm 1's outer iterations grow
    tab = summary["table"]
    for i, F in enumerate(tab["frictions"]):
        nmg, its = tab["nmg_vcycles"][i], tab["fixed_point_iterations"][i]
        assert max(nmg) - min(nmg) <= 4, (F, nmg)
        assert its[-1] > its[0], (F, its)
        assert all(f > n for f, n in zip(tab["fixed_point_vcycles"][i], nmg))
