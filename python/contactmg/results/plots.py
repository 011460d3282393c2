"""Plots in the paper's style (matplotlib). Every helper takes ax=None (a new figure then) and
returns the axes it drew on.

- plot_boundary_stress: Figure 2 (middle), boundary stresses with stick and slip zones;
- plot_convergence: Figure 1 (left), total cycles against the number of nodes, Algorithm 1 and
  Algorithm 2 in two panels (plot_cycles draws one);
- plot_fixed_point_iterations: Figure 1 (right), Algorithm 1's outer iterations per level and F;
- plot_table1: Table 1 as a table image;
- plot_correction_history: ||u^{k+1} - u^k||_A against the cycle for several solves.
"""
from __future__ import annotations

from typing import Dict, Iterable, List, Optional, Sequence

import numpy as np

from ..results.checks import VIOLATION_TOL
from ..results.result import SLIP, STICK

STICK_COLOR, SLIP_COLOR = "tab:green", "tab:orange"
_MARKERS = "os^vD<>ph*"


def _axes(ax, **kw):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(**kw)
    return ax


def _zones(x, mask):
    """Contiguous runs of True in mask (x sorted) as (x_start, x_end) spans that reach half-way to
    the neighbouring nodes (to the node itself at either end): every node of the run lies inside its
    span and every node outside the run lies outside it."""
    spans = []
    i, n = 0, len(x)
    while i < n:
        if not mask[i]:
            i += 1
            continue
        j = i
        while j + 1 < n and mask[j + 1]:
            j += 1
        lo = x[i] if i == 0 else 0.5 * (x[i - 1] + x[i])
        hi = x[j] if j == n - 1 else 0.5 * (x[j] + x[j + 1])
        spans.append((float(lo), float(hi)))
        i = j + 1
    return spans


def result_friction(result) -> Optional[float]:
    """The Coulomb coefficient a result was computed with, read off its friction bound
    (F |s_n| at the nodes in contact), or None when the law is not Coulomb or nothing is pressed."""
    if getattr(result, "law", None) != "coulomb":
        return None
    sn = np.abs(result.contact_force[:, 0])
    sel = (result.contact_state > 0) & (sn > 1e-12 * max(sn.max(initial=0.0), 1e-300))
    if not np.any(sel):
        return None
    return float(np.median(result.friction_bound[sel] / sn[sel]))


_AXES = {"x": 0, "y": 1, "z": 2}


def _position(result, along) -> tuple:
    """(position of each contact node, axis label) for along = "x"/"y"/"z"/0/1/2 or "arc"."""
    if along == "arc":
        return result.arc_length(), "arc length along the contact boundary"
    axis = _AXES.get(along, along)
    if isinstance(axis, bool) or not isinstance(axis, (int, np.integer)) or not 0 <= axis < result.mesh.dim:
        names = "/".join(list(_AXES)[:result.mesh.dim])
        raise ValueError(f"along must be one of {names}, an axis 0..{result.mesh.dim - 1} or 'arc', got {along!r}")
    return result.mesh.points[result.contact_nodes, int(axis)], "xyz"[int(axis)]


def boundary_stress_data(result, margin: Optional[float] = None, along="x") -> Dict[str, np.ndarray]:
    """The data plot_boundary_stress draws: the contact nodes sorted by their position `along` a
    coordinate ("x", "y", "z" or an axis number) or the arc length of the 2D contact boundary
    ("arc"), with their normal and tangential stress and contact state. Every contact node is
    kept unless `margin` is given: then only the nodes with |x| <= margin * the contact half-width
    (the Hertz view, zones centred on x = 0; all nodes when nothing is in contact)."""
    x, label = _position(result, along)
    sel = np.ones(len(x), bool)
    if margin is not None:
        axis = 0 if along == "arc" else int(_AXES.get(along, along))
        width = result.halfwidth(axis=axis)
        if width > 0:
            sel = np.abs(result.mesh.points[result.contact_nodes, axis]) <= margin * width
    idx = np.flatnonzero(sel)
    idx = idx[np.argsort(x[idx], kind="stable")]
    return {"index": idx, "x": x[idx], "normal": result.normal_stress[idx],
            "tangential": result.tangential_stress[idx, 0], "state": result.contact_state[idx],
            "bound": result.friction_bound[idx] / result.measure[idx], "label": label}


