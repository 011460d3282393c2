"""`contactmg run MODEL.toml`: the example models solved from their files, checked against the laws
of statics, the friction law and a solve of the same model through the Python API; bad model files
refused with exit status 2 and one line naming the file and the key."""
import json
import warnings
import os
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from contactmg.cli.main import main
from contactmg.cli.model_file import ModelError, read_model
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.mesh.io import read_mesh
from contactmg.model.friction import Coulomb
from contactmg.model.material import Material
from contactmg.model.obstacle import PlaneObstacle
from contactmg.model.problem import Body, ContactPair, Dirichlet, Problem
from contactmg.results.series import read_pvd_collection
from contactmg.solve.loadpath import LoadPath

MODELS = Path(__file__).resolve().parents[2] / "examples" / "models"
KEYS = ["command", "model", "dim", "cell", "bodies", "levels", "multigrid_levels", "notes", "nodes", "dofs", "method", "law", "friction", "tol",
        "converged", "status", "cycles", "cycles_per_step", "steps", "path", "setup_seconds", "solve_seconds",
        "read_seconds", "seconds", "contact_nodes", "stick_nodes", "slip_nodes", "contact_forces", "reactions", "spring_forces", "load",
        "max_von_mises", "check", "check_max", "peak_rss_mb", "outputs"]


def example(name, tmp_path):
    """A copy of an example folder (its outputs are written next to the model file)."""
    dst = tmp_path / name
    shutil.copytree(MODELS / name, dst)
    return dst


def run_main(capsys, *args):
    rc = main(["run", *map(str, args)])
    out, err = capsys.readouterr()
    return rc, out, err


def total(forces):
    return np.sum([np.asarray(f, float) for f in forces], axis=0)


# -- the examples -----------------------------------------------------------------------------
def test_block_2d_slides_in_equilibrium_and_matches_the_python_api(tmp_path, capsys):
    d = example("block_2d", tmp_path)
    rc, out, err = run_main(capsys, d / "block.toml", "-q")
    assert rc == 0, err
    assert out == "" and err == ""
    rep = json.loads((d / "out" / "block.json").read_text())
    assert all(k in rep for k in KEYS), set(KEYS) - set(rep)
    assert rep["command"] == "run" and rep["converged"] and rep["dim"] == 2 and rep["law"] == "coulomb"
    assert len(rep["steps"]) == 5 and rep["path"]["parameters"] == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0])
    assert rep["cycles_per_step"] == [s["cycles"] for s in rep["steps"]] and rep["cycles"] == rep["cycles_per_step"][-1]
    assert rep["dofs"] == 2 * rep["nodes"] and rep["check_max"] < 1e-8

    # statics: the loads, computed here from the file's data (traction 0.5 on the left edge of
    # length 0.5, body force -2 on the area 0.5), the support reaction and the contact force add up to 0
    load = np.array([0.5 * 0.5, -2.0 * 0.5])
    assert rep["load"] == pytest.approx(load, rel=1e-12)
    (reaction,) = rep["reactions"]
    assert reaction["tags"] == [3] and reaction["body"] == "block"
    contact = np.asarray(rep["contact_forces"]["obstacle"])
    balance = np.asarray(reaction["force"]) + contact + load
    assert np.abs(balance).max() <= 1e-10 * np.abs(contact).max()

    # Coulomb: the shear exceeds the bound, every contact node slides and the tangential force is F
    # times the normal force (the obstacle pushes up and holds the block back against its push right)
    assert rep["slip_nodes"] == rep["contact_nodes"] > 0 and rep["stick_nodes"] == 0
    assert contact[1] > 0 and contact[0] < 0
    assert abs(contact[0]) == pytest.approx(0.3 * contact[1], rel=1e-8)

    # the same model through the Python API: the same cycles and displacement
    mesh = read_mesh(d / "block.msh")
    body = Body(MeshHierarchy.build(mesh, 4), Material(1000.0, 0.3), [Dirichlet([3], (0.02, -0.005))],
                contact_tags=[1], body_force=(0.0, -2.0), traction={4: (0.5, 0.0)})
    problem = Problem(body, obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=Coulomb(0.3))
    path = LoadPath.proportional(problem, 5).solve("nmg", tol=1e-11)
    assert path.cycles == rep["cycles_per_step"]
    vtu = meshio.read(d / "out" / "block.vtu")
    assert np.abs(vtu.point_data["displacement"][:, :2] - path.last.displacement).max() <= 1e-14
    assert np.allclose(path.last.contact_forces()["obstacle"], contact, rtol=1e-12, atol=0)

    # the series: one frame per step, the load parameter as its time, the last frame the VTU's
    frames = read_pvd_collection(d / "out" / "block.pvd")
    assert [t for t, _ in frames] == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0])
    assert np.array_equal(frames[-1][1].point_data["displacement"], vtu.point_data["displacement"])
    assert (d / "out" / "block.png").read_bytes()[:4] == b"\x89PNG"


def test_block_3d_on_a_ball_balances_and_touches_under_its_centre(tmp_path, capsys):
    d = example("block_3d", tmp_path)
    rc, out, err = run_main(capsys, d / "block.toml", "--json", "-", "-q")
    assert rc == 0, err
    rep = json.loads(out)
    assert json.loads((d / "out" / "block.json").read_text()) == rep  # --json and output.json: one report
    assert rep["dim"] == 3 and rep["cell"] == "hexahedron" and rep["converged"] and len(rep["steps"]) == 2
    contact = np.asarray(rep["contact_forces"]["obstacle"])
    (reaction,) = rep["reactions"]
    # no loads: the top's reaction is the ball's force reversed
    assert np.abs(np.asarray(reaction["force"]) + contact).max() <= 1e-10 * np.abs(contact).max()
    assert contact[2] > 0
    # the block and the ball are symmetric about x = 0.5 and y = 0.5: no net tangential force
    assert np.abs(contact[:2]).max() <= 1e-8 * contact[2]
    # a ball touches a patch under the centre, not the whole bottom face (area 1)
    assert 0 < rep["contact_extent"] < 0.9
    vtu = meshio.read(d / "out" / "block.vtu")
    x = vtu.points
    state = vtu.point_data["node_state"]
    touching = x[state > 0]
    assert np.all(np.hypot(touching[:, 0] - 0.5, touching[:, 1] - 0.5) < np.hypot(0.5, 0.5))


