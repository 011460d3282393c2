"""The stick and slip zones of a load path against the load step: one row of markers per step at
the contact nodes' positions (a coordinate in 2D, the distance from an axis in 3D), stick and slip
coloured as in plot_boundary_stress, the zone half-widths as lines."""
from __future__ import annotations

from typing import Callable, Optional

import numpy as np

from ..results.result import SLIP, STICK

STICK_COLOUR, SLIP_COLOUR = "tab:blue", "tab:red"


def plot_zones_over_steps(path_result, ax=None, position: Optional[Callable] = None, label: str = "x"):
    """Markers at (position of node, step) for sticking and sliding contact nodes of every step of
    `path_result` (a PathResult). position(result) -> one value per contact node (default: the
    x coordinate). Returns the axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    position = position or (lambda r: r.mesh.points[r.contact_nodes, 0])
    steps = []
    stick_w, contact_w = [], []
    for r in path_result.steps:
        k = r.extra["step"]
        x = np.asarray(position(r))
        s = r.contact_state
        for state, colour, name in ((STICK, STICK_COLOUR, "stick"), (SLIP, SLIP_COLOUR, "slip")):
            sel = s == state
            ax.plot(x[sel], np.full(sel.sum(), k), "|", color=colour, ms=6, label=name if k == 1 else None)
        steps.append(k)
        stick_w.append(np.abs(x[s == STICK]).max() if np.any(s == STICK) else 0.0)
        contact_w.append(np.abs(x[s > 0]).max() if np.any(s > 0) else 0.0)
    ax.plot(stick_w, steps, "-", color=STICK_COLOUR, lw=0.8, label="stick half-width")
    ax.plot(contact_w, steps, "--", color="0.3", lw=0.8, label="contact half-width")
    ax.set_xlabel(label)
    ax.set_ylabel("load step")
    ax.legend(fontsize=8, loc="best")
    return ax
