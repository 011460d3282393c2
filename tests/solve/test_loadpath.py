"""Load paths with the incremental Coulomb law: the one-step path is
today's solve; the incremental path against its own properties (Coulomb's law on the slip
increment, full slip under a large shear, the self-similar stick zone of Spence's incremental
normal loading); the warm start reaches the same solution as a cold start; the time series reads
back."""
import json
import subprocess
import sys

import numpy as np
import pytest

from contactmg.model.frames import to_local
from contactmg.mesh.generators import HERTZ_TOP
from contactmg.examples.hertz import TOP_DISPLACEMENT, hertz_problem
from contactmg.solve.loadpath import LoadPath, two_phase_path
from contactmg.solve.options import resolve_options
from contactmg.results.result import SLIP, STICK
from contactmg.results.series import read_pvd_collection

F = 0.4


@pytest.fixture(scope="module")
def problem():
    return hertz_problem("triangle", 5, F)


def shear_path(problem, steps, shear, shear_steps):
    return two_phase_path(problem, [HERTZ_TOP], (0.0, TOP_DISPLACEMENT), steps, (shear, 0.0), shear_steps)


@pytest.fixture(scope="module")
def normal_then_shear(problem):
    res = shear_path(problem, 6, 0.001, 3).solve(tol=1e-11)
    assert res.converged
    return res


def test_one_step_path_is_the_single_solve(problem):
    """From u = 0 with no previous step the path computes exactly what problem.solve does."""
    ref = problem.solve(tol=1e-11)
    for path in (LoadPath.proportional(problem, 1), shear_path(problem, 1, 0.0, 0)):
        r = path.solve(tol=1e-11).last
        assert np.array_equal(r.displacement, ref.displacement)
        assert np.array_equal(r.node_state, ref.node_state) and r.cycles == ref.cycles
        assert np.array_equal(r.contact_force, ref.contact_force)


def test_one_step_path_on_an_adaptive_hierarchy_takes_the_problem_defaults():
    """There the single solve over-relaxes its post-smoothing and couples the sliding nodes
    (0006-petrov-galerkin-coupling): the path's steps make the same choices, so one step is that solve."""
    from contactmg.examples.hertz import hertz_adaptive_hierarchy

    p = hertz_problem("triangle", 6, 2.0, coulomb_at_zero=True, hierarchy=hertz_adaptive_hierarchy(6, 0.4))
    assert resolve_options(p).petrov_galerkin and resolve_options(p).omega_post != resolve_options(p).omega
    ref = p.solve(tol=1e-11)
    assert ref.extra["petrov_galerkin"]["cycles"] > 0
    r = LoadPath.proportional(p, 1).solve(tol=1e-11).last
    assert np.array_equal(r.displacement, ref.displacement) and r.cycles == ref.cycles


def test_zero_slip_origin_changes_nothing(problem):
    """A slip origin of zero is the reference configuration: the same iterates to the last bit
    (fresh core solvers each: a core's coarse matrices carry over between solves, round-off too)."""
    ref = problem.solver.new_core().solve(None, {"tol": 1e-11})
    core = problem.solver.new_core()
    core.set_slip_origin(np.zeros_like(ref["u"]))
    assert core.has_slip_origin
    raw = core.solve(None, {"tol": 1e-11})
    assert np.array_equal(raw["u"], ref["u"]) and raw["cycles"] == ref["cycles"]


def _increment_checks(r, previous):
    """Coulomb on the slip increment at every contact node of one step."""
    du = r.displacement - (0 if previous is None else previous)
    inc = to_local(r.contact_frames, du[r.contact_nodes])[:, 1]
    sn, st = r.contact_force[:, 0], r.contact_force[:, 1]
    s = r.contact_state
    scale = np.abs(sn).max()
    stick, slip = s == STICK, s == SLIP
    assert np.all(inc[stick] == 0)  # stick: no slip in this step, exactly
    assert np.all(np.abs(st[stick]) <= F * np.abs(sn[stick]) + 1e-9 * scale)
    assert np.all(inc[slip] != 0)
    assert np.all(st[slip] * inc[slip] < 0)  # the friction force opposes the slip increment
    assert np.allclose(np.abs(st[slip]), F * np.abs(sn[slip]), rtol=0, atol=1e-9 * scale)
    return inc