def test_two_blocks_mortar_pair_balances(tmp_path, capsys):
    d = example("two_blocks", tmp_path)
    rc, out, err = run_main(capsys, d / "blocks.toml")
    assert rc == 0, err
    assert "contact force pair 0" in out  # output.summary prints the result's table
    rep = json.loads((d / "out" / "blocks.json").read_text())
    assert [b["name"] for b in rep["bodies"]] == ["upper", "lower"] and rep["converged"]
    pair = np.asarray(rep["contact_forces"]["pair 0"])  # the lower body's force on the upper one
    forces = {r["body"]: np.asarray(r["force"]) for r in rep["reactions"]}
    scale = np.abs(pair).max()
    assert pair[1] > 0
    # the upper body: top reaction and contact force; the lower one: its weight 1 x 1.4 x 0.5 down,
    # the contact force reversed and the clamp's reaction
    assert np.abs(forces["upper"] + pair).max() <= 1e-10 * scale
    assert np.abs(forces["lower"] - pair + np.array([0.0, -0.7])).max() <= 1e-10 * scale
    assert rep["load"] == pytest.approx([0.0, -0.7], abs=1e-12)

    # the same model through the Python API
    up, lo = read_mesh(d / "upper.msh"), read_mesh(d / "lower.msh")
    upper = Body(MeshHierarchy.build(up, 3), Material(1000.0, 0.3), [Dirichlet([3], (0.002, -0.01))])
    lower = Body(MeshHierarchy.build(lo, 3), Material(2000.0, 0.25), [Dirichlet([1], (0.0, 0.0))],
                 body_force=(0.0, -1.0))
    problem = Problem([upper, lower], pairs=[ContactPair(0, 1, [1], [3], 0.1)], friction=Coulomb(0.3))
    res = problem.solve("nmg")
    assert res.cycles == rep["cycles"]
    vtu = meshio.read(d / "out" / "blocks.vtu")
    assert np.abs(vtu.point_data["displacement"][:, :2] - res.displacement).max() <= 1e-14
    # the bodies told apart in the VTU, as Problem.write_vtu does: 0 on the upper body's nodes, then 1
    assert np.array_equal(vtu.point_data["body_id"], np.repeat([0, 1], [b["nodes"] for b in rep["bodies"]]))


def test_seconds_is_the_whole_command_with_the_reading(tmp_path, capsys):
    """`seconds` holds the reading of the model and its meshes, the set-up (hierarchies, assembly,
    the core's build) and the solve, which do not overlap; `path.seconds` stays the solve's."""
    d = example("block_2d", tmp_path)
    rc, _, err = run_main(capsys, d / "block.toml", "-q")
    assert rc == 0, err
    rep = json.loads((d / "out" / "block.json").read_text())
    assert rep["read_seconds"] > 0 and rep["setup_seconds"] > 0 and rep["solve_seconds"] > 0
    assert rep["seconds"] >= rep["read_seconds"] + rep["setup_seconds"] + rep["solve_seconds"]
    assert rep["seconds"] > rep["path"]["seconds"] >= rep["solve_seconds"]


def test_a_warning_prints_as_one_line_without_the_python_source(tmp_path):
    """The obstacle placed 0.2 into the block: the warning about it is one line of the command's own,
    with neither the file and line of the library nor its source line."""
    d = example("block_2d", tmp_path)
    model = d / "block.toml"
    text = model.read_text().replace("point = [0.0, 0.0]", "point = [0.0, 0.2]").replace("count = 5", "count = 1")
    model.write_text(text.replace("levels = 4", "levels = 2"))
    r = subprocess.run([sys.executable, "-m", "contactmg", "run", str(model), "-q"], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactmg: warning: 9 node(s) of the facets tagged [1] start "
                                                   "inside the obstacle"), r.stderr
    assert ".py" not in r.stderr and "UserWarning" not in r.stderr


def test_the_command_leaves_the_warning_format_of_its_caller():
    import warnings
    before = warnings.showwarning
    main(["run", "/no/such/model.toml"])
    assert warnings.showwarning is before


def test_no_convergence_exits_3_with_the_json_written(tmp_path, capsys):
    d = example("block_2d", tmp_path)
    model = d / "block.toml"
    model.write_text(model.read_text().replace("tol = 1e-11", "tol = 1e-11\nmax_cycles = 2"))
    rc, out, err = run_main(capsys, model, "-q")
    assert rc == 3
    rep = json.loads((d / "out" / "block.json").read_text())
    assert rep["converged"] is False and rep["steps"][0]["cycles"] == 2
    # a load path stops at the first step that does not converge
    assert rep["path"]["steps_solved"] == 1 and rep["path"]["steps"] == 5


def test_single_step_without_obstacle_is_linear_elasticity(tmp_path, capsys):
    """No obstacle: one linear solve; the clamp holds the body force (reaction = -load)."""
    shutil.copy(MODELS / "block_2d" / "block.msh", tmp_path)
    (tmp_path / "m.toml").write_text(
        '[[body]]\nname = "b"\nmesh = "block.msh"\nlevels = 3\nmaterial = { E = 10.0, nu = 0.2 }\n'
        'body_force = [1.0, -3.0]\n[[body.dirichlet]]\ntags = [4]\nvalue = [0.0, 0.0]\n'
        '[output]\njson = "r.json"\npvd = "r.pvd"\n')
    rc, _, err = run_main(capsys, tmp_path / "m.toml", "-q")
    assert rc == 0, err
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["law"] == "linear" and rep["contact_forces"] == {} and rep["contact_nodes"] == 0
    (reaction,) = rep["reactions"]
    assert np.asarray(reaction["force"]) == pytest.approx([-0.5, 1.5], rel=1e-10)
    assert len(read_pvd_collection(tmp_path / "r.pvd")) == 1