def plot_boundary_stress(result, ax=None, friction: Optional[float] = None, margin: Optional[float] = None,
                         along="x"):
    """Figure 2 (middle) of the paper: normal (blue) and tangential (red) boundary stress at the
    contact nodes against a coordinate or the arc length (`along`, see boundary_stress_data; every
    node unless `margin` crops to |x| <= margin * the contact half-width, the paper's view of the
    Hertz problem with margin=1.5), the Coulomb bound +-F|sigma_n| dashed (F = `friction`, else the
    coefficient read off the result; for Tresca the given bound), stick zones (green) and slip
    zones (orange) shaded. A shaded span reaches half-way to the neighbouring nodes on either
    side. In 3D the first tangential component is drawn."""
    ax = _axes(ax, figsize=(7, 4))
    data = boundary_stress_data(result, margin, along)
    xs, sn, st, state = data["x"], data["normal"], data["tangential"], data["state"]
    for k, (lo, hi) in enumerate(_zones(xs, state == STICK)):
        ax.axvspan(lo, hi, color=STICK_COLOR, alpha=0.18, lw=0, label="stick" if k == 0 else None)
    for k, (lo, hi) in enumerate(_zones(xs, state == SLIP)):
        ax.axvspan(lo, hi, color=SLIP_COLOR, alpha=0.18, lw=0, label="slip" if k == 0 else None)
    ax.plot(xs, sn, "-", color="tab:blue", marker=".", ms=4, label="normal stress")
    ax.plot(xs, st, "-", color="tab:red", marker=".", ms=4, label="tangential stress")
    if friction is None:
        friction = result_friction(result)
    bound = None
    if friction is not None and friction > 0:
        bound = friction * np.abs(sn)
        name = r"$\pm F|\sigma_n|$"
    elif getattr(result, "law", None) == "tresca":
        bound, name = data["bound"], "Tresca bound"
    if bound is not None:
        ax.plot(xs, bound, "--", color="0.35", lw=1, label=name)
        ax.plot(xs, -bound, "--", color="0.35", lw=1)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel(data["label"])
    ax.set_ylabel("boundary stress")
    ax.set_title(f"{result.method}, {result.law}" + (f", F = {friction:g}" if friction is not None else ""))
    ax.legend(loc="best", fontsize=8)
    return ax


def _method_name(method: str) -> str:
    return {"fixed-point": "Algorithm 1 (fixed point)", "nmg": "Algorithm 2 (nmg)"}.get(method, method)


def plot_correction_history(results, ax=None, labels: Optional[Sequence[str]] = None):
    """Correction norm ||u^{k+1} - u^k||_A against the cycle (log y) for one or more results. The
    legend names the method and the friction coefficient (read off each result) unless `labels`
    are given. For Algorithm 1 the cycles run on across its outer iterations."""
    ax = _axes(ax, figsize=(6, 4))
    if not isinstance(results, (list, tuple)):
        results = [results]
    for k, r in enumerate(results):
        if labels is not None:
            label = labels[k]
        else:
            F = result_friction(r)
            label = _method_name(r.method) + (f", F={F:g}" if F is not None else f" ({r.law})")
            if r.outer_iterations is not None:
                label += f", {r.outer_iterations} outer"
        ax.semilogy(r.history["cycle"], r.history["correction_norm"], marker=".", ms=3, lw=1, label=label)
    ax.set_xlabel("cycle")
    ax.set_ylabel(r"$\|u^{k+1}-u^k\|_A$")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def _fmt_iterations(v) -> str:
    return "no conv." if v is None else str(v)


