"""The gallery scripts run, write their pictures, and draw what they claim: the Hertz half-width,
the friction laws' bounds, a load path's growing contact zone."""
import importlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

GALLERY = Path(__file__).resolve().parents[2] / "docs" / "gallery"
SCRIPTS = sorted(p.stem for p in GALLERY.glob("*.py") if not p.stem.startswith("_"))


@pytest.fixture(scope="module")
def gallery():
    sys.path.insert(0, str(GALLERY))
    try:
        yield lambda name: importlib.import_module(name)
    finally:
        sys.path.remove(str(GALLERY))


def test_every_script_is_tested():
    assert set(SCRIPTS) == {"hertz_stresses", "friction_laws", "load_path", "adaptive_hierarchy", "two_cylinders"}


def test_hertz_stresses(gallery, tmp_path):
    out = gallery("hertz_stresses").main([str(tmp_path)])
    assert out["path"] == tmp_path / "hertz_stresses.png" and out["path"].stat().st_size > 10_000
    assert out["result"].converged
    # the plotted contact zone has Hertz's half-width (within 10 %)
    assert out["halfwidth"] == pytest.approx(out["hertz_halfwidth"], rel=0.10)
    ax = out["figure"].axes[0]
    assert ax.get_xlabel() == "x" and ax.get_ylabel() == "boundary stress"
    labels = [line.get_label() for line in ax.get_lines()]
    assert "normal stress" in labels and "tangential stress" in labels
    normal = next(line for line in ax.get_lines() if line.get_label() == "normal stress").get_ydata()
    assert np.all(normal <= 1e-9) and normal.min() < 0  # compression is negative


def test_friction_laws(gallery, tmp_path):
    out = gallery("friction_laws").main([str(tmp_path)])
    assert (tmp_path / "friction_laws.png").is_file()
    top, bottom = out["figure"].axes
    assert len(top.get_lines()) == 3 and len(bottom.get_lines()) == 3
    assert bottom.get_ylabel() == "tangential stress" and bottom.get_xlabel() == "x"
    t = {line.get_label(): np.asarray(line.get_ydata()) for line in bottom.get_lines()}
    n = {line.get_label(): np.asarray(line.get_ydata()) for line in top.get_lines()}
    assert np.abs(t["frictionless"]).max() < 1e-8
    assert np.abs(t["Tresca, bound 20"]).max() <= 20 * (1 + 1e-6)
    assert np.abs(t["Tresca, bound 20"]).max() > 19  # the bound is reached where it slips
    coulomb = "Coulomb, F = 0.4"
    assert np.all(np.abs(t[coulomb]) <= 0.4 * np.abs(n[coulomb]) * (1 + 1e-6) + 1e-9)
    assert all(r.converged for r in out["results"].values())


def test_load_path(gallery, tmp_path):
    out = gallery("load_path").main([str(tmp_path)])
    assert (tmp_path / "load_path.png").is_file()
    assert out["result"].converged and len(out["result"].steps) == 5
    contact, stick = out["contact"], out["stick"]
    assert np.all(np.diff(contact) > 0)  # the contact zone grows with the load
    assert np.all(stick <= contact)
    left, right = out["figure"].axes
    assert len(right.patches) == 5  # one bar of cycles per step
    assert right.get_ylabel() == "multigrid cycles"


def test_adaptive_hierarchy(gallery, tmp_path):
    out = gallery("adaptive_hierarchy").main([str(tmp_path)])
    assert (tmp_path / "adaptive_hierarchy.png").is_file()
    h, dofs = out["hierarchy"], out["dofs"]
    assert h.levels == 6 and np.all(np.diff(dofs) > 0)
    est = np.array(h.estimated_error)
    assert len(est) == h.levels and np.all(np.diff(est) < 0)  # the estimate falls on every level
    # the refinement concentrates at the contact zone: cells there are far smaller than at the top
    mesh = h.finest
    centroids = mesh.points[mesh.cells].mean(axis=1)
    p = mesh.points[mesh.cells]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    near = (np.abs(centroids[:, 0]) < 0.04) & (centroids[:, 1] < 0.02)
    far = centroids[:, 1] > 0.3
    assert near.any() and far.any()
    assert area[near].mean() < area[far].mean() / 20
    ax, ax2 = out["figure"].axes
    assert ax2.get_xlabel() == "unknowns" and ax2.get_xscale() == "log"


def test_two_cylinders(gallery, tmp_path):
    out = gallery("two_cylinders").main([str(tmp_path)])
    assert (tmp_path / "two_cylinders.png").is_file()
    assert out["result"].converged
    # the interface's contact zone has the two-body Hertz half-width (within 10 %: the discrete
    # half-width is the last node in contact, up to one node spacing short)
    assert out["halfwidth"] == pytest.approx(out["hertz_halfwidth"], rel=0.10)
    ax = out["figure"].axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    n, t = lines["normal stress"].get_ydata(), lines["tangential stress"].get_ydata()
    # Coulomb's bound holds (to round-off of the largest stress: a free node keeps forces of 1e-11 of it)
    assert np.all(np.abs(t) <= 0.4 * np.abs(n) * (1 + 1e-6) + 1e-9 * np.abs(n).max())
    # the tangential stress is odd about the centre (the same curvature above and below)
    assert abs(t.max() + t.min()) < 0.05 * t.max()


def test_output_folder_from_the_environment(tmp_path):
    env = dict(os.environ, CONTACTMG_GALLERY_OUT=str(tmp_path / "env"))
    run = subprocess.run([sys.executable, str(GALLERY / "load_path.py")], env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "env" / "load_path.png").is_file()
