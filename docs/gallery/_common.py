"""Shared by the gallery scripts: where the pictures go and the Hertz problem they start from."""
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import contactmg as cm  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parent / "images"


def out_dir(argv=None) -> Path:
    """The folder to write into: the first argument, else $CONTACTMG_GALLERY_OUT, else docs/gallery/images."""
    argv = sys.argv[1:] if argv is None else argv
    path = Path(argv[0]) if argv else Path(os.environ.get("CONTACTMG_GALLERY_OUT", DEFAULT_DIR))
    path.mkdir(parents=True, exist_ok=True)
    return path


def hertz_problem(levels: int, friction, top=-0.005) -> "cm.Problem":
    """The paper's Hertz problem: a half disk of radius 0.4 (E = 2000, nu = 0.28) pushed down by
    `top` on its upper edge onto the rigid plane y = 0."""
    h = cm.MeshHierarchy.build(cm.hertz_half_disk("triangle"), levels=levels, projector=cm.hertz_projector())
    body = cm.Body(h, cm.Material(E=2000.0, nu=0.28),
                   dirichlet=[cm.Dirichlet([cm.HERTZ_TOP], (0.0, top))],
                   contact_tags=[cm.HERTZ_ARC])
    return cm.Problem(body, obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=friction)


def stress_figure(result, a_hertz: float, name: str, argv=None, title=None) -> dict:
    """The boundary stresses of `result` with Hertz's half-width marked, saved as `name`.png."""
    import matplotlib.pyplot as plt
    from contactmg.results import plots

    fig, ax = plt.subplots(figsize=(7, 4))
    plots.plot_boundary_stress(result, ax=ax, margin=1.5)
    ax.axvline(-a_hertz, color="k", ls=":", lw=1, label="Hertz half-width")
    ax.axvline(a_hertz, color="k", ls=":", lw=1)
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path = out_dir(argv) / f"{name}.png"
    fig.savefig(path, dpi=110)
    return {"figure": fig, "path": path, "result": result, "hertz_halfwidth": a_hertz,
            "halfwidth": result.halfwidth()}