# -- bad model files ----------------------------------------------------------------------------
BASE = """
[[body]]
name = "block"
mesh = "block.msh"
levels = 2
material = { E = 1000.0, nu = 0.3 }
[[body.dirichlet]]
tags = [3]
value = [0.0, -0.01]
[[body.dirichlet]]
tags = [2]
value = ["free", 0.0]
[[obstacle]]
body = "block"
tags = [1]
type = "plane"
point = [0.0, 0.0]
normal = [0.0, -1.0]
[friction]
law = "coulomb"
coefficient = 0.3
[solver]
tol = 1e-10
"""


def bad_model(tmp_path, old, new):
    shutil.copy(MODELS / "block_2d" / "block.msh", tmp_path)
    text = BASE.replace(old, new)
    assert text != BASE or old == new
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path


def test_the_base_of_the_bad_models_is_good(tmp_path, capsys):
    rc, _, err = run_main(capsys, bad_model(tmp_path, "", ""), "-q")
    assert rc == 0, err


@pytest.mark.parametrize("old,new,key,words", [
    ('name = "block"\nmesh', 'name = "block"\nmsh = "x"\nmesh', "body[0].msh", ["unknown key", "did you mean 'mesh'"]),
    ("[friction]", "[fricton]", "fricton", ["did you mean 'friction'"]),
    ("levels = 2", 'levels = "two"', "body[0].levels", ["integer"]),
    ("levels = 2", "levels = 0", "body[0].levels", ["1..12"]),
    ("tags = [2]", "tags = [9]", "body[0].dirichlet[1].tags", ["no boundary facet", "9"]),
    ("tags = [2]", 'tags = ["2"]', "body[0].dirichlet[1].tags", ["integer"]),
    ('value = ["free", 0.0]', "value = [0.0]", "body[0].dirichlet[1].value", ["2 numbers"]),
    ('value = ["free", 0.0]', 'value = ["loose", 0.0]', "body[0].dirichlet[1].value[0]", ["free"]),
    ("tags = [1]\ntype", "tags = [7]\ntype", "obstacle[0].tags", ["no boundary facet"]),
    ('type = "plane"', 'type = "plain"', "obstacle[0].type", ["did you mean 'plane'"]),
    ('body = "block"\ntags', 'body = "blok"\ntags', "obstacle[0].body", ["no body is named 'blok'"]),
    ("normal = [0.0, -1.0]", "normal = [0.0, 0.0]", "obstacle[0].normal", ["zero"]),
    ("nu = 0.3", "nu = 0.5", "body[0].material.nu", ["(-1, 0.5)"]),
    ("E = 1000.0", "E = -1.0", "body[0].material.E", ["positive"]),
    ("coefficient = 0.3", "coefficient = -0.3", "friction.coefficient", ["negative"]),
    ('law = "coulomb"', 'law = "colomb"', "friction.law", ["did you mean 'coulomb'"]),
    ("tol = 1e-10", "tolerance = 1e-10", "solver.tolerance", ["did you mean 'tol'"]),
    ("tol = 1e-10", 'method = "newton"', "solver.method", ["method must be one of"]),
    ("tol = 1e-10", "max_cycles = 0", "solver.max_cycles", ["max_cycles"]),
    ("tol = 1e-10", 'tol = 1e-10\nmethod = "linear"\n[steps]\ncount = 3', "solver.method", ["load steps"]),
    ("[solver]", "[steps]\ncount = 0\n[solver]", "steps.count", ["1..100000"]),
    ("[solver]", '[output]\nvtu = "out.txt"\n[solver]', "output.vtu", [".vtu"]),
    ('mesh = "block.msh"', 'mesh = "nothere.msh"', "body[0].mesh", ["no such file"]),
    ("levels = 2", "levels = 2\nbody_force = [0.0, 1.0, 2.0]", "body[0].body_force", ["2 numbers", "2D"]),
    ("[friction]", '[[pair]]\nnonmortar = "block"\nmortar = "block"\nnonmortar_tags = [1]\nmortar_tags = [3]\n'
                   'search = 0.1\n[friction]', "pair[0].mortar", ["two different bodies"]),
    ("tol = 1e-10", "tol = 1e-10\n[solver.extra]", "solver.extra", ["unknown key"]),
    ("levels = 2", 'levels = 2\nhierarchy = "coarsening"', "body[0].hierarchy", ["levels must be 1"]),
    ("levels = 2", 'levels = 1\nhierarchy = "algebraic"', "body[0].hierarchy", ["must be one of refine, coarsening"]),
    ("[friction]", "[friction\n", None, ["not valid TOML"]),
])
def test_bad_model_exits_2_with_one_line_naming_file_and_key(tmp_path, capsys, old, new, key, words):
    path = bad_model(tmp_path, old, new)
    rc, out, err = run_main(capsys, path, "-q")
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith(f"contactmg run: error: {path}: ")
    if key is not None:
        assert f": {key}: " in lines[0]
    for w in words:
        assert w in lines[0], lines[0]


def test_a_missing_model_file_through_the_command(tmp_path):
    missing = tmp_path / "absent.toml"
    r = subprocess.run([sys.executable, "-m", "contactmg", "run", str(missing)], capture_output=True, text=True,
                       timeout=60, env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2] / "python")})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines() == [f"contactmg run: error: {missing}: no such file"]