def test_slip_increments_oppose_the_tangential_traction(normal_then_shear):
    previous = None
    for r in normal_then_shear.steps:
        inc = _increment_checks(r, previous)
        assert np.array_equal(inc, r.extra["slip_increment"][:, 0])
        previous = r.displacement


def test_shear_steps_slip_in_the_shear_direction(normal_then_shear):
    """Moving the top in +x drags the body: every sliding node of a shear step slips in +x (the
    frame tangent t = (-1, 0) for n = (0, -1)... so its tangential traction on the body is -x)."""
    for r in normal_then_shear.steps[6:]:
        slip = r.contact_state == SLIP
        assert slip.any()
        assert np.all(r.reaction[0] < 0)  # the obstacle holds the body back
        du_x = r.extra["slip_increment"][slip, 0] * r.contact_frames[slip, 0, 1]
        assert np.all(du_x > 0)


def test_stick_set_grows_under_normal_loading_and_shrinks_under_shear(normal_then_shear):
    """Spence: under increasing normal load a point that sticks keeps sticking (the stick zone
    only grows); the shear phase then releases it from the edges (Cattaneo-Mindlin)."""
    st = [r.contact_state == STICK for r in normal_then_shear.steps]
    for a, b in zip(st[:5], st[1:6]):
        assert np.all(b[a])
    assert st[-1].sum() < st[5].sum()
    assert np.all(st[5][st[-1]])  # the last shear step sticks only where the loading ended sticking


def test_full_slip_identity_beyond_the_friction_limit(problem):
    """A shear far beyond what friction holds: every contact node slides and sum |t| = F sum |n|."""
    r = shear_path(problem, 2, 0.02, 2).solve(tol=1e-11).last
    assert r.converged
    s = r.contact_state
    assert np.all(s[s > 0] == SLIP)
    sn, st = r.contact_force[:, 0], r.contact_force[:, 1]
    assert np.abs(st).sum() == pytest.approx(F * np.abs(sn).sum(), rel=1e-9)
    assert abs(r.reaction[0]) == pytest.approx(F * abs(r.reaction[1]), rel=1e-9)


def test_stick_fraction_is_self_similar_under_incremental_normal_loading():
    """Spence (1975): under monotone proportional normal loading with the incremental law the stick
    zone is a constant fraction of the contact zone (self-similar), unlike the one-step solve."""
    p = hertz_problem("triangle", 6, F)
    res = LoadPath.proportional(p, 6).solve(tol=1e-10)
    assert res.converged
    h = p.mesh.points[p.contact.nodes, 0]
    width = np.diff(np.sort(h[np.abs(h) < 0.05])).max()  # the boundary mesh width near the contact
    frac = []
    for r in res.steps[2:]:  # once several elements are in contact
        a, b = r.halfwidth((STICK, SLIP)), r.halfwidth((STICK,))
        assert 0 < b < a
        frac.append((b, a))
    ratios = [b / a for b, a in frac]
    # the incremental stick zone is not the one-step one
    one = p.solve(tol=1e-10)
    assert res.last.halfwidth((STICK,)) > one.halfwidth((STICK,)) + 2 * width
    # constant up to the resolution of the zone edges (one boundary element at each edge)
    for b, a in frac:
        assert abs(b / a - np.mean(ratios)) <= 2 * width / a


