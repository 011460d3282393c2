"""3D plots: contact stresses of the Hertz sphere against the radius, the deformed cork in its neck
(the seed paper's Figure 2, right) with matplotlib's 3D axes, and the cork's side against the neck's
tapered wall in a cross-section. Each helper takes ax=None and returns the axes it drew on."""
from __future__ import annotations

from typing import Dict, Optional

import numpy as np

from ..results.result import FREE, SLIP, STICK

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


def plot_cork(problem, result, ax=None, scale: Optional[float] = None, neck=None, z_range=None,
              length_unit: str = "mm"):
    """The deformed cork, its boundary faces coloured by contact state (stick green, slip orange,
    free grey, with a legend), the neck's wall drawn transparent, the axes labelled in
    `length_unit`. `scale` magnifies the displacement (default: the largest displacement drawn as
    3 % of the cork's size). Returns the axes; the faces are the collection labelled "cork",
    coloured by `face_states`."""
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
    for set_label, name in ((ax.set_xlabel, "x"), (ax.set_ylabel, "y"), (ax.set_zlabel, "z")):
        set_label(f"{name} ({length_unit})")
    from matplotlib.patches import Patch

    ax.legend(handles=[Patch(facecolor=STATE_COLORS[k], edgecolor="0.3", label=name)
                       for k, name in ((STICK, "stick"), (SLIP, "slip"), (FREE, "no contact"))],
              loc="upper left", fontsize=9, title="surface", title_fontsize=9)
    ax.set_title(f"deformed cork, displacement magnified {scale:.3g}x", fontsize=10)
    return ax


def side_section_data(result, axis_point=(0.0, 0.0)) -> Dict[str, np.ndarray]:
    """The contact boundary of a body of revolution about the z axis through `axis_point`, as seen
    in a meridian section: per contact node (order of contact_nodes) its deformed distance from
    the axis r = |(x + u)_xy - axis_point|, deformed height z + u_z, the contact pressure -s_n
    (0 where not in contact) and the contact state."""
    x = result.mesh.points[result.contact_nodes] + result.displacement[result.contact_nodes]
    r = np.hypot(x[:, 0] - axis_point[0], x[:, 1] - axis_point[1])
    state = result.contact_state
    pressure = np.where(state > 0, -result.normal_stress, 0.0)
    return {"r": r, "z": x[:, 2], "pressure": pressure, "state": state}


def plot_cork_section(result, neck, ax=None, radius: Optional[float] = None, length_unit: str = "mm",
                      stress_unit: str = "MPa", colorbar: bool = True):
    """The cork's side against the neck's tapered wall in a meridian section (distance from the
    axis r against the height z, the r axis zoomed so that the taper shows): the wall's profile
    r = neck.radius(z) as a line (label "neck wall"), the undeformed side r = `radius` dashed, and
    every contact node of the side at its deformed (r, z): in contact coloured by its contact
    pressure -s_n (colour bar "contact pressure (MPa)"; marker o stick, ^ slip), out of contact as
    grey dots. Returns the axes; the nodes in contact are the collection labelled "in contact"."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 7))
    d = side_section_data(result)
    r, z, p, st = d["r"], d["z"], d["pressure"], d["state"]
    zall = result.mesh.points[:, 2] + result.displacement[:, 2]  # the whole cork, not its side's nodes only
    zlo, zhi = float(zall.min()), float(zall.max())
    pad = 0.1 * (zhi - zlo)
    zz = np.linspace(zlo - pad, zhi + pad, 400)
    wall = np.asarray(neck.radius(zz), float)
    ax.plot(wall, zz, "-", color="k", lw=2.0, label="neck wall", zorder=4)
    ax.fill_betweenx(zz, wall, wall.max() + 1.0, color="0.85", zorder=0)
    if radius is not None:
        ax.axvline(radius, color="0.4", ls="--", lw=1, label=f"cork, undeformed (r = {radius:g} {length_unit})")
    free = st == FREE
    ax.scatter(r[free], z[free], s=6, color="0.55", label="no contact", zorder=2)
    on = ~free
    vmax = float(p[on].max()) if np.any(on) else 1.0
    sc = None
    for code, marker, name in ((STICK, "o", "stick"), (SLIP, "^", "slip")):
        sel = st == code
        if not np.any(sel):
            continue
        sc = ax.scatter(r[sel], z[sel], c=p[sel], cmap="viridis", vmin=0.0, vmax=vmax, marker=marker, s=22,
                        edgecolors="k", linewidths=0.3, zorder=3, label=f"in contact: {name}")
        sc.set_gid("in contact")
    if colorbar and sc is not None:
        cb = ax.figure.colorbar(sc, ax=ax, pad=0.02)
        cb.set_label(f"contact pressure $-\\sigma_n$ ({stress_unit})")
    lo = min(float(wall.min()), float(r.min()), radius if radius is not None else np.inf)
    hi = max(float(r.max()), radius if radius is not None else -np.inf)
    span = hi - lo
    ax.set_xlim(lo - 0.3 * span, hi + 0.3 * span)
    ax.set_ylim(zz[0], zz[-1])
    ax.set_xlabel(f"distance from the axis r ({length_unit})")
    ax.set_ylabel(f"height z ({length_unit})")
    ax.set_title("side of the cork against the neck's wall\n(r axis zoomed: the taper)", fontsize=10)
    # the contact markers' legend entries in white: their colour is the pressure, read on the bar
    handles, labels = ax.get_legend_handles_labels()
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], ls="none", marker="o" if "stick" in lab else "^", mfc="w", mec="k",
                      ms=6) if lab.startswith("in contact") else h for h, lab in zip(handles, labels)]
    ax.legend(handles, labels, loc="upper left", fontsize=8)
    return ax