def test_read_model_raises_model_error_with_its_parts(tmp_path):
    path = bad_model(tmp_path, "tags = [2]", "tags = [9]")
    with pytest.raises(ModelError) as e:
        read_model(path)
    assert e.value.file == str(path) and e.value.key == "body[0].dirichlet[1].tags"
    assert isinstance(e.value, ValueError)


# -- loads, supports and regions ----------------------------------------------------------------
LOADED = """
[[body]]
name = "slab"
mesh = "slab.msh"
levels = 3
materials = [ { region = 1, E = 1000.0, nu = 0.3, density = 1.0 },
              { region = 2, E = 3000.0, nu = 0.2, density = 2.0 } ]
gravity = [0.0, -9.81]
[[body.dirichlet]]
tags = [4]
value = [0.0, "free"]
[[body.pressure]]
tags = [3]
value = 2.0
[[body.spring]]
tags = [2]
stiffness = [0.0, 50.0]
[[body.point_load]]
point = [1.0, 0.5]
force = [0.1, -0.3]
[[obstacle]]
body = "slab"
tags = 1
type = "plane"
point = [0.0, 0.0]
normal = [0.0, -1.0]
[output]
json = "slab.json"
vtu = "slab.vtu"
"""


def slab_mesh(tmp_path):
    """The block 1 x 0.5 with two regions: cells below y = 0.25 region 1, above region 2."""
    from contactmg.mesh.generators import rectangle
    from contactmg.mesh.io import write_mesh

    m = rectangle(4, 2, lx=1.0, ly=0.5)
    m.cell_tags = np.where(m.points[m.cells].mean(axis=1)[:, 1] < 0.25, 1, 2).astype(np.int64)
    write_mesh(tmp_path / "slab.msh", m)
    return tmp_path / "slab.msh"


def test_pressure_gravity_point_load_springs_and_regions(tmp_path, capsys):
    """Frictionless contact: the obstacle's force is normal (y); statics in x and y with the loads
    computed here from the file's numbers and the springs' force from the displacement."""
    slab_mesh(tmp_path)
    (tmp_path / "slab.toml").write_text(LOADED)
    rc, _, err = run_main(capsys, tmp_path / "slab.toml", "-q")
    assert rc == 0, err
    rep = json.loads((tmp_path / "slab.json").read_text())
    # pressure 2 on the top (length 1) pushes down; the point load; the weight of the two halves (0.25 each)
    load = np.array([0.1, -2.0 * 1.0 - 0.3 - 9.81 * (1.0 * 0.25 + 2.0 * 0.25)])
    assert rep["load"] == pytest.approx(load, rel=1e-12)
    contact = np.asarray(rep["contact_forces"]["obstacle"])
    (reaction,) = rep["reactions"]
    vtu = meshio.read(tmp_path / "slab.vtu")
    x, u = vtu.points[:, :2], vtu.point_data["displacement"][:, :2]
    right = np.nonzero(np.abs(x[:, 0] - 1.0) < 1e-12)[0]
    right = right[np.argsort(x[right, 1])]
    h = np.diff(x[right, 1])
    share = np.r_[h, 0.0] / 2 + np.r_[0.0, h] / 2  # each node's part of the edge (the lumped measure)
    spring = np.array([0.0, -50.0 * np.sum(share * u[right, 1])])
    balance = contact + np.asarray(reaction["force"]) + spring + load
    assert np.abs(balance).max() <= 1e-10 * np.abs(load).max()
    assert contact[0] == pytest.approx(0.0, abs=1e-12 * contact[1]) and contact[1] > 0
    assert abs(spring[1]) > 1e-6  # the spring does carry load
    (reported,) = rep["spring_forces"]
    assert reported["body"] == "slab" and reported["tags"] == [2]
    assert reported["force"] == pytest.approx(spring, rel=1e-10, abs=1e-12)

    from contactmg.model.loads import PointLoad
    mesh = read_mesh(tmp_path / "slab.msh")
    body = Body(MeshHierarchy.build(mesh, 3), {1: Material(1000.0, 0.3, 1.0), 2: Material(3000.0, 0.2, 2.0)},
                [Dirichlet([4], (0.0, None))], contact_tags=[1], gravity=(0.0, -9.81), pressure={3: 2.0},
                springs={2: (0.0, 50.0)}, point_loads=[PointLoad((1.0, 0.5), (0.1, -0.3))])
    res = Problem(body, obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0))).solve("nmg")
    assert res.cycles == rep["cycles"]
    assert np.abs(u - res.displacement).max() <= 1e-14


def test_the_report_and_summary_give_the_spring_forces_and_the_statics_close(tmp_path, capsys):
    """The report's forces alone (contact, reactions, springs) balance the load, as the guide says;
    the summary table lists the spring's force too."""
    slab_mesh(tmp_path)
    (tmp_path / "slab.toml").write_text(LOADED + "summary = true\n")
    rc, out, err = run_main(capsys, tmp_path / "slab.toml")
    assert rc == 0, err
    rep = json.loads((tmp_path / "slab.json").read_text())
    load = np.asarray(rep["load"])
    springs = [np.asarray(s["force"]) for s in rep["spring_forces"]]
    assert len(springs) == 1 and abs(springs[0][1]) > 1e-6 * abs(load[1])
    forces = list(rep["contact_forces"].values()) + [r["force"] for r in rep["reactions"]] + springs
    assert np.abs(total(forces) + load).max() <= 1e-10 * np.abs(load).max()
    row = next(line for line in out.splitlines() if line.startswith("spring force 2"))
    assert float(row.split("(")[1].split(",")[1].rstrip(")")) == pytest.approx(springs[0][1], rel=1e-5)


