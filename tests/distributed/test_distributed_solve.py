"""The distributed solve (truncated monotone multigrid, frictionless and Tresca) on 1-4 ranks: the
same displacement bit for bit and the same correction norms on every rank count and partition; the
serial solver's answer within the stop; monotone energy, feasibility; what is not distributed yet
refused on every rank."""
import numpy as np
import pytest

import contactmg
from contactmg.distributed import SerialComm
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.model.friction import Tresca
from contactmg.model.problem import Problem
from contactmg.solve.options import SolverOptions

from mpi_launch import missing, run_ranks
from solve_checks import CASES, OPTIONS, solve_case

ONE_RANK = {}


def one_rank(name):
    """The case solved in this process (SerialComm: no MPI)."""
    if name not in ONE_RANK:
        ONE_RANK[name] = solve_case(name, SerialComm())
    return ONE_RANK[name]


def serial(name):
    example, levels, cell, bound, _ = CASES[name]
    make = hertz_problem if example.__name__ == "hertz" else sphere_problem
    p = make(cell, levels, 0.0)
    if bound > 0:
        p = Problem(p.bodies[0], obstacle=p.obstacle, friction=Tresca(bound))
    return contactmg.Solver(p, OPTIONS.replace(method="nmg")).solve()


@pytest.mark.parametrize("name", sorted(CASES))
def test_one_rank_agrees_with_the_serial_solver(name):
    got, ref = one_rank(name), serial(name)
    assert got["converged"]
    # the same cycle, swept in another colour order (hashed colours): the same solution to the stop
    # (1e-11 in the energy norm), within one cycle of the serial count
    scale = np.abs(ref.displacement).max()
    assert np.abs(got["u"] - ref.displacement).max() <= 1e-9 * scale
    assert abs(got["cycles"] - ref.cycles) <= 1
    # monotone: the energy never rises (round-off of the exact sums aside)
    e = got["energy"]
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())
    assert got["correction"][-1] <= OPTIONS.tol


def test_contact_zone_and_feasibility():
    got = one_rank("hertz-triangle-frictionless")
    u = got["u"]
    # the plane y = 0 below the disk (centre y = 0.4, radius 0.4): no point of the arc goes below it
    from contactmg.mesh.generators import hertz_half_disk
    from contactmg.mesh.hierarchy import MeshHierarchy
    from contactmg.mesh.generators import hertz_projector
    m = MeshHierarchy.build(hertz_half_disk("triangle"), 4, projector=hertz_projector()).finest
    y = m.points[:, 1] + u[:, 1]
    assert y.min() >= -1e-12
    assert np.count_nonzero(np.abs(y) <= 1e-12) >= 3  # a contact zone of several nodes


pytestmark = [pytest.mark.mpi]


@pytest.mark.skipif(bool(missing()), reason=missing() or "MPI available")
@pytest.mark.parametrize("ranks", [2, 3, 4])
def test_every_rank_count_gives_the_one_rank_bits(ranks, tmp_path):
    r = run_ranks(ranks, "solve", str(tmp_path), timeout=180)
    assert r.returncode == 0, f"mpirun -n {ranks} failed (exit {r.returncode}):\n{r.stdout}\n{r.stderr}"
    for name in CASES:
        assert f"OK solve {name}" in r.stdout.splitlines(), r.stdout
        got, ref = np.load(tmp_path / f"{name}.npz"), one_rank(name)
        assert int(got["cycles"]) == ref["cycles"]
        assert np.array_equal(got["correction"], ref["correction"]), name
        assert np.array_equal(got["energy"], ref["energy"]), name
        assert np.array_equal(got["u"], ref["u"]), f"{name}: largest difference {np.abs(got['u'] - ref['u']).max()}"


@pytest.mark.skipif(bool(missing()), reason=missing() or "MPI available")
def test_coulomb_is_refused_on_every_rank():
    r = run_ranks(2, "coulomb", timeout=60)
    assert r.returncode != 0
    for rank in range(2):
        assert f"rank {rank} stops: rank 0: ValueError: Coulomb friction is not distributed yet" in r.stdout, \
            r.stdout + r.stderr


@pytest.mark.skipif(bool(missing()), reason=missing() or "MPI available")
def test_commands_on_two_ranks_report_the_serial_keys(tmp_path):
    import json
    import meshio
    from contactmg.cli.main import main as cli_main
    r = run_ranks(2, "cli", str(tmp_path), timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    assert "EXIT hertz 0" in lines and "EXIT sphere 0" in lines, r.stdout
    # Coulomb is not distributed yet: exit status 2 and one line from rank 0 alone
    assert "EXIT coulomb 2" in lines, r.stdout
    errors = [ln for ln in r.stderr.splitlines() if ln.startswith("contactmg hertz: error:")]
    assert errors == ["contactmg hertz: error: Coulomb friction is not distributed yet: run with --friction 0 "
                      "(frictionless) or on one rank"], r.stderr
    for name, argv in (("hertz", ["hertz", "--levels", "4", "--friction", "0"]),
                       ("sphere", ["sphere", "--levels", "2", "--cell", "tetra", "--friction", "0"])):
        serial_json = tmp_path / f"{name}-serial.json"
        assert cli_main(argv + ["--json", str(serial_json), "-q"]) == 0
        serial, dist = json.loads(serial_json.read_text()), json.loads((tmp_path / f"{name}.json").read_text())
        assert set(serial) <= set(dist), set(serial) - set(dist)
        assert dist["ranks"] == 2 and serial["ranks"] == 1
        assert len(dist["rank_solve_seconds"]) == 2 and len(dist["rank_memory_bytes"]) == 2
        assert dist["converged"] and abs(dist["cycles"] - serial["cycles"]) <= 1
        assert dist["dofs"] == serial["dofs"] and dist["contact_nodes"] == serial["contact_nodes"]
        assert np.allclose(dist["reaction"], serial["reaction"], rtol=1e-9, atol=1e-9 * abs(serial["reaction"][-1]))
        assert dist["contact_halfwidth"] == pytest.approx(serial["contact_halfwidth"], rel=1e-12)
        assert dist["max_normal_stress"] == pytest.approx(serial["max_normal_stress"], rel=1e-8)
        if name == "sphere":
            assert dist["central_pressure"] == pytest.approx(serial["central_pressure"], rel=1e-8)
    # the gathered .vtu: the serial mesh's points, the displacement in global components
    m = meshio.read(tmp_path / "hertz.vtu")
    assert m.point_data["displacement"].shape[0] == json.loads((tmp_path / "hertz.json").read_text())["nodes"]
    assert m.point_data["displacement"][:, 1].min() < 0
