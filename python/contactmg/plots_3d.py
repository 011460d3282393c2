"""3D plots: contact stresses of the Hertz sphere against the radius, and the deformed cork in its
neck (the seed paper's Figure 2, right) with matplotlib's 3D axes. Each helper takes ax=None and
returns the axes it drew on."""
from __future__ import annotations

from typing import Dict, Optional

import numpy as np

from .results import FREE, SLIP, STICK

STICK_COLOR, SLIP_COLOR, FREE_COLOR = "tab:green", "tab:orange", "lightgray"
STATE_COLORS = {STICK: STICK_COLOR, SLIP: SLIP_COLOR, FREE: FREE_COLOR}


def radial_stress_data(result, center=(0.0, 0.0), margin: float = 1.5) -> Dict[str, np.ndarray]:
    """Contact nodes within margin * (contact radius) of the axis through `center`, sorted by the
    radius r: r, normal stress, tangential stress magnitude, state."""
    x = result.mesh.points[result.contact_nodes]
    r = np.hypot(x[:, 0] - center[0], x[:, 1] - center[1])
    sel = np.isin(result.contact_state, (STICK, SLIP))
    width = float(r[sel].max()) if np.any(sel) else float(r.max())
    idx = np.flatnonzero(r <= margin * width)
    idx = idx[np.argsort(r[idx], kind="stable")]
    return {"index": idx, "r": r[idx], "normal": result.normal_stress[idx],
            "tangential": np.linalg.norm(result.tangential_stress[idx], axis=1), "state": result.contact_state[idx]}


def plot_radial_stress(result, ax=None, hertz: Optional[Dict[str, float]] = None, center=(0.0, 0.0)):
    """Normal stress (as pressure -s_n, blue dots) and tangential stress |s_T| (red) of the contact
    nodes against their distance from the axis; the stick and slip zones shaded (a node's zone spans
    from its own radius to the next node's); with `hertz` ({"radius": a, "p0": p0}) Hertz's
    pressure p0 sqrt(1 - (r/a)^2) as a line."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 4))
    d = radial_stress_data(result, center)
    r, st = d["r"], d["state"]
    ax.plot(r, -d["normal"], "o", ms=3, color="tab:blue", label="pressure $-\\sigma_n$")
    ax.plot(r, d["tangential"], "s", ms=3, color="tab:red", label="$|\\sigma_T|$")
    stick_r = r[st == STICK]
    slip_r = r[st == SLIP]
    if len(stick_r):
        ax.axvspan(0.0, stick_r.max(), color=STICK_COLOR, alpha=0.15, label="stick")
    if len(slip_r):
        ax.axvspan(stick_r.max() if len(stick_r) else 0.0, slip_r.max(), color=SLIP_COLOR, alpha=0.15, label="slip")
    if hertz:
        rr = np.linspace(0, hertz["radius"], 200)
        ax.plot(rr, hertz["p0"] * np.sqrt(np.clip(1 - (rr / hertz["radius"]) ** 2, 0, None)), "-", color="k", lw=1,
                label="Hertz")
    ax.set_xlabel("distance from the axis r")
    ax.set_ylabel("contact stress")
    ax.legend(loc="upper right", fontsize=8)
    return ax


def face_states(facets: np.ndarray, node_state: np.ndarray) -> np.ndarray:
    """The state a boundary face is drawn in: STICK if all its nodes stick, SLIP if all its nodes
    are in contact and one slips, FREE otherwise."""
    s = node_state[facets]
    in_contact = np.all(s > 0, axis=1)
    out = np.full(len(facets), FREE, dtype=np.int8)
    out[in_contact & np.all(s == STICK, axis=1)] = STICK
    out[in_contact & np.any(s == SLIP, axis=1)] = SLIP
    return out


def plot_cork(problem, result, ax=None, scale: Optional[float] = None, neck=None, z_range=None):
    """The deformed cork, its boundary faces coloured by contact state (stick green, slip orange,
    free grey), the neck's wall drawn transparent. `scale` magnifies the displacement (default:
    the largest displacement drawn as 3 % of the cork's size). Returns the axes; the faces are the
    collection labelled "cork", coloured by `face_states`."""
    import matplotlib.colors as mcolors
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if ax is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(6, 7))
        ax = fig.add_subplot(projection="3d")
    mesh = result.mesh
    X = mesh.points
    size = float(np.ptp(X, axis=0).max())
    umax = float(np.abs(result.displacement).max())
    if scale is None:
        scale = 0.03 * size / umax if umax > 0 else 1.0
    Y = X + scale * result.displacement
    facets = mesh.facets
    states = face_states(facets, result.node_state)
    # one collection, so that matplotlib sorts all faces by depth together (separate collections
    # are stacked whole, and the bottom face would hide the side)
    colors = np.array([mcolors.to_rgba(STATE_COLORS[int(s)]) for s in states]).reshape(-1, 4)
    poly = Poly3DCollection(Y[facets], facecolors=colors, edgecolors=(0, 0, 0, 0.25), linewidths=0.2, label="cork")
    ax.add_collection3d(poly)
    if neck is not None:
        zlo, zhi = z_range if z_range is not None else (X[:, 2].min() - 0.1 * size, X[:, 2].max() + 0.1 * size)
        z = np.linspace(zlo, zhi, 30)
        th = np.linspace(0, 2 * np.pi, 49)
        Z, T = np.meshgrid(z, th)
        R = neck.radius(Z)
        ax.plot_surface(R * np.cos(T), R * np.sin(T), Z, color="tab:blue", alpha=0.08, linewidth=0, shade=False)
        ax.plot_wireframe(R * np.cos(T), R * np.sin(T), Z, color="tab:blue", alpha=0.15, linewidth=0.3,
                          rstride=4, cstride=6)
    lo, hi = Y.min(axis=0), Y.max(axis=0)
    c, h = 0.5 * (lo + hi), 0.6 * float((hi - lo).max())
    ax.set_xlim(c[0] - h, c[0] + h)
    ax.set_ylim(c[1] - h, c[1] + h)
    ax.set_zlim(c[2] - h, c[2] + h)
    ax.set_box_aspect((1, 1, 1))
    ax.set_title(f"stick (green), slip (orange), free (grey); displacement x{scale:.3g}", fontsize=9)
    return ax