@pytest.mark.parametrize("old,new,key,words", [
    (", density = 2.0 }", " }", "body[0].gravity", ["density", "every region"]),
    ("{ region = 2,", "{ region = 5,", "body[0].materials[1].region", ["no cell carries the region tag 5"]),
    ("              { region = 2, E = 3000.0, nu = 0.2, density = 2.0 } ]", "]", "body[0].materials",
     ["region(s) 2 have no material"]),
    ("point = [1.0, 0.5]", "point = [0.9, 0.5]", "body[0].point_load[0].point", ["no mesh node"]),
    ("stiffness = [0.0, 50.0]", 'stiffness = "stiff"', "body[0].spring[0].stiffness", ["number"]),
    ("value = 2.0", "value = [2.0, 0.0]", "body[0].pressure[0].value", ["number"]),
    ("[[body.pressure]]\ntags = [3]", "[[body.pressure]]\ntags = [13]", "body[0].pressure[0].tags",
     ["no boundary facet"]),
])
def test_bad_loads_and_regions(tmp_path, capsys, old, new, key, words):
    slab_mesh(tmp_path)
    text = LOADED.replace(old, new)
    assert text != LOADED
    (tmp_path / "slab.toml").write_text(text)
    rc, _, err = run_main(capsys, tmp_path / "slab.toml", "-q")
    assert rc == 2
    (line,) = err.strip().splitlines()
    assert f"slab.toml: {key}: " in line
    for w in words:
        assert w in line, line


@pytest.mark.parametrize("lower", ['levels = 2', 'levels = 1\nhierarchy = "coarsening"'])
def test_two_blocks_of_unequal_hierarchies_balance(tmp_path, capsys, lower):
    """The lower body refined once less, or coarsened from its mesh alone, beside the upper body's
    three levels: the model solves and its statics hold as with equal levels."""
    d = example("two_blocks", tmp_path)
    model = d / "blocks.toml"
    text = model.read_text()
    old = "levels = 3\nmaterial = { E = 2000.0"
    assert old in text
    model.write_text(text.replace(old, lower + "\nmaterial = { E = 2000.0", 1))
    rc, _, err = run_main(capsys, model, "-q")
    assert rc == 0, err
    rep = json.loads((d / "out" / "blocks.json").read_text())
    assert rep["converged"] and [b["levels"] for b in rep["bodies"]][0] == 3
    pair = np.asarray(rep["contact_forces"]["pair 0"])
    forces = {r["body"]: np.asarray(r["force"]) for r in rep["reactions"]}
    scale = np.abs(pair).max()
    assert np.abs(forces["upper"] + pair).max() <= 1e-10 * scale
    assert np.abs(forces["lower"] - pair + np.array([0.0, -0.7])).max() <= 1e-10 * scale


@pytest.mark.parametrize("old,new,key,words", [
    ('mortar = "lower"', 'mortar = "lowr"', "pair[0].mortar", ["did you mean 'lower'"]),
    ("mortar_tags = [3]", "mortar_tags = [5]", "pair[0].mortar_tags", ["lower.msh"]),
    ("search = 0.1", "search = -0.1", "pair[0].search", ["positive"]),
    ('name = "lower"', 'name = "upper"', "body[1].name", ["taken by body[0]"]),
])
def test_bad_two_body_models(tmp_path, capsys, old, new, key, words):
    d = example("two_blocks", tmp_path)
    model = d / "blocks.toml"
    text = model.read_text()
    assert old in text
    model.write_text(text.replace(old, new, 1))
    rc, _, err = run_main(capsys, model, "-q")
    assert rc == 2
    (line,) = err.strip().splitlines()
    assert f"blocks.toml: {key}: " in line
    for w in words:
        assert w in line, line


# -- several contacts ---------------------------------------------------------------------------
CORNER = """
[[body]]
name = "block"
mesh = "block.msh"
levels = 3
material = { E = 100.0, nu = 0.3 }
[[body.dirichlet]]
tags = 3
value = [-0.01, -0.02]
[[obstacle]]
body = "block"
tags = 1
type = "plane"
point = [0.0, 0.0]
normal = [0.0, -1.0]
[[obstacle]]
body = "block"
tags = 4
type = "plane"
point = [0.0, 0.0]
normal = [-1.0, 0.0]
[friction]
law = "coulomb"
coefficient = 0.2
[output]
json = "corner.json"
"""


def test_a_block_pushed_into_a_corner_touches_floor_and_wall(tmp_path, capsys):
    shutil.copy(MODELS / "block_2d" / "block.msh", tmp_path)
    (tmp_path / "corner.toml").write_text(CORNER)
    rc, _, err = run_main(capsys, tmp_path / "corner.toml", "-q")
    assert rc == 0, err
    rep = json.loads((tmp_path / "corner.json").read_text())
    f = {k: np.asarray(v) for k, v in rep["contact_forces"].items()}
    assert set(f) == {"obstacle 0", "obstacle 1"}
    assert f["obstacle 0"][1] > 0 and f["obstacle 1"][0] > 0  # the floor pushes up, the wall right
    (reaction,) = rep["reactions"]
    balance = f["obstacle 0"] + f["obstacle 1"] + np.asarray(reaction["force"])
    assert np.abs(balance).max() <= 1e-10 * np.abs(f["obstacle 0"]).max()
    assert rep["check_max"] < 1e-8


