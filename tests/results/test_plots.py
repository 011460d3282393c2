"""Plot helpers: the artists hold the data; table1() and `contactmg table1`."""
import argparse
import json
import subprocess
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from contactmg.examples import hertz  # noqa: E402
from contactmg.results import plots  # noqa: E402
from contactmg.examples import table1 as t1  # noqa: E402
from contactmg.results.checks import contact_conditions  # noqa: E402
from contactmg.results.result import SLIP, STICK  # noqa: E402

TABLE_KEYS = ("levels", "dofs", "frictions", "fixed_point_iterations", "fixed_point_vcycles", "nmg_vcycles", "nodes",
              "cell", "nmg_converged", "fixed_point_status", "fixed_point_seconds", "nmg_seconds")


@pytest.fixture(scope="module")
def hertz_f04():
    p = hertz.hertz_problem("triangle", 5, 0.4, coulomb_at_zero=True)
    return p, p.solve("nmg"), p.solve("fixed-point")


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def fake_table():
    return {"levels": [3, 4, 5], "nodes": [325, 1225, 4753], "dofs": [650, 2450, 9506], "frictions": [0.4, 5.0],
            "cell": "triangle", "fixed_point_iterations": [[4, 8, 8], [3, None, None]],
            "fixed_point_vcycles": [[37, 64, 77], [27, 900, 1200]], "nmg_vcycles": [[14, 16, 17], [14, 16, 16]],
            "nmg_converged": [[True, True, True], [True, True, True]],
            "nmg_status": [["converged"] * 3] * 2, "nmg_violation": [[1e-12] * 3] * 2}


def span_x(patch):
    if isinstance(patch, Rectangle):
        return patch.get_x(), patch.get_x() + patch.get_width()
    xy = np.asarray(patch.get_xy())
    return xy[:, 0].min(), xy[:, 0].max()


def line_by_color(ax, color, ls="-"):
    lines = [ln for ln in ax.get_lines() if to_rgb(ln.get_color()) == to_rgb(color) and ln.get_linestyle() == ls]
    assert len(lines) == 1, [ln.get_label() for ln in ax.get_lines()]
    return lines[0]


def test_boundary_stress_lines_hold_the_sorted_stresses(hertz_f04):
    p, res, _ = hertz_f04
    ax = plots.plot_boundary_stress(res, friction=0.4, margin=1.5)
    # independent selection: contact nodes within 1.5 x the largest |x| of a node in contact
    x = p.mesh.points[res.contact_nodes, 0]
    a = np.abs(x[res.contact_state > 0]).max()
    sel = np.flatnonzero(np.abs(x) <= 1.5 * a)
    o = sel[np.argsort(x[sel])]
    assert len(o) > np.sum(res.contact_state > 0)  # some free nodes on either side are shown
    blue, red = line_by_color(ax, "tab:blue"), line_by_color(ax, "tab:red")
    np.testing.assert_array_equal(blue.get_xdata(), x[o])
    np.testing.assert_allclose(blue.get_ydata(), res.contact_force[o, 0] / res.measure[o], rtol=1e-14)
    np.testing.assert_allclose(red.get_ydata(), res.contact_force[o, 1] / res.measure[o], rtol=1e-14)
    assert np.all(blue.get_ydata() <= 1e-9 * np.abs(blue.get_ydata()).max())  # compression only
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert len(dashed) == 2
    ys = sorted((ln.get_ydata() for ln in dashed), key=lambda y: y.sum())
    np.testing.assert_allclose(ys[1], 0.4 * np.abs(blue.get_ydata()))
    np.testing.assert_allclose(ys[0], -0.4 * np.abs(blue.get_ydata()))
    # the tangential stress stays within the Coulomb bound
    scale = np.abs(blue.get_ydata()).max()
    assert np.all(np.abs(red.get_ydata()) <= ys[1] + 1e-9 * scale)
    labels = ax.get_legend_handles_labels()[1]
    assert "stick" in labels and "slip" in labels and ax.get_xlabel() == "x"


