"""The distributed solve (truncated monotone multigrid; frictionless, Tresca, Coulomb) on 1-4 ranks: the
same displacement bit for bit and the same correction norms on every rank count and partition; the
serial solver's answer within the stop; monotone energy, feasibility; what is not distributed yet
refused on every rank."""
import numpy as np
import pytest

import contactmg
from contactmg.distributed import SerialComm
from contactmg.examples.hertz import hertz_problem
from contactmg.examples.sphere import sphere_problem
from contactmg.model.friction import Coulomb, Tresca
from contactmg.model.problem import Problem
from contactmg.solve.options import SolverOptions

from mpi_launch import SUITE, missing, require_part
from solve_checks import CASES, OPTIONS, RANKS_ONLY, solve_case

ONE_RANK = {}


def one_rank(name):
    """The case solved in this process (SerialComm: no MPI)."""
    if name not in ONE_RANK:
        ONE_RANK[name] = solve_case(name, SerialComm())
    return ONE_RANK[name]


def serial(name):
    example, levels, cell, friction, _, _ = CASES[name]
    make = hertz_problem if example.__name__ == "hertz" else sphere_problem
    p = make(cell, levels, 0.0)
    if not isinstance(friction, type(p.friction)) or isinstance(friction, (Tresca, Coulomb)):
        p = Problem(p.bodies[0], obstacle=p.obstacle, friction=friction)
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
    assert got["correction"][-1] <= OPTIONS.tol
    assert got["final_check"].max() <= 1e-6  # converged only after the final check
    if isinstance(CASES[name][3], Coulomb):  # sliding nodes: the Anderson-mixed cycles are exercised
        assert got["slip_nodes"] > 0 and got["slip_nodes"] == ref.counts()["slip_nodes"]
    else:  # a minimization: monotone, the energy never rises (round-off of the exact sums aside)
        e = got["energy"]
        assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())

def test_contact_zone_and_feasibility():
    got = one_rank("hertz-triangle-coulomb")
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
@pytest.mark.parametrize("ranks", [r for r in sorted(SUITE) if "solve" in SUITE[r]])
def test_every_rank_count_gives_the_one_rank_bits(ranks):
    r, folder = require_part(ranks, "solve")
    for name in [*CASES, *RANKS_ONLY]:
        assert f"OK solve {name}" in r.stdout.splitlines(), r.stdout
        got, ref = np.load(f"{folder}/{name}.npz"), one_rank(name)
        assert int(got["cycles"]) == ref["cycles"]
        assert np.array_equal(got["correction"], ref["correction"]), name
        assert np.array_equal(got["energy"], ref["energy"]), name
        assert np.array_equal(got["u"], ref["u"]), f"{name}: largest difference {np.abs(got['u'] - ref['u']).max()}"
        # the final check's figures: maxima and exact sums over the ranks
        assert np.array_equal(got["final_check"], ref["final_check"]), name