def test_an_obstacle_beside_a_pair(tmp_path, capsys):
    """The two blocks, the lower one resting on a floor instead of clamped (held sideways at its left
    edge, vertically by a spring too weak to matter): the floor carries the upper block's push."""
    d = example("two_blocks", tmp_path)
    model = d / "blocks.toml"
    text = model.read_text().replace('tags = [1]\nvalue = [0.0, 0.0]', 'tags = [4]\nvalue = [0.0, "free"]')
    text = text.replace("body_force = [0.0, -1.0]\n", "[[body.spring]]\ntags = 2\nstiffness = [0.0, 1e-6]\n")
    text += ('[[obstacle]]\nbody = "lower"\ntags = [1]\ntype = "plane"\npoint = [0.0, 0.0]\n'
             'normal = [0.0, -1.0]\n')
    model.write_text(text)
    rc, out, err = run_main(capsys, model, "-q")
    assert rc == 0, err
    rep = json.loads((d / "out" / "blocks.json").read_text())
    f = {k: np.asarray(v) for k, v in rep["contact_forces"].items()}
    assert set(f) == {"pair 0", "obstacle 0"}
    push = -next(r["force"] for r in rep["reactions"] if r["body"] == "upper")[1]
    assert push > 0 and f["pair 0"][1] == pytest.approx(push, rel=1e-10)
    assert f["obstacle 0"][1] == pytest.approx(push, rel=1e-6)


def test_a_plane_given_the_wrong_way_round_is_refused(tmp_path, capsys):
    shutil.copy(MODELS / "block_2d" / "block.msh", tmp_path)
    (tmp_path / "corner.toml").write_text(CORNER.replace("normal = [0.0, -1.0]", "normal = [0.0, 1.0]"))
    rc, _, err = run_main(capsys, tmp_path / "corner.toml", "-q")
    assert rc == 2
    (line,) = err.strip().splitlines()
    assert "corner.toml: " in line and "normal" in line


def test_the_boundary_stress_plot_is_refused_for_a_3d_model(tmp_path, capsys):
    d = example("block_3d", tmp_path)
    model = d / "block.toml"
    model.write_text(model.read_text().replace('json = "out/block.json"', 'json = "out/block.json"\nplot = "b.png"'))
    rc, _, err = run_main(capsys, model, "-q")
    assert rc == 2
    (line,) = err.strip().splitlines()
    assert "block.toml: output.plot: " in line and "2D" in line
    assert not (d / "out").exists()  # nothing written before the model is read whole


# -- curved and meshed obstacles ----------------------------------------------------------------
def _swap_obstacle(text, new):
    start = text.index("[[obstacle]]")
    end = text.index("[friction]")
    return text[:start] + new + text[end:]


def _solve_text(tmp_path, capsys, name, text):
    (tmp_path / f"{name}.toml").write_text(text.replace('json = "out/block.json"', f'json = "{name}.json"')
                                            .replace('vtu = "out/block.vtu"', f'vtu = "{name}.vtu"'))
    rc, _, err = run_main(capsys, tmp_path / f"{name}.toml", "-q")
    assert rc == 0, err
    return json.loads((tmp_path / f"{name}.json").read_text()), meshio.read(tmp_path / f"{name}.vtu")


def test_load_steps_without_a_method_take_the_load_paths_default(tmp_path, capsys):
    """steps.count > 1 and no solver.method: the load path's default for the problem (that of a
    single solve): nmg on the block, the same steps as the file that names it; and nmg where a single
    solve would take tnnmg (nu = 0.49), which takes no slip origin."""
    d = example("block_2d", tmp_path)
    text = (d / "block.toml").read_text().replace("pvd = ", "# pvd = ").replace("plot = ", "# plot = ")
    assert 'method = "nmg"\n' in text
    named, _ = _solve_text(d, capsys, "named", text)
    plain, vtu_plain = _solve_text(d, capsys, "plain", text.replace('method = "nmg"\n', ""))
    assert plain["method"] == named["method"] == "nmg" and plain["converged"]
    assert plain["cycles_per_step"] == named["cycles_per_step"]
    stiff = text.replace('method = "nmg"\n', "").replace("nu = 0.3 }", "nu = 0.49 }")
    assert stiff.count("nu = 0.49") == 1
    rep, _ = _solve_text(d, capsys, "stiff", stiff)
    assert rep["method"] == "nmg" and rep["converged"] and len(rep["steps"]) == 5
    from contactmg.solve.options import resolve_options

    assert resolve_options(read_model(d / "stiff.toml").problem).method == "tnnmg"


def test_a_2d_cylinder_is_the_circle_and_a_flat_surface_mesh_the_plane(tmp_path, capsys):
    d = example("block_2d", tmp_path)
    text = (d / "block.toml").read_text().replace("pvd = ", "# pvd = ").replace("plot = ", "# plot = ")
    circle = '[[obstacle]]\nbody = "block"\ntags = [1]\ntype = "{}"\n{} = [0.5, -2.0]\nradius = 2.0\n'
    rep_c, vtu_c = _solve_text(d, capsys, "cyl", _swap_obstacle(text, circle.format("cylinder", "point")))
    rep_s, vtu_s = _solve_text(d, capsys, "sph", _swap_obstacle(text, circle.format("sphere", "center")))
    assert rep_c["cycles_per_step"] == rep_s["cycles_per_step"]
    assert np.array_equal(vtu_c.point_data["displacement"], vtu_s.point_data["displacement"])
    assert 0 < rep_c["contact_nodes"] < 33  # a circle touches part of the bottom edge (33 nodes)

    # the floor y = 0 as a surface mesh of two segments: the plane's answer
    meshio.write(d / "floor.msh", meshio.Mesh(np.array([[-1.0, 0.0, 0.0], [0.5, 0.0, 0.0], [2.0, 0.0, 0.0]]),
                                             [("line", np.array([[0, 1], [1, 2]]))]), file_format="gmsh22")
    floor = '[[obstacle]]\nbody = "block"\ntags = [1]\ntype = "mesh"\nmesh = "floor.msh"\n'
    rep_m, vtu_m = _solve_text(d, capsys, "floor", _swap_obstacle(text, floor))
    rep_p, vtu_p = _solve_text(d, capsys, "plane", text)
    assert rep_m["cycles_per_step"] == rep_p["cycles_per_step"]
    assert np.abs(vtu_m.point_data["displacement"] - vtu_p.point_data["displacement"]).max() <= 1e-12