def _nmg_ok(table: Dict, i: int, j: int) -> bool:
    """Algorithm 2 converged in run [i][j] (and, where the table has the check, to a solution)."""
    ok = bool(table["nmg_converged"][i][j]) if "nmg_converged" in table else True
    if "nmg_violation" in table:
        ok = ok and table["nmg_violation"][i][j] <= VIOLATION_TOL
    return ok


def plot_table1(table: Dict, ax=None, vcycles: bool = False):
    """Table 1 as an image: rows F, columns the number of dofs, entries Algorithm 1's outer
    iterations, "no conv." where it did not converge. With vcycles=True an entry also shows the
    V-cycles of both algorithms, "its (Alg. 1 / Alg. 2)", with a "!" after Algorithm 2's count where
    it did not converge or stopped on a non-solution."""
    ax = _axes(ax, figsize=(1.6 + 1.2 * len(table["dofs"]) * (2 if vcycles else 1), 0.8 + 0.3 * len(table["frictions"])))
    cells = []
    for i, row in enumerate(table["fixed_point_iterations"]):
        line = []
        for j, v in enumerate(row):
            s = _fmt_iterations(v)
            if vcycles:
                s += f" ({table['fixed_point_vcycles'][i][j]}/{table['nmg_vcycles'][i][j]}{'' if _nmg_ok(table, i, j) else '!'})"
            line.append(s)
        cells.append(line)
    t = ax.table(cellText=cells, rowLabels=[f"{F:g}" for F in table["frictions"]],
                 colLabels=[f"{d:,}" for d in table["dofs"]], loc="center", cellLoc="center")
    t.auto_set_font_size(False)
    t.set_fontsize(10)
    t.scale(1, 1.5)
    t.auto_set_column_width([-1])
    for (r, c), cell in t.get_celld().items():
        if r > 0 and c >= 0 and ("no conv." in cell.get_text().get_text() or "!" in cell.get_text().get_text()):
            cell.get_text().set_color("tab:red")
    ax.axis("off")
    ax.set_title("Table 1: Algorithm 1's outer iterations\n(rows: friction coefficient F, columns: degrees of freedom)" +
                 (" (cycles Alg. 1 / Alg. 2)" if vcycles else ""), fontsize=11)
    return ax


def convergence_records(table: Dict) -> List[Dict]:
    """Flat records {friction, nodes, method, cycles, converged} from a table1() dict (an nmg run
    that stopped on a non-solution, per its nmg_violation, counts as not converged)."""
    out = []
    for i, F in enumerate(table["frictions"]):
        for j, n in enumerate(table["nodes"]):
            it = table["fixed_point_iterations"][i][j]
            out.append({"friction": F, "nodes": n, "method": "fixed-point", "cycles": table["fixed_point_vcycles"][i][j],
                        "converged": it is not None})
            out.append({"friction": F, "nodes": n, "method": "nmg", "cycles": table["nmg_vcycles"][i][j],
                        "converged": _nmg_ok(table, i, j)})
    return out


# Figure 1's friction coefficients: one colour each from a sequential map, cut before its pale
# yellow end (which vanishes on white), and one marker each, so that a line is told apart by either.
FRICTION_CMAP = "plasma"
_CMAP_RANGE = (0.0, 0.88)
NOT_CONVERGED_MARKER = "X"
NOT_CONVERGED_LABEL = "not converged"
_FAIL_BAND_SCALE = 1.3  # the y axis reaches 1.3 x the largest count: the top band holds the failures
_ALGORITHM = {"fixed-point": "Algorithm 1 (fixed point)", "nmg": "Algorithm 2 (nonlinear multigrid)"}


