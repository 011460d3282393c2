"""The 3D commands `contactmg sphere` and `contactmg cork`: JSON keys,
exit statuses, the plots drawn from the right data."""
import json
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from contactmg.examples import cork  # noqa: E402
from contactmg.examples import sphere  # noqa: E402
from contactmg.cli.main import main  # noqa: E402
from contactmg.results.plots_3d import (FREE_COLOR, SLIP_COLOR, STICK_COLOR, face_states, plot_cork,  # noqa: E402
                                plot_cork_section, plot_radial_stress, radial_stress_data)
from contactmg.results.result import FREE, SLIP, STICK  # noqa: E402

KEYS = ["problem", "dim", "cell", "levels", "nodes", "dofs", "method", "friction", "tol", "converged", "cycles",
        "outer_iterations", "setup_seconds", "solve_seconds", "history", "contact_nodes", "stick_nodes", "slip_nodes",
        "contact_halfwidth", "stick_halfwidth", "reaction", "max_normal_stress", "peak_rss_mb"]


def run(*args, timeout=300, cwd=None):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd)


def test_sphere_json_has_the_hertz_keys_and_the_hertz_formulas(tmp_path, capsys):
    out = tmp_path / "s.json"
    plot = tmp_path / "s.png"
    vtu = tmp_path / "s.vtu"
    assert main(["sphere", "--levels", "2", "--friction", "0.1", "--json", str(out), "--plot", str(plot),
                 "--vtu", str(vtu), "-q"]) == 0
    d = json.loads(out.read_text())
    for k in KEYS + ["contact_radius", "stick_radius", "hertz_radius", "hertz_p0"]:
        assert k in d, k
    assert d["problem"] == "sphere" and d["dim"] == 3 and d["cell"] == "hexahedron" and d["converged"]
    assert len(d["reaction"]) == 3 and d["dofs"] == 3 * d["nodes"]
    P = d["reaction"][2]
    assert d["hertz_radius"] == pytest.approx((3 * P * 0.4 / (4 * 2000 / (1 - 0.28 ** 2))) ** (1 / 3), rel=1e-12)
    assert d["hertz_p0"] == pytest.approx(3 * P / (2 * np.pi * d["hertz_radius"] ** 2), rel=1e-12)
    assert d["stick_nodes"] >= 1 and 0 <= d["stick_radius"] <= d["contact_radius"]
    assert d["stick_nodes"] + d["slip_nodes"] == d["contact_nodes"]
    assert plot.stat().st_size > 10000 and vtu.stat().st_size > 10000
    import meshio

    m = meshio.read(vtu)
    assert set(m.point_data) >= {"displacement", "normal_stress", "tangential_stress", "node_state"}
    ts = m.point_data["tangential_stress"]  # two tangential components (VTK may pad them to 3)
    assert ts.shape[0] == len(m.points) and ts.shape[1] in (2, 3) and np.all(ts[:, 2:] == 0)