def test_a_3d_block_on_a_rod_touches_along_it(tmp_path, capsys):
    """A rod along y under the block's centre line: contact along the whole width in y, a narrow band
    in x; symmetric about x = 0.5 (no net x force); the rod's force balances the top's reaction."""
    d = example("block_3d", tmp_path)
    rod = ('[[obstacle]]\nbody = "block"\ntags = [5]\ntype = "cylinder"\npoint = [0.5, 0.0, -2.0]\n'
           'axis = [0.0, 1.0, 0.0]\nradius = 2.0\n')
    rep, vtu = _solve_text(d, capsys, "rod", _swap_obstacle((d / "block.toml").read_text(), rod))
    contact = np.asarray(rep["contact_forces"]["obstacle"])
    (reaction,) = rep["reactions"]
    assert np.abs(np.asarray(reaction["force"]) + contact).max() <= 1e-10 * np.abs(contact).max()
    assert contact[2] > 0 and abs(contact[0]) <= 1e-8 * contact[2]
    touching = vtu.points[vtu.point_data["node_state"] > 0]
    assert touching[:, 1].min() == 0.0 and touching[:, 1].max() == 1.0
    assert np.abs(touching[:, 0] - 0.5).max() < 0.5


@pytest.mark.parametrize("new,key,words", [
    ('type = "cylinder"\npoint = [0.5, -2.0]\naxis = [0.0, 1.0]\nradius = 2.0\n', "obstacle[0].axis", ["circle"]),
    ('type = "mesh"\nmesh = "nofloor.msh"\n', "obstacle[0].mesh", ["no such file"]),
    ('type = "mesh"\nmesh = "block.msh"\nbody_side = 2\n', "obstacle[0].body_side", ["1 or -1"]),
])
def test_bad_curved_and_meshed_obstacles(tmp_path, capsys, new, key, words):
    text = BASE.replace('type = "plane"\npoint = [0.0, 0.0]\nnormal = [0.0, -1.0]\n', new)
    assert text != BASE
    shutil.copy(MODELS / "block_2d" / "block.msh", tmp_path)
    (tmp_path / "bad.toml").write_text(text)
    rc, _, err = run_main(capsys, tmp_path / "bad.toml", "-q")
    assert rc == 2
    (line,) = err.strip().splitlines()
    assert f"bad.toml: {key}: " in line
    for w in words:
        assert w in line, line


def test_fillet_cylinder_on_a_tilted_plane(tmp_path, capsys):
    """The gmsh-made 3D cylinder with a filleted edge: it balances, sticks and slides on the tilted
    plane within the friction cone, and its contact zone lies on the fillet's side that the plane's
    tilt lifts towards (x > 0)."""
    d = example("fillet_cylinder", tmp_path)
    rc, out, err = run_main(capsys, d / "cylinder.toml", "--json", "-", "-q")
    assert rc == 0, err
    rep = json.loads(out)
    assert rep["dim"] == 3 and rep["cell"] == "tetra" and rep["converged"] and rep["cycles"] <= 30
    contact = np.asarray(rep["contact_forces"]["obstacle"])
    (reaction,) = rep["reactions"]
    assert np.abs(np.asarray(reaction["force"]) + contact).max() <= 1e-10 * np.abs(contact).max()
    # the force of the plane lies in its friction cone: tangential <= 0.3 x normal
    n = np.array([0.1736482, 0.0, -0.9848078])
    normal = -contact @ n
    assert normal > 0 and np.linalg.norm(contact + normal * n) <= 0.3 * normal * (1 + 1e-9)
    assert rep["check_max"] < 1e-8 and rep["stick_nodes"] > 0
    vtu = meshio.read(d / "out" / "cylinder.vtu")
    assert np.all(vtu.points[vtu.point_data["node_state"] > 0][:, 0] > 0)


@pytest.mark.parametrize("kind", ["coarsening", "aggregation"])
def test_a_fine_mesh_alone_from_the_model_file(tmp_path, capsys, kind):
    """The block's mesh refined three times, written out and given as the fine mesh alone: the coarse
    levels are made from it, and the answer is the refined hierarchy's on the same mesh."""
    from contactmg.mesh.io import write_mesh

    d = example("block_2d", tmp_path)
    write_mesh(d / "fine.msh", MeshHierarchy.build(read_mesh(d / "block.msh"), 4).finest)
    text = (d / "block.toml").read_text()
    assert "levels = 4" in text and 'mesh = "block.msh"' in text
    (d / "fine.toml").write_text(text.replace('mesh = "block.msh"', 'mesh = "fine.msh"')
                                 .replace("levels = 4", f'levels = 1\nhierarchy = "{kind}"'))
    rc, out, err = run_main(capsys, d / "fine.toml", "--json", "-", "-q")
    assert rc == 0, err
    rep = json.loads(out)
    rc, ref_out, err = run_main(capsys, d / "block.toml", "--json", "-", "-q")
    ref = json.loads(ref_out)
    assert rep["bodies"][0]["hierarchy"] == kind and ref["bodies"][0]["hierarchy"] == "refine"
    assert rep["multigrid_levels"] >= 2 and rep["nodes"] == ref["nodes"]
    assert rep["converged"] and max(rep["cycles_per_step"]) <= 30
    # the same mesh, the same law of statics, the same answer
    f, g = np.asarray(rep["contact_forces"]["obstacle"]), np.asarray(ref["contact_forces"]["obstacle"])
    assert np.abs(f - g).max() <= 1e-6 * np.abs(g).max()


HALF_DISK = """
[[body]]
name = "disk"
mesh = "disk.msh"
levels = 3
material = { E = 2000.0, nu = 0.28 }
[[body.dirichlet]]
tags = [2]
value = [0.0, -0.01]
[[body.surface]]
tags = [1]
type = "sphere"
center = [0.0, 0.4]
radius = 0.4

[[obstacle]]
body = "disk"
tags = [1]
type = "plane"
point = [0.0, 0.0]
normal = [0.0, -1.0]
"""