def test_warm_and_cold_starts_reach_the_same_step_solution(problem):
    """Each step's incremental problem solved from u^{k-1} and from 0 (same slip origin): one
    solution (F = 0.4: unique), to the tolerance."""
    path = shear_path(problem, 3, 0.001, 2)
    warm = path.solve(tol=1e-11)
    cold = path.solve(tol=1e-11, warm_start=False)
    assert warm.converged and cold.converged
    for w, c in zip(warm.steps, cold.steps):
        scale = np.abs(w.displacement).max()
        assert np.abs(w.displacement - c.displacement).max() <= 1e-8 * scale
        assert np.array_equal(w.node_state, c.node_state)


def test_time_series_reads_back_with_meshio(normal_then_shear, tmp_path):
    files = normal_then_shear.write_pvd(tmp_path / "path.pvd")
    frames = read_pvd_collection(tmp_path / "path.pvd")
    assert len(frames) == len(files) == len(normal_then_shear.steps)
    for (t, m), r in zip(frames, normal_then_shear.steps):
        assert t == r.extra["parameter"]
        assert np.array_equal(m.point_data["displacement"][:, :2], r.displacement)
        assert np.array_equal(m.point_data["node_state"], r.node_state)
        inc = np.zeros(r.mesh.num_points)
        inc[r.contact_nodes] = r.extra["slip_increment"][:, 0]
        assert np.array_equal(m.point_data["slip_increment"], inc)


def test_zone_plot_draws_every_step_state(normal_then_shear):
    import matplotlib
    matplotlib.use("Agg")
    from contactmg.results.plots_loadpath import plot_zones_over_steps

    ax = plot_zones_over_steps(normal_then_shear)
    lines = [ln for ln in ax.get_lines() if ln.get_marker() == "|"]
    stick = sum(len(ln.get_xdata()) for ln in lines if ln.get_color() == "tab:blue")
    slip = sum(len(ln.get_xdata()) for ln in lines if ln.get_color() == "tab:red")
    assert stick == sum(r.counts()["stick_nodes"] for r in normal_then_shear.steps)
    assert slip == sum(r.counts()["slip_nodes"] for r in normal_then_shear.steps)


def test_bad_path_input(problem):
    with pytest.raises(ValueError, match="at least one step"):
        LoadPath(problem, [])
    with pytest.raises(ValueError, match="one entry per"):
        LoadPath(problem, [0.5, 1.0], dirichlet=[[]])
    with pytest.raises(ValueError, match="steps must be"):
        LoadPath.proportional(problem, 0)
    with pytest.raises(ValueError, match="load path is solved"):
        LoadPath.proportional(problem, 2).solve(method="linear")
    from contactmg.model.problem import Dirichlet
    with pytest.raises(ValueError, match="other components"):
        LoadPath(problem, [1.0], dirichlet=lambda t: [Dirichlet([HERTZ_TOP], (None, -0.005))]).solve()


def run(*args):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=300)


STEP_KEYS = ["cycles", "converged", "reaction", "contact_halfwidth", "stick_halfwidth", "contact_nodes", "stick_nodes",
             "slip_nodes"]


def test_cli_hertz_steps_and_shear(tmp_path):
    pvd = tmp_path / "h.pvd"
    r = run("hertz", "--levels", "4", "--steps", "3", "--shear", "0.001", "--shear-steps", "2", "--json", "-", "-q",
            "--series", str(pvd), "--zone-plot", str(tmp_path / "z.png"))
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert len(d["steps"]) == 5 and all(all(k in s for k in STEP_KEYS) for s in d["steps"])
    last = d["steps"][-1]
    for k in ("cycles", "reaction", "contact_nodes", "stick_nodes", "slip_nodes", "stick_halfwidth"):
        assert d[k] == last[k]
    assert d["path"]["total_cycles"] == sum(s["cycles"] for s in d["steps"])
    assert d["reaction"][0] < 0 < d["reaction"][1]  # sheared in +x: the obstacle pulls back
    assert len(read_pvd_collection(pvd)) == 5 and (tmp_path / "z.png").stat().st_size > 0