@pytest.mark.skipif(bool(missing()), reason=missing() or "MPI available")
def test_commands_on_two_ranks_report_the_serial_keys():
    import json
    import meshio
    from contactmg.cli.main import main as cli_main
    r, folder = require_part(2, "cli")
    lines = r.stdout.splitlines()
    assert "EXIT hertz 0" in lines and "EXIT sphere 0" in lines, r.stdout
    # an option not distributed yet: exit status 2 and one line from rank 0 alone
    assert "EXIT adaptive 2" in lines, r.stdout
    errors = [ln for ln in r.stderr.splitlines() if ln.startswith("contactmg hertz: error:")]
    assert errors == ["contactmg hertz: error: --hierarchy adaptive is not distributed yet: run on one rank"], r.stderr
    # a command not distributed yet: the same, rather than every rank solving it alone
    assert "EXIT cork 2" in lines, r.stdout
    errors = [ln for ln in r.stderr.splitlines() if ln.startswith("contactmg cork:")]
    assert errors == ["contactmg cork: error: cork is not distributed yet (on several ranks only hertz and sphere run): "
                      "run it on one rank, without mpirun"], r.stderr
    for name, argv in (("hertz", ["hertz", "--levels", "4", "--friction", "0.4"]),
                       ("sphere", ["sphere", "--levels", "2", "--cell", "tetra", "--friction", "0"])):
        serial_json = f"{folder}/{name}-serial.json"
        assert cli_main(argv + ["--json", serial_json, "-q"]) == 0
        with open(serial_json) as fh, open(f"{folder}/{name}.json") as gh:
            serial, dist = json.load(fh), json.load(gh)
        assert set(serial) <= set(dist), set(serial) - set(dist)
        assert dist["ranks"] == 2 and serial["ranks"] == 1
        assert len(dist["rank_solve_seconds"]) == 2 and len(dist["rank_memory_bytes"]) == 2
        assert dist["converged"] and abs(dist["cycles"] - serial["cycles"]) <= 1
        assert dist["dofs"] == serial["dofs"] and dist["contact_nodes"] == serial["contact_nodes"]
        assert (dist["stick_nodes"], dist["slip_nodes"]) == (serial["stick_nodes"], serial["slip_nodes"])
        assert np.allclose(dist["reaction"], serial["reaction"], rtol=1e-9, atol=1e-9 * abs(serial["reaction"][-1]))
        assert dist["contact_halfwidth"] == pytest.approx(serial["contact_halfwidth"], rel=1e-12)
        assert dist["stick_halfwidth"] == pytest.approx(serial["stick_halfwidth"], rel=1e-12)
        assert dist["max_normal_stress"] == pytest.approx(serial["max_normal_stress"], rel=1e-8)
        if name == "sphere":
            assert dist["central_pressure"] == pytest.approx(serial["central_pressure"], rel=1e-8)
    assert json.load(open(f"{folder}/hertz.json"))["slip_nodes"] > 0  # Coulomb with sliding nodes
    # in the distributed colours (--ordering hashed) the one-process command takes the same cycles
    hashed = f"{folder}/hertz-hashed.json"
    assert cli_main(["hertz", "--levels", "4", "--friction", "0.4", "--ordering", "hashed", "--json", hashed, "-q"]) == 0
    assert json.load(open(hashed))["cycles"] == json.load(open(f"{folder}/hertz.json"))["cycles"]
    # the gathered .vtu: the serial mesh's points, the displacement in global components
    m = meshio.read(f"{folder}/hertz.vtu")
    assert m.point_data["displacement"].shape[0] == json.loads(open(f"{folder}/hertz.json").read())["nodes"]
    assert m.point_data["displacement"][:, 1].min() < 0


def test_threads_per_rank_give_the_bits_of_one_thread():
    # level 7: colours of some 10,000 fine rows and 2,600 rows of the top coarse level, past the size
    # where a colour's rows go to the threads; the first five cycles
    from contactmg.examples.distributed import hertz
    got = {}
    for threads in (1, 2):
        r = hertz(7, "triangle", Coulomb(0.4), SerialComm()).solve(OPTIONS.replace(threads=threads, max_cycles=5))
        got[threads] = (r.u, [h["correction_norm"] for h in r.history])
    assert len(got[1][1]) == 5 and got[1][1] == got[2][1]
    assert np.array_equal(got[1][0], got[2][0])


def test_whole_levels_threshold_is_checked():
    from contactmg.distributed import DistributedError
    from contactmg.examples.distributed import hertz
    problem = hertz(2, "triangle", Coulomb(0.4), SerialComm())
    for bad in (-1, 2.5, True):
        with pytest.raises(DistributedError, match="whole_below must be an integer >= 0 or None"):
            problem.solve(OPTIONS, whole_below=bad)


def test_an_empty_contact_boundary_is_refused_with_the_serial_message():
    from contactmg.distributed import DistributedError, DistributedHierarchy, DistributedProblem
    from contactmg.examples import hertz as _hertz
    from contactmg.mesh.generators import HERTZ_ARC, HERTZ_TOP, hertz_half_disk
    from contactmg.model.material import Material
    from contactmg.model.obstacle import PlaneObstacle
    from contactmg.model.problem import Dirichlet
    h = DistributedHierarchy.build(hertz_half_disk("triangle"), 2, SerialComm())
    plane = PlaneObstacle((0.0, 0.0), (0.0, -1.0))
    # the contact tags are the Dirichlet tags: every contact node is fixed
    with pytest.raises(DistributedError, match="the contact boundary is empty: every node of the facets tagged"):
        DistributedProblem(h, Material(_hertz.E, _hertz.NU), [Dirichlet([HERTZ_TOP, HERTZ_ARC], (0.0, -0.1))],
                           contact_tags=[HERTZ_ARC], obstacle=plane)
    with pytest.raises(DistributedError, match="no boundary facet carries the contact tags"):
        DistributedProblem(h, Material(_hertz.E, _hertz.NU), [Dirichlet([HERTZ_TOP], (0.0, -0.1))],
                           contact_tags=[987], obstacle=plane)