def friction_styles(frictions: Iterable[float]) -> Dict[float, Dict]:
    """{F: {"color", "marker"}} for the friction coefficients in increasing order: colours evenly
    spaced along FRICTION_CMAP (by rank, so that 0.08 and 0.4 differ as much as 8 and 40), one
    marker each."""
    import matplotlib

    Fs = sorted({float(F) for F in frictions})
    cmap = matplotlib.colormaps[FRICTION_CMAP]
    lo, hi = _CMAP_RANGE
    pos = np.linspace(lo, hi, len(Fs)) if len(Fs) > 1 else [lo]
    return {F: {"color": cmap(float(t)), "marker": _MARKERS[k % len(_MARKERS)]} for k, (F, t) in enumerate(zip(Fs, pos))}


def _as_records(records):
    cycle_type = records.get("cycle_type", "F(3,3)") if isinstance(records, dict) else None
    if isinstance(records, dict):
        records = convergence_records(records)
    return list(records), cycle_type


def plot_cycles(records, method: str, ax=None, frictions: Optional[Iterable[float]] = None, legend: bool = True,
                styles: Optional[Dict[float, Dict]] = None):
    """One algorithm's panel of Figure 1 (left): its total multigrid cycles against the number of
    nodes (log x), one line per friction coefficient (colour and marker from friction_styles,
    label "F = 0.4"). A run that did not converge is not drawn as a count: its line breaks there
    (NaN), and an X in the coefficient's colour marks it at the top edge of the panel, in a band
    above the largest count (the k-th failure at the same number of nodes a little lower, so that
    none hides another) and "F = ..." written beside it, with one legend entry "not converged".

    `records`: a table1() dict, or per-solve records with the keys friction, nodes, method
    ("fixed-point" or "nmg"), cycles and optionally converged (e.g. the JSON reports of
    `contactmg hertz`). `method`: "fixed-point" (Algorithm 1) or "nmg" (Algorithm 2)."""
    if method not in _ALGORITHM:
        raise ValueError(f"method must be 'fixed-point' or 'nmg', got {method!r}")
    ax = _axes(ax, figsize=(6, 4.5))
    records, cycle_type = _as_records(records)
    allF = sorted({float(r["friction"]) for r in records})
    keep = allF if frictions is None else sorted(float(F) for F in frictions)
    styles = styles or friction_styles(allF)
    failed = {}  # nodes -> [(F, colour), ...] of the runs that did not converge there
    for F in keep:
        rs = sorted((r for r in records if float(r["friction"]) == F and r["method"] == method), key=lambda r: r["nodes"])
        if not rs:
            continue
        st = styles[F]
        x = np.array([r["nodes"] for r in rs], dtype=float)
        ok = np.array([bool(r.get("converged", True)) for r in rs])
        y = np.where(ok, [float(r["cycles"]) for r in rs], np.nan)
        ax.plot(x, y, color=st["color"], marker=st["marker"], ms=6, lw=1.6, label=f"F = {F:g}")
        for n in x[~ok]:
            failed.setdefault(float(n), []).append((F, st["color"]))
    counts = [float(r["cycles"]) for r in records if r["method"] == method and r.get("converged", True)
              and float(r["friction"]) in keep]
    ymax = max(counts, default=1.0)
    # a band above the largest count holds the failures' marks: no mark sits on a count
    ax.set_ylim(0, _FAIL_BAND_SCALE * ymax)
    from matplotlib.ticker import MaxNLocator

    ax.yaxis.set_major_locator(MaxNLocator(integer=True))  # cycles are counted
    if failed:
        from matplotlib.transforms import blended_transform_factory

        # x in data coordinates, y in axes coordinates: at the top edge whatever the counts
        trans = blended_transform_factory(ax.transData, ax.transAxes)
        xs, ys, cs = [], [], []
        for n, runs in sorted(failed.items()):
            for k, (F, c) in enumerate(runs):
                xs.append(n)
                ys.append(0.95 - 0.05 * k)
                cs.append(c)
                # the coefficient beside its mark: the colours of neighbouring F are close
                ax.annotate(f"F = {F:g}", (n, ys[-1]), xycoords=trans, xytext=(-9, 0), textcoords="offset points",
                            ha="right", va="center", fontsize=8, color="0.2")
        ax.scatter(xs, ys, transform=trans, marker=NOT_CONVERGED_MARKER, s=110, c=cs, edgecolors="k", linewidths=0.6,
                   zorder=5, clip_on=False, label=NOT_CONVERGED_LABEL)
    ax.set_xscale("log")
    ax.set_xlabel("number of nodes")
    ax.set_ylabel("multigrid cycles, all together" + (f" ({cycle_type})" if cycle_type else ""))
    ax.set_title(_ALGORITHM[method])
    ax.grid(True, which="major", alpha=0.3)
    if legend:
        ax.legend(fontsize=9, title="friction", title_fontsize=9, loc="best")
    return ax