def test_boundary_stress_zones_cover_exactly_the_stick_and_slip_nodes(hertz_f04):
    _, res, _ = hertz_f04
    ax = plots.plot_boundary_stress(res, margin=1.5)  # F read off the result
    assert "F = 0.4" in ax.get_title()
    x = res.mesh.points[res.contact_nodes, 0]
    shown = np.abs(x) <= 1.5 * res.contact_halfwidth
    xs, state = x[shown], res.contact_state[shown]
    for color, code in ((plots.STICK_COLOR, STICK), (plots.SLIP_COLOR, SLIP)):
        spans = [span_x(pt) for pt in ax.patches if np.allclose(pt.get_facecolor()[:3], to_rgb(color))]
        assert spans, color
        inside = np.array([any(lo <= v <= hi for lo, hi in spans) for v in xs])
        np.testing.assert_array_equal(inside, state == code)
        # the spans together reach from the outermost such node to half-way to the next one
        lo, hi = min(s[0] for s in spans), max(s[1] for s in spans)
        assert xs[state == code].min() >= lo and xs[state == code].max() <= hi
    # stick nodes sit in the middle, slip nodes on both sides of them (F = 0.4)
    assert np.all(np.abs(xs[state == STICK]).max() < np.abs(xs[state == SLIP]).max())


def test_result_friction_is_read_off_the_bound(hertz_f04):
    _, res, fp = hertz_f04
    assert plots.result_friction(res) == pytest.approx(0.4, rel=1e-12)
    assert plots.result_friction(fp) == pytest.approx(0.4, rel=1e-6)
    r0 = hertz.hertz_problem("triangle", 3, 0.0).solve()
    assert plots.result_friction(r0) is None
    for F in (None, 0.0):  # no bound without friction (the command line passes F = 0)
        ax = plots.plot_boundary_stress(r0, friction=F)
        assert not [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
        assert len(ax.get_lines()) == 3  # normal, tangential and the zero line


def test_correction_history_lines_and_legend(hertz_f04):
    _, nm, fp = hertz_f04
    ax = plots.plot_correction_history([fp, nm])
    assert ax.get_yscale() == "log"
    lines = ax.get_lines()
    assert len(lines) == 2
    np.testing.assert_array_equal(lines[0].get_ydata(), fp.history["correction_norm"])
    np.testing.assert_array_equal(lines[1].get_xdata(), np.arange(1, nm.cycles + 1))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0].startswith("Algorithm 1") and f"{fp.outer_iterations} outer" in labels[0] and "F=0.4" in labels[0]
    assert labels[1].startswith("Algorithm 2") and "F=0.4" in labels[1]
    # explicit labels win
    ax = plots.plot_correction_history(nm, labels=["mine"])
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["mine"]


@pytest.mark.parametrize("vcycles", [False, True])
def test_table_image_shows_the_numbers(vcycles):
    tab = fake_table()
    ax = plots.plot_table1(tab, vcycles=vcycles)
    cells = ax.tables[0].get_celld()
    text = {k: c.get_text().get_text() for k, c in cells.items()}
    assert [text[(0, j)] for j in range(3)] == ["650", "2,450", "9,506"]
    assert [text[(i, -1)] for i in (1, 2)] == ["0.4", "5"]
    for i in range(2):
        for j in range(3):
            v = tab["fixed_point_iterations"][i][j]
            want = "no conv." if v is None else str(v)
            if vcycles:
                want += f" ({tab['fixed_point_vcycles'][i][j]}/{tab['nmg_vcycles'][i][j]})"
            assert text[(i + 1, j)] == want
    assert to_rgb(cells[(2, 1)].get_text().get_color()) == to_rgb("tab:red")
    if vcycles:  # an nmg run that stopped on a non-solution is flagged
        tab["nmg_violation"] = [[1e-12] * 3, [1e-12, 1e-12, 0.3]]
        cells = plots.plot_table1(tab, vcycles=True).tables[0].get_celld()
        assert cells[(2, 2)].get_text().get_text() == "no conv. (1200/16!)"
        assert cells[(1, 2)].get_text().get_text() == "8 (77/17)"


def lines_by_label(ax):
    return {ln.get_label(): ln for ln in ax.get_lines()}


def failure_marks(ax):
    """(x in data, y in axes coordinates) of the "not converged" marks of a Figure 1 panel."""
    (marks,) = [c for c in ax.collections if c.get_label() == plots.NOT_CONVERGED_LABEL]
    return np.asarray(marks.get_offsets())


