"""Plots in the paper's style. Every helper takes ax=None (a new figure then) and returns the axes."""
from __future__ import annotations

import numpy as np

from .results import SLIP, STICK


def _axes(ax, **kw):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(**kw)
    return ax


def _zones(x, mask):
    """Contiguous runs of True in mask (x sorted) as (x_start, x_end) spans reaching half-way to
    the neighbouring nodes."""
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
        spans.append((lo, hi))
        i = j + 1
    return spans


def plot_boundary_stress(result, ax=None, friction=None, margin: float = 1.5):
    """Figure 2 (middle) of the paper: normal (blue) and tangential (red) boundary stress along x,
    the Coulomb bound +-F|sigma_n| dashed, stick and slip zones shaded. Shows the contact nodes with
    |x| up to `margin` times the contact half-width."""
    ax = _axes(ax, figsize=(7, 4))
    x = result.mesh.points[result.contact_nodes, 0]
    width = max(result.contact_halfwidth, 1e-12)
    sel = np.abs(x) <= margin * width
    order = np.argsort(x[sel])
    xs = x[sel][order]
    sn = result.normal_stress[sel][order]
    st = result.tangential_stress[sel][order, 0]
    state = result.contact_state[sel][order]
    for lo, hi in _zones(xs, state == STICK):
        ax.axvspan(lo, hi, color="tab:green", alpha=0.15, lw=0, label="stick" if lo == _zones(xs, state == STICK)[0][0] else None)
    for k, (lo, hi) in enumerate(_zones(xs, state == SLIP)):
        ax.axvspan(lo, hi, color="tab:orange", alpha=0.15, lw=0, label="slip" if k == 0 else None)
    ax.plot(xs, sn, "-", color="tab:blue", marker=".", label=r"normal stress $\sigma_n$")
    ax.plot(xs, st, "-", color="tab:red", marker=".", label=r"tangential stress $\sigma_T$")
    if friction:
        bound = friction * np.abs(sn)
        ax.plot(xs, bound, "--", color="0.4", lw=1, label=r"$\pm F|\sigma_n|$")
        ax.plot(xs, -bound, "--", color="0.4", lw=1)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("x")
    ax.set_ylabel("boundary stress")
    ax.set_title(f"{result.method}, {result.law}" + (f", F = {friction:g}" if friction else ""))
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_correction_history(results, ax=None, labels=None):
    """Correction norm ||u^{k+1} - u^k||_A against cycle (log scale) for one or more results."""
    ax = _axes(ax, figsize=(6, 4))
    if not isinstance(results, (list, tuple)):
        results = [results]
    for k, r in enumerate(results):
        label = labels[k] if labels else f"{r.method} ({r.law})"
        ax.semilogy(r.history["cycle"], r.history["correction_norm"], marker=".", label=label)
    ax.set_xlabel("cycle")
    ax.set_ylabel(r"$\|u^{k+1}-u^k\|_A$")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_table1(table, ax=None):
    """Table 1 as an image: fixed-point iterations per friction coefficient (rows) and dofs
    (columns), "no conv." where Algorithm 1 failed."""
    ax = _axes(ax, figsize=(8, 4))
    cells = [[("no conv." if v is None else str(v)) for v in row] for row in table["fixed_point_iterations"]]
    t = ax.table(cellText=cells, rowLabels=[f"{F:g}" for F in table["frictions"]],
                 colLabels=[f"{d:,}" for d in table["dofs"]], loc="center", cellLoc="center")
    t.auto_set_font_size(False)
    t.set_fontsize(8)
    t.scale(1, 1.3)
    ax.axis("off")
    ax.set_title("Table 1: fixed-point iterations (F \\ dofs)")
    return ax


def plot_convergence(table, ax=None, frictions=None):
    """Figure 1 left: total V-cycles against the number of nodes (log axis), Algorithm 1 (fixed
    point) blue and Algorithm 2 (nmg) red, one curve per friction coefficient."""
    ax = _axes(ax, figsize=(6, 4.5))
    nodes = np.asarray(table["nodes"])
    frictions = table["frictions"] if frictions is None else frictions
    markers = "os^vD<>ph*"
    for k, F in enumerate(table["frictions"]):
        if F not in frictions:
            continue
        m = markers[k % len(markers)]
        ax.semilogx(nodes, table["fixed_point_vcycles"][k], "-", color="tab:blue", marker=m, ms=4, lw=1,
                    label=f"Alg. 1, F={F:g}")
        ax.semilogx(nodes, table["nmg_vcycles"][k], "-", color="tab:red", marker=m, ms=4, lw=1, label=f"Alg. 2, F={F:g}")
    ax.set_xlabel("number of nodes")
    ax.set_ylabel("number of V-cycles")
    ax.set_title("Figure 1 (left): Algorithm 1 blue, Algorithm 2 red")
    ax.legend(fontsize=6, ncol=2)
    return ax


def plot_fixed_point_iterations(table, ax=None):
    """Figure 1 right: fixed-point iterations against level and friction coefficient (3D bars;
    "no conv." drawn as a red bar at the iteration limit)."""
    if ax is None:
        import matplotlib.pyplot as plt

        ax = plt.figure(figsize=(6, 5)).add_subplot(projection="3d")
    levels = table["levels"]
    F = table["frictions"]
    its = table["fixed_point_iterations"]
    top = max([v for row in its for v in row if v is not None] + [1])
    for i in range(len(F)):
        for j in range(len(levels)):
            v = its[i][j]
            ax.bar3d(j, i, 0, 0.6, 0.6, top * 1.1 if v is None else v, color="tab:red" if v is None else "tab:blue",
                     alpha=0.8, shade=True)
    ax.set_xticks(np.arange(len(levels)) + 0.3)
    ax.set_xticklabels([str(L) for L in levels])
    ax.set_yticks(np.arange(len(F)) + 0.3)
    ax.set_yticklabels([f"{f:g}" for f in F], fontsize=7)
    ax.set_xlabel("level")
    ax.set_ylabel("F")
    ax.set_zlabel("iterations")
    ax.set_title("Figure 1 (right): fixed-point iterations (red: no conv.)")
    return ax