def plot_convergence(records, axes=None, frictions: Optional[Iterable[float]] = None):
    """Figure 1 (left), the two algorithms apart: the total multigrid cycles of Algorithm 1 (fixed
    point, first panel) and Algorithm 2 (nmg, second panel) against the number of nodes, each
    panel with its own y scale, one line per friction coefficient in the same colour and marker in
    both (see plot_cycles: runs that did not converge break the line and are marked with an X at
    the top edge). One legend, right of the second panel. `axes`: two axes (a new figure when
    None). Returns the two axes."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    ax1, ax2 = axes
    recs, cycle_type = _as_records(records)
    styles = friction_styles(float(r["friction"]) for r in recs)
    rec_in = records if isinstance(records, dict) else recs
    plot_cycles(rec_in, "fixed-point", ax=ax1, frictions=frictions, legend=False, styles=styles)
    plot_cycles(rec_in, "nmg", ax=ax2, frictions=frictions, legend=False, styles=styles)
    handles, labels = {}, []
    for ax in (ax1, ax2):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in handles:
                handles[lab] = h
                labels.append(lab)
    # the failures' entry in black: its points carry the colour of their coefficient
    if NOT_CONVERGED_LABEL in handles:
        from matplotlib.lines import Line2D

        handles[NOT_CONVERGED_LABEL] = Line2D([], [], ls="none", marker=NOT_CONVERGED_MARKER, ms=9, mfc="0.6",
                                              mec="k", label=NOT_CONVERGED_LABEL)
    ax2.legend([handles[lab] for lab in labels], labels, fontsize=9, title="friction", title_fontsize=9,
               loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return ax1, ax2


# Axes3D gives its collections zorders above every 2D artist's as it sorts them by depth: the
# numbers on the bars need a larger one to stay readable
_ON_TOP = 1e6
_FAILED_TILE = (1.0, 0.85, 0.85, 0.9)
NOT_CONVERGED_MARK = "\u00d7"


def _floor_tile(ax, x, y, w, d, **kw):
    """A w x d square on the floor (z = 0) of a 3D axes at (x, y): where a bar would stand."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    tile = Poly3DCollection([[(x, y, 0.0), (x + w, y, 0.0), (x + w, y + d, 0.0), (x, y + d, 0.0)]], **kw)
    ax.add_collection3d(tile)
    return tile