def test_convergence_plot_draws_each_algorithm_apart_from_a_table():
    tab = fake_table()
    ax1, ax2 = plots.plot_convergence(tab)
    assert ax1 is not ax2 and "Algorithm 1" in ax1.get_title() and "Algorithm 2" in ax2.get_title()
    styles = plots.friction_styles(tab["frictions"])
    for ax, key in ((ax1, "fixed_point_vcycles"), (ax2, "nmg_vcycles")):
        assert ax.get_xscale() == "log" and ax.get_xlabel() == "number of nodes"
        assert "cycles" in ax.get_ylabel() and "F(3,3)" in ax.get_ylabel()
        lines = lines_by_label(ax)
        assert set(lines) == {"F = 0.4", "F = 5"}  # one line per coefficient, nothing else
        for i, F in enumerate(tab["frictions"]):
            ln = lines[f"F = {F:g}"]
            np.testing.assert_array_equal(ln.get_xdata(), tab["nodes"])
            assert to_rgb(ln.get_color()) == to_rgb(styles[F]["color"]) and ln.get_marker() == styles[F]["marker"]
        # the same coefficient looks the same in both panels
    assert {ln.get_label(): to_rgb(ln.get_color()) for ln in ax1.get_lines()} == \
        {ln.get_label(): to_rgb(ln.get_color()) for ln in ax2.get_lines()}
    # Algorithm 1: F = 0.4 converged everywhere; F = 5 failed on levels 4 and 5: its line holds
    # the count of level 3 only (a failed run's stall count is not drawn) ...
    l1 = lines_by_label(ax1)
    np.testing.assert_array_equal(l1["F = 0.4"].get_ydata(), [37, 64, 77])
    y5 = np.asarray(l1["F = 5"].get_ydata(), float)
    assert y5[0] == 27 and np.all(np.isnan(y5[1:]))
    assert ax1.get_ylim()[1] < 900  # the stall counts 900 and 1200 set no scale
    # ... and the failures are marked at the top edge, above every count, in F = 5's colour
    marks = failure_marks(ax1)
    np.testing.assert_array_equal(marks[:, 0], [1225, 4753])
    assert np.all(marks[:, 1] > 0.85) and np.all(marks[:, 1] <= 1.0)
    assert np.all(marks[:, 1] * ax1.get_ylim()[1] > 77)
    (coll,) = [c for c in ax1.collections if c.get_label() == plots.NOT_CONVERGED_LABEL]
    assert all(to_rgb(c) == to_rgb(styles[5.0]["color"]) for c in coll.get_facecolors())
    assert sorted(t.get_text() for t in ax1.texts) == ["F = 5", "F = 5"]
    # Algorithm 2 converged everywhere: all counts, no marks, its own y scale
    l2 = lines_by_label(ax2)
    np.testing.assert_array_equal(l2["F = 5"].get_ydata(), [14, 16, 16])
    assert not [c for c in ax2.collections if c.get_label() == plots.NOT_CONVERGED_LABEL]
    assert ax2.get_ylim()[1] < 30
    # one legend, readable, with an entry per coefficient and one for the failures
    legend = ax2.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["F = 0.4", "F = 5", plots.NOT_CONVERGED_LABEL]
    assert min(t.get_fontsize() for t in legend.get_texts()) >= 8
    assert ax1.get_legend() is None


def test_convergence_plot_marks_an_nmg_run_that_stopped_on_a_non_solution():
    tab = fake_table()
    tab["nmg_violation"] = [[1e-12] * 3, [1e-12, 0.3, 1e-12]]
    _, ax2 = plots.plot_convergence(tab)
    y = np.asarray(lines_by_label(ax2)["F = 5"].get_ydata(), float)
    assert y[0] == 14 and np.isnan(y[1]) and y[2] == 16
    np.testing.assert_array_equal(failure_marks(ax2)[:, 0], [1225])


def test_friction_styles_tell_the_coefficients_apart():
    Fs = [0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0]
    st = plots.friction_styles(reversed(Fs))
    assert list(st) == Fs
    assert len({to_rgb(v["color"]) for v in st.values()}) == 10 and len({v["marker"] for v in st.values()}) == 10
    # a sequential map: the lightness grows with F
    lum = [np.dot(to_rgb(st[F]["color"]), (0.299, 0.587, 0.114)) for F in Fs]
    assert lum == sorted(lum)