@pytest.mark.parametrize("name", ["hertz-triangle-coulomb", "sphere-hexahedron-tresca"])
def test_the_final_check_on_the_ranks_is_the_serial_check(name):
    """The distributed final check (the ranks' owned rows, reduced) gives the serial check's figures
    (results.checks.contact_conditions of the serial problem) for an iterate that violates every
    condition: a converged solve's displacement with its contact nodes pushed into the obstacle and
    the others moved off balance."""
    from types import SimpleNamespace

    from contactmg.distributed.final_check import final_check
    from contactmg.results.checks import contact_conditions

    example, levels, cell, friction, _, _ = CASES[name]
    problem = example(levels, cell, friction, SerialComm())
    result = problem.solve(OPTIONS)
    fine, lev = problem.fine, problem.hierarchy.levels[-1]
    # the solve's iterate in the cycle's storage (frame components at the contact nodes), perturbed
    u = result.u.copy()
    u[fine.contact_nodes] = np.einsum("cab,ca->cb", fine.frames, u[fine.contact_nodes])  # canonical -> frames
    rng = np.random.default_rng(1)
    scale = np.abs(u).max()
    free = ~fine.fixed
    free[fine.contact_nodes] = False
    u[free] += 1e-3 * scale * rng.normal(size=np.count_nonzero(free))
    u[fine.contact_nodes, 0] += 1e-3 * scale  # into the obstacle
    got = final_check(fine, u, problem.comm)
    # the same displacement in the serial problem's numbering and result
    ref_solver = contactmg.Solver(serial_problem_of(name), OPTIONS.replace(method="nmg"))
    ref = ref_solver.solve()
    w = np.empty_like(u)
    w[lev.gid] = fine.core.to_canonical(u)
    want = contact_conditions(ref_solver.problem, SimpleNamespace(displacement=w, contact_frames=ref.contact_frames,
                                                                  frame_fixed=ref.frame_fixed))
    assert want["penetration"] > 1e-6 and want["interior"] > 1e-6 and want["balance"] > 1e-9
    for k in want:
        assert got[k] == pytest.approx(want[k], rel=1e-8, abs=1e-14), k


def serial_problem_of(name):
    example, levels, cell, friction, _, _ = CASES[name]
    make = hertz_problem if example.__name__ == "hertz" else sphere_problem
    p = make(cell, levels, 0.0)
    return Problem(p.bodies[0], obstacle=p.obstacle, friction=friction)


def test_options_not_distributed_are_refused_and_the_old_options_class_warns():
    """A distributed solve takes SolverOptions; what its cycle does not have is refused with one line
    (not ignored), and the former DistributedOptions name warns and is SolverOptions."""
    from contactmg.distributed.problem import resolve
    import contactmg.distributed as dist

    for given, words in ((SolverOptions(method="tnnmg"), "method 'tnnmg' is not distributed yet"),
                         (SolverOptions(start="nested"), "nested start is not distributed yet"),
                         (SolverOptions(lines=True, method="tnnmg"), "not distributed yet")):
        with pytest.raises(ValueError, match=words):
            resolve(given, "triangle")
    got = resolve(SolverOptions(omega=1.2), "quad")
    assert (got.method, got.omega, got.omega_post, got.threads) == ("nmg", 1.2, 1.2, 1)
    with pytest.warns(DeprecationWarning, match="SolverOptions"):
        assert dist.DistributedOptions is SolverOptions


def test_the_solver_of_a_distributed_problem_is_its_solve():
    """contactmg.Solver takes a DistributedProblem as it takes a Problem: the same result as the
    problem's own solve, bit for bit; per-solve changes as a dict; what is not distributed refused
    when the solver is made."""
    from contactmg.examples.distributed import hertz
    from contactmg.distributed import DistributedSolver

    p = hertz(3, "triangle", Coulomb(0.4), SerialComm())
    solver = contactmg.Solver(p, {"cycle": "V"})
    assert isinstance(solver, DistributedSolver) and solver.options.cycle == "V"
    got, ref = solver.solve(), p.solve(SolverOptions(cycle="V"))
    assert got.converged and got.cycles == ref.cycles and np.array_equal(got.u, ref.u)
    short = solver.solve({"max_cycles": 2})
    assert not short.converged and short.cycles == 2 and short.status == "no convergence in 2 cycles"
    from contactmg.distributed import DistributedError

    with pytest.raises(DistributedError, match="rank 0: ValueError: method 'tnnmg' is not distributed yet"):
        contactmg.Solver(p, {"method": "tnnmg"})