def plot_fixed_point_iterations(table: Dict, ax=None, kind: str = "bar3d", annotate: bool = True):
    """Figure 1 right: Algorithm 1's outer iterations against level and friction coefficient.
    kind="bar3d" (like the paper; needs a 3D axes, created when ax is None) draws one bar per
    (level, F) as high as the iterations, in the coefficient's colour (friction_styles); where
    Algorithm 1 did not converge there is no count to draw: a hatched red tile on the floor
    (gid "not converged") with a red cross (NOT_CONVERGED_MARK) instead of a bar, and a legend
    entry. kind="heatmap" draws the iterations as an image (not converged: masked, hatched, "no
    conv."). With annotate the numbers are written on the bars/cells."""
    levels = list(table["levels"])
    F = list(table["frictions"])
    its = table["fixed_point_iterations"]
    data = np.array([[np.nan if v is None else v for v in row] for row in its], dtype=float)
    top = float(np.nanmax(data)) if np.any(np.isfinite(data)) else 1.0
    if kind == "bar3d":
        if ax is None:
            import matplotlib.pyplot as plt

            ax = plt.figure(figsize=(6, 5)).add_subplot(projection="3d")
        styles = friction_styles(F)
        w = 0.6
        failed = False
        for i in range(len(F)):
            for j in range(len(levels)):
                v = data[i, j]
                if np.isnan(v):
                    _floor_tile(ax, j, i, w, w, facecolors=_FAILED_TILE, edgecolors="tab:red", hatch="xxx",
                                linewidths=1.0, gid=NOT_CONVERGED_LABEL)
                    failed = True
                else:
                    ax.bar3d(j, i, 0, w, w, v, color=styles[float(F[i])]["color"], alpha=0.85, shade=True)
                # a cross on each failure's tile (words would overlap on neighbouring tiles)
                if np.isnan(v):
                    ax.text(j + w / 2, i + w / 2, 0.0, NOT_CONVERGED_MARK, fontsize=13, ha="center", va="center",
                            color="tab:red", fontweight="bold", zorder=_ON_TOP)
                elif annotate:
                    ax.text(j + w / 2, i + w / 2, v + 0.02 * top, f"{int(v)}", fontsize=7, ha="center", color="k",
                            zorder=_ON_TOP)
        ax.set_xticks(np.arange(len(levels)) + w / 2)
        ax.set_xticklabels([str(L) for L in levels])
        ax.set_yticks(np.arange(len(F)) + w / 2)
        ax.set_yticklabels([f"{f:g}" for f in F], fontsize=8)
        ax.set_zlim(0, top * 1.05)
        # seen from the corner of the finest level and the largest F, where Algorithm 1 fails:
        # the failures' tiles stand in front, not behind the tallest bars
        ax.view_init(elev=28, azim=35)
        ax.set_zlabel("outer iterations")
        ax.set_ylabel("friction coefficient F")
        title = "Algorithm 1: outer iterations"
        if failed:
            from matplotlib.patches import Patch

            ax.legend(handles=[Patch(facecolor=_FAILED_TILE, edgecolor="tab:red", hatch="xxx",
                                     label=f"{NOT_CONVERGED_MARK} {NOT_CONVERGED_LABEL} (no bar)")],
                      loc="upper left", fontsize=9)
    elif kind == "heatmap":
        ax = _axes(ax, figsize=(1.5 + 0.8 * len(levels), 1 + 0.4 * len(F)))
        import matplotlib.pyplot as plt

        cmap = plt.get_cmap("Blues").with_extremes(bad="mistyrose")
        ax.imshow(np.ma.masked_invalid(data), cmap=cmap, aspect="auto", origin="lower", vmin=0, vmax=top)
        for i in range(len(F)):
            for j in range(len(levels)):
                v = data[i, j]
                if np.isnan(v):
                    ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch="//", ec="tab:red", lw=0))
                if annotate:
                    ax.text(j, i, "no conv." if np.isnan(v) else f"{int(v)}", ha="center", va="center", fontsize=7,
                            color="tab:red" if np.isnan(v) else ("w" if v > 0.6 * top else "k"))
        ax.set_xticks(np.arange(len(levels)))
        ax.set_xticklabels([str(L) for L in levels])
        ax.set_yticks(np.arange(len(F)))
        ax.set_yticklabels([f"{f:g}" for f in F], fontsize=7)
        ax.set_ylabel("F")
        title = "Algorithm 1: outer iterations (red: no conv.)"
    else:
        raise ValueError(f"kind must be 'bar3d' or 'heatmap', got {kind!r}")
    ax.set_xlabel("level")
    ax.set_title(title)
    return ax