def test_cycles_panel_from_records():
    # records, e.g. JSON reports of `contactmg hertz`, unordered
    recs = [{"friction": 0.4, "nodes": n, "method": m, "cycles": c}
            for n, m, c in [(1225, "nmg", 16), (325, "nmg", 14), (325, "fixed-point", 37), (1225, "fixed-point", 64)]]
    ax = plots.plot_cycles(recs, "fixed-point")
    (ln,) = ax.get_lines()
    assert ln.get_label() == "F = 0.4"
    np.testing.assert_array_equal(ln.get_xdata(), [325, 1225])
    np.testing.assert_array_equal(ln.get_ydata(), [37, 64])
    assert not ax.collections
    ax = plots.plot_cycles(recs + [{"friction": 2.0, "nodes": 325, "method": "nmg", "cycles": 200, "converged": False}],
                           "nmg")
    assert set(lines_by_label(ax)) == {"F = 0.4", "F = 2"}
    assert np.isnan(lines_by_label(ax)["F = 2"].get_ydata()[0])
    np.testing.assert_array_equal(failure_marks(ax)[:, 0], [325])
    with pytest.raises(ValueError):
        plots.plot_cycles(recs, "linear")


def vertices_3d(collection):
    """The (n, 3) vertices of a Poly3DCollection (matplotlib keeps them in a private field whose
    name changed between versions)."""
    if hasattr(collection, "_faces"):
        return np.asarray(collection._faces, float).reshape(-1, 3)
    return np.asarray(collection._vec[:3], float).T


def bar_heights(ax):
    """{(x, y) of the bar's corner: height} of the bars Axes3D.bar3d drew (their vertices)."""
    out = {}
    for c in ax.collections:
        if c.get_gid() == plots.NOT_CONVERGED_LABEL:
            continue
        xyz = vertices_3d(c)
        out[(round(xyz[:, 0].min(), 6), round(xyz[:, 1].min(), 6))] = xyz[:, 2].max()
    return out


def test_fixed_point_iterations_heatmap_and_bars():
    tab = fake_table()
    ax = plots.plot_fixed_point_iterations(tab, kind="heatmap")
    img = ax.get_images()[0].get_array()
    np.testing.assert_array_equal(img.mask, [[False] * 3, [False, True, True]])
    np.testing.assert_array_equal(img.data[0], [4, 8, 8])
    texts = sorted(t.get_text() for t in ax.texts)
    assert texts == sorted(["4", "8", "8", "3", "no conv.", "no conv."])
    ax = plots.plot_fixed_point_iterations(tab)  # 3D bars
    assert ax.name == "3d"
    assert len(ax.collections) == 6
    # a bar per converged run, as high as its iterations; none where Algorithm 1 failed ...
    assert bar_heights(ax) == {(0, 0): 4, (1, 0): 8, (2, 0): 8, (0, 1): 3}
    # ... but a hatched tile on the floor, with a cross on it
    tiles = [c for c in ax.collections if c.get_gid() == plots.NOT_CONVERGED_LABEL]
    assert len(tiles) == 2 and all(c.get_hatch() for c in tiles)
    corners = sorted((round(vertices_3d(c)[:, 0].min(), 6), round(vertices_3d(c)[:, 1].min(), 6)) for c in tiles)
    assert corners == [(1, 1), (2, 1)] and all(np.allclose(vertices_3d(c)[:, 2], 0) for c in tiles)
    assert ax.get_zlim()[1] < 10  # no fake height above the largest count (8)
    assert sorted(t.get_text() for t in ax.texts) == sorted(["4", "8", "8", "3"] + [plots.NOT_CONVERGED_MARK] * 2)
    assert plots.NOT_CONVERGED_LABEL in ax.get_legend().get_texts()[0].get_text()
    assert ax.get_zlabel() == "outer iterations" and ax.get_xlabel() == "level" and "friction" in ax.get_ylabel()
    ax = plots.plot_fixed_point_iterations(tab, annotate=False)  # the crosses stay
    assert sorted(t.get_text() for t in ax.texts) == [plots.NOT_CONVERGED_MARK] * 2
    with pytest.raises(ValueError):
        plots.plot_fixed_point_iterations(tab, kind="pie")


def test_table1_figure_has_its_panels():
    tab = fake_table()
    fig, axes = t1.table1_figure(tab)
    assert set(axes) == {"table", "alg1", "alg2", "bars"}
    assert axes["bars"].name == "3d" and axes["table"].tables
    assert "Algorithm 1" in axes["alg1"].get_title() and "Algorithm 2" in axes["alg2"].get_title()
    np.testing.assert_array_equal(lines_by_label(axes["alg2"])["F = 0.4"].get_ydata(), tab["nmg_vcycles"][0])