@pytest.mark.parametrize("args,word", [
    (["--shear-steps", "2"], "--shear"), (["--steps", "2", "--method", "linear"], "linear"),
    (["--steps", "0"], "--steps"), (["--series", "x.vtu", "--steps", "2"], "--series"), (["--series", "x.pvd"], "--steps"),
    (["--shear", "nan"], "--shear"),
])
def test_cli_bad_path_options_exit_2(args, word):
    r = run("hertz", "--levels", "2", *args)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert word in r.stderr.strip().splitlines()[-1]


def test_cli_sphere_steps():
    r = run("sphere", "--levels", "2", "--steps", "2", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert len(d["steps"]) == 2 and all("contact_radius" in s and "stick_radius" in s for s in d["steps"])
    assert d["steps"][1]["reaction"][2] > d["steps"][0]["reaction"][2] > 0
    assert d["contact_radius"] == d["steps"][-1]["contact_radius"]


def test_cli_cork_push_and_pull_back_dissipates():
    """Push the cork in and move the plunger back: at the same plunger position the force on the
    way back is below the force on the way in (friction holds the cork against both motions: the
    incremental law remembers the path; the one-step law could not tell the two apart)."""
    r = run("cork", "--levels", "2", "--steps", "2", "--pull-back", "--pull-back-steps", "2", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)["steps"]
    assert [x["parameter"] for x in s] == [0.5, 1.0, 1.5, 2.0]
    assert s[0]["push_force"] > 0 and s[1]["push_force"] > s[0]["push_force"]
    assert s[2]["push_force"] < s[0]["push_force"]  # the same plunger position, D / 2
    r = run("cork", "--levels", "2", "--pull-back-steps", "2")
    assert r.returncode == 2 and "--pull-back" in r.stderr.strip().splitlines()[-1]


def test_cork_on_eight_axial_layers_pushed_and_pulled_back():
    """The finer coarse mesh of the cork (8 axial layers) on the push-and-pull-back path: it
    stopped with "the coarsest-level matrix is singular" -- nodes sliding by a round-off slip
    increment put friction Hessians of 1e17 on the coarse diagonal, whose incremental removal left
    the coarsest matrix indefinite. Every step now converges to a state that meets Coulomb's
    law on the increment, and the way back takes less force than the way in at the same plunger
    position."""
    from contactmg.examples import cork
    from contactmg.mesh.generators_3d import CORK_TOP

    p = cork.cork_problem(2, F, cork.PUSH, axial_layers=8)
    res = two_phase_path(p, [CORK_TOP], (0.0, 0.0, -cork.PUSH), 2, (0.0, 0.0, cork.PUSH), 2).solve(tol=1e-11)
    assert res.converged and len(res.steps) == 4
    for r in res.steps:
        s, inc = r.contact_state, r.extra["slip_increment"]
        n, t = np.abs(r.contact_force[:, 0]), r.contact_force[:, 1:]
        scale = n.max()
        # zero up to the round-off of the rotated frames on the conical neck
        assert np.abs(inc[s == STICK]).max(initial=0.0) <= 1e-12 * np.abs(r.displacement).max()
        assert np.all(np.linalg.norm(t[s == STICK], axis=1) <= F * n[s == STICK] + 1e-9 * scale)
        slip = s == SLIP
        unit = inc[slip] / np.linalg.norm(inc[slip], axis=1)[:, None]
        assert np.abs(t[slip] + F * n[slip][:, None] * unit).max(initial=0.0) <= 1e-8 * scale
    force = [cork.push_force(p, r) for r in res.steps]
    assert 0 < force[0] < force[1] and force[2] < force[0]


def test_fixed_point_path_reaches_the_nmg_path():
    """Algorithm 1 on the same incremental steps (Tresca solves with the bound of the previous
    outer iterate, friction on the increment) reaches the steps of Algorithm 2 (F = 0.4: unique)."""
    p = hertz_problem("triangle", 4, F, coulomb_at_zero=True)
    path = shear_path(p, 2, 0.001, 1)
    a, b = path.solve("nmg", tol=1e-12), path.solve("fixed-point", tol=1e-12)
    assert a.converged and b.converged
    for x, y in zip(a.steps, b.steps):
        assert np.abs(x.displacement - y.displacement).max() <= 1e-7 * np.abs(x.displacement).max()
        assert np.array_equal(x.node_state, y.node_state)


def test_3d_friction_force_opposes_the_slip_increment():
    """Sphere (3D, two tangential components): normal loading then a shear along x; at every
    sliding node the tangential force is -F |n| times the unit slip increment, at every sticking
    node the increment is exactly zero and |t| <= F |n|."""
    from contactmg.mesh.generators_3d import BALL_TOP
    from contactmg.examples.sphere import DISPLACEMENT, sphere_problem

    p = sphere_problem("hexahedron", 2, F)
    res = two_phase_path(p, [BALL_TOP], (0.0, 0.0, -DISPLACEMENT), 2, (0.008, 0.0, 0.0), 2).solve(tol=1e-11)
    assert res.converged
    for r in res.steps:
        s, inc = r.contact_state, r.extra["slip_increment"]
        n, t = np.abs(r.contact_force[:, 0]), r.contact_force[:, 1:]
        scale = n.max()
        stick, slip = s == STICK, s == SLIP
        assert np.all(inc[stick] == 0)
        assert np.all(np.linalg.norm(t[stick], axis=1) <= F * n[stick] + 1e-9 * scale)
        unit = inc[slip] / np.linalg.norm(inc[slip], axis=1)[:, None]
        assert np.abs(t[slip] + F * n[slip][:, None] * unit).max(initial=0.0) <= 1e-8 * scale
    assert (res.last.contact_state == SLIP).sum() > (res.steps[1].contact_state == SLIP).sum()


def test_the_default_method_is_the_problems_as_for_a_single_solve():
    """method=None means what it means for problem.solve: the method the problem's default_options
    name, else resolve_options' choice for the problem -- but nmg where that is tnnmg, which takes no
    slip origin; a method given (to solve or in its options) still wins."""
    from contactmg.model.material import Material
    from contactmg.model.problem import Body, Dirichlet, Problem
    from contactmg.solve.options import options_from

    def methods(path_result):
        assert path_result.converged
        return {r.method for r in path_result.steps}

    named = hertz_problem("triangle", 3, F)  # its defaults name nmg
    path = LoadPath.proportional(named, 2)
    default, nmg = path.solve(tol=1e-11), path.solve("nmg", tol=1e-11)
    assert methods(default) == {"nmg"} and default.cycles == nmg.cycles
    assert np.array_equal(default.last.displacement, nmg.last.displacement)
    named.default_options = options_from(named.default_options).replace(method="fixed-point")
    assert methods(path.solve(tol=1e-11)) == {"fixed-point"}
    assert methods(path.solve("nmg", tol=1e-11)) == {"nmg"}
    assert methods(path.solve(options=dict(method="nmg", tol=1e-11))) == {"nmg"}
    named.default_options = options_from(named.default_options).replace(method="tnnmg")
    with pytest.raises(ValueError, match="load path is solved by one of"):
        path.solve()

    # no defaults of its own: the solver's choice, nmg on the Hertz material; tnnmg (for the
    # nearly incompressible one) turns to nmg
    for nu, single in ((0.28, "nmg"), (0.49, "tnnmg")):
        body = Body(named.hierarchy, Material(2000.0, nu), [Dirichlet([HERTZ_TOP], (0.0, TOP_DISPLACEMENT))],
                    contact_tags=named.bodies[0].contact_tags)
        p = Problem(body, obstacle=named.obstacle, friction=named.friction)
        assert p.default_options is None and resolve_options(p).method == single
        assert methods(LoadPath.proportional(p, 2).solve(max_cycles=300)) == {"nmg"}