def test_sphere_linear_reference_and_tetra(tmp_path):
    r = run("sphere", "--cell", "tetra", "--levels", "2", "--method", "linear", "--json", "-", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["cell"] == "tetra" and d["nmg_cycles"] >= 5
    assert d["nmg_over_linear"] == pytest.approx(d["nmg_solve_seconds"] / d["solve_seconds"])


@pytest.mark.parametrize("args,word", [
    (["sphere", "--cell", "triangle"], "cell"), (["sphere", "--levels", "0"], "levels"),
    (["sphere", "--displacement", "-1"], "displacement"), (["sphere", "--displacement", "0.3"], "displacement"),
    (["cork", "--push", "nan"], "push"), (["cork", "--push", "9"], "push"), (["cork", "--picture", "c.bmp"], "--picture"),
    (["cork", "--friction", "-1"], "friction"),
])
def test_bad_3d_arguments_exit_2_with_one_line(args, word, tmp_path):
    r = run(*args, "-q", cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert word in r.stderr.strip().splitlines()[-1]


def test_no_convergence_exits_3_and_still_writes_json(tmp_path):
    out = tmp_path / "c.json"
    assert main(["cork", "--levels", "2", "--max-cycles", "2", "--json", str(out), "-q"]) == 3
    d = json.loads(out.read_text())
    assert d["converged"] is False and d["cycles"] == 2


def test_cork_json_and_picture(tmp_path):
    out, pic = tmp_path / "c.json", tmp_path / "c.png"
    assert main(["cork", "--levels", "2", "--json", str(out), "--picture", str(pic), "-q"]) == 0
    d = json.loads(out.read_text())
    for k in KEYS + ["push_force"]:
        assert k in d, k
    assert d["problem"] == "cork" and d["converged"] and d["stick_nodes"] > 0 and d["slip_nodes"] > 0
    assert d["push_force"] == pytest.approx(d["reaction"][2], rel=1e-8)
    assert pic.stat().st_size > 20000


def test_cork_json_reports_what_its_zones_measure(tmp_path, cork_level2):
    out = tmp_path / "c.json"
    assert main(["cork", "--levels", "2", "--json", str(out), "-q"]) == 0
    d = json.loads(out.read_text())
    # the contract's half-widths stay, null: the largest |x| of a zone node is the cork's radius
    assert d["contact_halfwidth"] is None and d["stick_halfwidth"] is None
    assert "contact_radius" not in d and "stick_radius" not in d
    # the zones as bands around the side: areas from the nodes' shares of the side, heights
    prob, res = cork_level2  # the same solve, in this process (tol 1e-10: the same states)
    side = 2 * np.pi * cork.RADIUS * cork.LENGTH
    on, stick = res.contact_state > 0, res.contact_state == STICK
    assert d["contact_nodes"] == on.sum() and d["stick_nodes"] == stick.sum()
    assert d["contact_area"] == pytest.approx(res.measure[on].sum(), rel=1e-12)
    assert d["stick_area"] == pytest.approx(res.measure[stick].sum(), rel=1e-12)
    assert d["stick_area"] + d["slip_area"] == pytest.approx(d["contact_area"], rel=1e-12)
    assert 0 < d["stick_area"] < d["contact_area"] < side
    z = res.mesh.points[res.contact_nodes, 2]
    assert d["contact_z_range"] == [z[on].min(), z[on].max()] and d["stick_z_range"] == [z[stick].min(), z[stick].max()]
    assert d["contact_length"] == pytest.approx(z[on].max() - z[on].min())
    # the cork is squeezed below the taper's top (z = 20), sticks at the bottom and slides above
    assert d["contact_z_range"][0] == 0.0 and d["contact_z_range"][1] < cork.TAPER_TOP
    assert 0 < d["stick_length"] < d["contact_length"]
    # the band is about as large as its circumference times its length (one node spacing more)
    assert d["contact_area"] == pytest.approx(2 * np.pi * cork.RADIUS * d["contact_length"], rel=0.3)


def test_cork_load_path_steps_report_the_zone_measures(capsys):
    assert main(["cork", "--levels", "2", "--steps", "2", "--json", "-"]) == 0
    captured = capsys.readouterr()
    d = json.loads(captured.out)
    for row in d["steps"]:
        assert row["contact_halfwidth"] is None and row["stick_halfwidth"] is None
        assert "contact_radius" not in row
        assert 0 < row["stick_area"] < row["contact_area"] and row["contact_length"] > 0
    assert d["steps"][-1]["contact_area"] == d["contact_area"]
    assert "stick area per step" in captured.err


def test_cork_picture_is_drawn_from_the_node_states(cork_level2):
    prob, res = cork_level2
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    plot_cork(prob, res, ax=ax, neck=cork.neck())
    facets = res.mesh.facets
    expect = face_states(facets, res.node_state)
    # independent of face_states: a face is stick/slip exactly when all its nodes are in contact
    s = res.node_state[facets]
    assert np.array_equal(expect == STICK, np.all(s == STICK, axis=1))
    assert np.array_equal(expect == SLIP, np.all(s > 0, axis=1) & np.any(s == SLIP, axis=1))
    assert {STICK, SLIP, FREE} <= set(expect.tolist())
    fig.canvas.draw()
    (poly,) = [c for c in ax.collections if c.get_label() == "cork"]
    fc = poly.get_facecolor()  # sorted by depth when drawn: compare the colours as a multiset
    assert len(fc) == len(facets)
    for state, color in ((STICK, STICK_COLOR), (SLIP, SLIP_COLOR), (FREE, FREE_COLOR)):
        drawn = np.all(np.isclose(fc, matplotlib.colors.to_rgba(color)), axis=1).sum()
        assert drawn == np.sum(expect == state), (state, drawn)
    plt.close(fig)


@pytest.fixture(scope="module")
def cork_level2():
    prob = cork.cork_problem(2, 0.4)
    return prob, prob.solve(tol=1e-10)


def test_cork_section_draws_the_tapered_wall_and_the_pressure(cork_level2):
    _, res = cork_level2
    neck = cork.neck()
    fig, ax = plt.subplots()
    plot_cork_section(res, neck, ax=ax, radius=cork.RADIUS)
    # the wall's line is the obstacle's radius function: it narrows below z = 20 (the taper)
    (wall,) = [ln for ln in ax.get_lines() if ln.get_label() == "neck wall"]
    z = np.asarray(wall.get_ydata())
    np.testing.assert_allclose(wall.get_xdata(), neck.radius(z), rtol=1e-14)
    assert z.min() < 0 and z.max() > cork.LENGTH
    np.testing.assert_allclose(neck.radius(np.array([0.0, cork.TAPER_TOP, cork.LENGTH])),
                               [cork.RADIUS - cork.INTERFERENCE, cork.RADIUS + cork.CLEARANCE, cork.RADIUS + cork.CLEARANCE])
    # the r axis is zoomed so that the taper (0.3 mm over 20 mm) spans a good part of it
    lo, hi = ax.get_xlim()
    assert hi - lo < 2.0 and (cork.CLEARANCE + cork.INTERFERENCE) / (hi - lo) > 0.3
    # the nodes in contact sit at their deformed (r, z), coloured by their contact pressure
    x = res.mesh.points[res.contact_nodes] + res.displacement[res.contact_nodes]
    on = res.contact_state > 0
    drawn = [c for c in ax.collections if c.get_gid() == "in contact"]
    offsets = np.vstack([c.get_offsets() for c in drawn])
    values = np.concatenate([c.get_array() for c in drawn])
    want = np.column_stack([np.hypot(x[on, 0], x[on, 1]), x[on, 2]])
    order = lambda a: np.lexsort(a.T[::-1])  # noqa: E731
    np.testing.assert_allclose(offsets[order(offsets)], want[order(want)], rtol=1e-12)
    np.testing.assert_allclose(np.sort(values), np.sort(-res.normal_stress[on]), rtol=1e-12)
    assert np.all(values > 0)
    # in contact means on the wall: the deformed radius is the wall's there (no penetration)
    np.testing.assert_allclose(want[:, 0], neck.radius(want[:, 1]), atol=1e-6)
    # the colour bar says what the colours are, with the unit
    (cbar,) = [c.colorbar for c in drawn if c.colorbar is not None]
    assert cbar.ax.get_ylabel() == "contact pressure $-\\sigma_n$ (MPa)"
    # one colour scale for stick and slip markers, from 0 to the largest pressure
    assert {c.get_clim() for c in drawn} == {(0.0, float(values.max()))}
    assert ax.get_xlabel() == "distance from the axis r (mm)" and ax.get_ylabel() == "height z (mm)"
    plt.close(fig)


def test_cork_picture_has_units_and_a_key(cork_level2):
    from contactmg.cli.three_d import cork_figure

    prob, res = cork_level2
    fig, ax3, ax2 = cork_figure(prob, res, 0.4, cork.PUSH)
    assert [ax3.get_xlabel(), ax3.get_ylabel(), ax3.get_zlabel()] == ["x (mm)", "y (mm)", "z (mm)"]
    assert [t.get_text() for t in ax3.get_legend().get_texts()] == ["stick", "slip", "no contact"]
    assert any(a.get_ylabel().startswith("contact pressure") and a.get_ylabel().endswith("(MPa)") for a in fig.axes)
    assert "neck wall" in [ln.get_label() for ln in ax2.get_lines()]


def test_radial_stress_plot_data():
    prob = sphere.sphere_problem("hexahedron", 2, 0.1)
    res = prob.solve(tol=1e-11)
    d = radial_stress_data(res)
    x = res.mesh.points[res.contact_nodes[d["index"]]]
    np.testing.assert_allclose(d["r"], np.hypot(x[:, 0], x[:, 1]))
    assert np.all(np.diff(d["r"]) >= 0)
    np.testing.assert_allclose(d["normal"], res.normal_stress[d["index"]])
    ax = plot_radial_stress(res, hertz={"radius": 0.1, "p0": 300.0})
    pressure = ax.lines[0].get_ydata()
    np.testing.assert_allclose(pressure, -res.normal_stress[d["index"]])
    plt.close(ax.figure)