def test_a_body_surface_makes_the_refinement_follow_it(tmp_path):
    """[[body.surface]]: the half disk's arc refined onto its circle (its new nodes on radius 0.4 to
    round-off), where without the key it stays on the coarse chords; a bad surface is named."""
    from contactmg.mesh.generators import polar_half_disk
    from contactmg.mesh.io import write_mesh

    write_mesh(tmp_path / "disk.msh", polar_half_disk())
    (tmp_path / "disk.toml").write_text(HALF_DISK)

    def arc_radii(model):
        m = model.problem.mesh
        nodes = np.unique(m.facets[m.facet_tags == 1])
        return np.linalg.norm(m.points[nodes] - [0.0, 0.4], axis=1)

    r = arc_radii(read_model(tmp_path / "disk.toml"))
    assert np.abs(r - 0.4).max() < 1e-12
    (tmp_path / "faceted.toml").write_text(HALF_DISK.split("[[body.surface]]")[0] + HALF_DISK.split("radius = 0.4\n")[1])
    with pytest.warns(UserWarning, match="approximate a curved surface"):
        faceted = arc_radii(read_model(tmp_path / "faceted.toml"))
    assert np.abs(faceted - 0.4).max() > 1e-4
    (tmp_path / "bad.toml").write_text(HALF_DISK.replace('type = "sphere"', 'type = "cylinder"'))
    with pytest.raises(ModelError, match=r"body\[0\].surface\[0\].type: a 2D section of a cylinder is a circle"):
        read_model(tmp_path / "bad.toml")


def test_a_body_geometry_makes_the_refinement_follow_the_cad(tmp_path):
    """geometry = the CAD file a .msh was made from: every level's new nodes on the rounded
    rectangle's quarter circles lie on them to round-off, where the faceted model's stay on the
    coarse chords; the model solves. A geometry beside a [[body.surface]], or beside a mesh gmsh
    did not write, is named."""
    gmsh = pytest.importorskip("gmsh")
    brep, msh = tmp_path / "plate.brep", tmp_path / "plate.msh"
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.occ.addRectangle(0, 0, 0, 2, 1, roundedRadius=0.3)
        gmsh.model.occ.synchronize()
        gmsh.write(str(brep))
        curves = gmsh.model.getEntities(1)
        bottom = [t for _, t in curves if gmsh.model.occ.getCenterOfMass(1, t)[1] < 0.2]
        top = [t for _, t in curves if gmsh.model.occ.getCenterOfMass(1, t)[1] > 0.8]
        gmsh.model.addPhysicalGroup(1, bottom, 1)
        gmsh.model.addPhysicalGroup(1, top, 2)
        gmsh.model.addPhysicalGroup(1, [t for _, t in curves if t not in bottom + top], 3)
        gmsh.model.addPhysicalGroup(2, [1], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(msh))
    finally:
        gmsh.finalize()
    model = """
[[body]]
name = "plate"
mesh = "plate.msh"
levels = 3
material = { E = 1000.0, nu = 0.3 }
[[body.dirichlet]]
tags = [2]
value = [0.0, -0.01]

[[obstacle]]
body = "plate"
tags = [1]
type = "plane"
point = [0.0, 0.0]
normal = [0.0, -1.0]
"""
    (tmp_path / "cad.toml").write_text(model.replace('mesh = "plate.msh"', 'mesh = "plate.msh"\ngeometry = "plate.brep"'))
    (tmp_path / "faceted.toml").write_text(model)

    def corner_radii(m):
        # the rounded corners' new boundary nodes against their circles (centres 0.3 in from the corners)
        x = m.points[np.unique(m.facets)]
        centres = np.array([[0.3, 0.3], [1.7, 0.3], [1.7, 0.7], [0.3, 0.7]])
        out = []
        for c, (sx, sy) in zip(centres, [(-1, -1), (1, -1), (1, 1), (-1, 1)]):
            sel = (sx * (x[:, 0] - c[0]) > 1e-9) & (sy * (x[:, 1] - c[1]) > 1e-9)
            out.append(np.abs(np.linalg.norm(x[sel] - c, axis=1) - 0.3))
        return np.concatenate(out)

    cad = read_model(tmp_path / "cad.toml")
    assert not gmsh.isInitialized()  # the CAD model is closed once the problem is built
    assert len(corner_radii(cad.problem.mesh)) > 20 and corner_radii(cad.problem.mesh).max() < 1e-9
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        faceted = read_model(tmp_path / "faceted.toml")
    assert corner_radii(faceted.problem.mesh).max() > 1e-4
    res = cad.problem.solve()
    assert res.converged and res.contact_forces()["obstacle"][1] > 0
    with_cad = model.replace('mesh = "plate.msh"', 'mesh = "plate.msh"\ngeometry = "plate.brep"')
    surface = '[[body.surface]]\ntags = [3]\ntype = "sphere"\ncenter = [0.3, 0.3]\nradius = 0.3\n'
    both = with_cad.replace("\n[[obstacle]]", surface + "\n[[obstacle]]", 1)
    (tmp_path / "both.toml").write_text(both)
    with pytest.raises(ModelError, match=r"body\[0\].surface: give the curved surfaces by the geometry or by"):
        read_model(tmp_path / "both.toml")
    from contactmg.mesh.io import write_mesh
    write_mesh(tmp_path / "plate.vtu", faceted.problem.hierarchy.meshes[0])
    (tmp_path / "vtu.toml").write_text(model.replace('mesh = "plate.msh"', 'mesh = "plate.vtu"\ngeometry = "plate.brep"'))
    with pytest.raises(ModelError, match=r"body\[0\].geometry: goes with a gmsh .msh mesh"):
        read_model(tmp_path / "vtu.toml")