def test_table1_keys_shapes_and_counts():
    tab = t1.table1(levels=[2, 3], frictions=[0.4, 5.0], progress=False)
    for k in TABLE_KEYS:
        assert k in tab, k
    assert tab["levels"] == [2, 3] and tab["frictions"] == [0.4, 5.0] and tab["cell"] == "triangle"
    assert tab["dofs"] == [2 * n for n in tab["nodes"]] and tab["nodes"][0] < tab["nodes"][1]
    for k in t1._PER_RUN:
        assert np.shape(np.array(tab[k], dtype=object)) == (2, 2), k
    # the numbers are those of independent solves
    p = hertz.hertz_problem("triangle", 3, 0.4, coulomb_at_zero=True)
    fp, nm = p.solve("fixed-point"), p.solve("nmg")
    assert tab["fixed_point_iterations"][0][1] == fp.outer_iterations
    assert tab["fixed_point_vcycles"][0][1] == fp.cycles and tab["nmg_vcycles"][0][1] == nm.cycles
    assert all(v < 1e-8 for row in tab["nmg_violation"] + tab["fixed_point_violation"] for v in row)
    json.dumps(tab)  # JSON-serializable as it is


def test_table1_counts_cycles_of_failed_fixed_point_runs():
    tab = t1.table1(levels=[5], frictions=[2.0], progress=False, fixed_point_max=2)
    assert tab["fixed_point_iterations"] == [[None]]
    assert "no convergence" in tab["fixed_point_status"][0][0]
    assert tab["fixed_point_vcycles"][0][0] > tab["nmg_vcycles"][0][0] > 0
    assert t1.failed_runs(tab) == []  # Algorithm 2 converged


def test_run_table1_exit_status_and_outputs(tmp_path, monkeypatch, capsys):
    tab = fake_table()
    tab.update(cell="triangle", seconds=1.0)
    monkeypatch.setattr(t1, "table1", lambda **kw: tab)
    args = argparse.Namespace(levels=None, frictions=None, cell="triangle", json=str(tmp_path / "t.json"),
                              plot=str(tmp_path / "t.png"), quiet=True)
    backend = matplotlib.get_backend()
    assert t1.run_table1(args) == 0
    assert json.loads((tmp_path / "t.json").read_text())["fixed_point_iterations"][1] == [3, None, None]
    assert (tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG" and matplotlib.get_backend() == backend
    # an nmg run that stops "converged" on a non-solution counts as not converged
    tab["nmg_violation"] = [[1e-12, 1e-12, 1e-12], [1e-12, 1e-12, 0.3]]
    assert t1.run_table1(args) == 3
    assert "F = 5, level 5" in capsys.readouterr().err
    tab["nmg_violation"] = [[1e-12] * 3] * 2
    tab["nmg_converged"] = [[True, False, True], [True, True, True]]
    assert t1.run_table1(args) == 3


def test_command_line_table1(tmp_path):
    png = tmp_path / "t1.png"
    r = subprocess.run([sys.executable, "-m", "contactmg", "table1", "--levels", "2", "3", "--frictions", "0.4", "5",
                        "--json", "-", "-q", "--plot", str(png)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    for k in TABLE_KEYS:
        assert k in d, k
    assert d["levels"] == [2, 3] and d["frictions"] == [0.4, 5.0]
    for k in ("fixed_point_vcycles", "nmg_vcycles", "fixed_point_iterations"):
        assert np.array(d[k]).shape == (2, 2), k
    assert all(f > n for fr, nr in zip(d["fixed_point_vcycles"], d["nmg_vcycles"]) for f, n in zip(fr, nr))
    # one image: Figure 1 left as two panels above Table 1 and Figure 1 right
    from PIL import Image

    w, h = Image.open(png).size
    assert w > h > 0.5 * w


def test_contact_conditions_detect_a_non_solution(hertz_f04):
    p, res, _ = hertz_f04
    assert contact_conditions(p, res)["max"] < 1e-9
    # push one interior node by 1e-6 (0.02 % of the prescribed displacement): out of equilibrium
    u = res.displacement.copy()
    interior = np.flatnonzero(~p.fixed.any(axis=1) & ~np.isin(np.arange(len(u)), p.contact.nodes))
    u[interior[len(interior) // 2], 0] += 1e-6
    v = contact_conditions(p, res.__class__(**{**res.__dict__, "displacement": u}))
    assert v["interior"] > 1e-5 and v["max"] == v["interior"], v
    # lift the whole contact boundary off by 1e-7: forces remain where nothing is in contact
    u = res.displacement.copy()
    u[p.contact.nodes, 1] += 1e-7
    v = contact_conditions(p, res.__class__(**{**res.__dict__, "displacement": u}))
    assert v["inactive_force"] > 0.1, v
