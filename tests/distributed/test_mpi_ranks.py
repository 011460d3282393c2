"""The distributed pieces on 1-4 ranks (oversubscribed on a small machine), each rank count in one
mpirun launch of mpi_checks.py (mpi_launch.SUITE, shared with test_distributed_solve.py): hierarchy equal to the serial one, halo exchange, exact sums,
partition-independent colouring; distributed output (.pvtu pieces and the gathered .vtu) equal to
the serial mesh; and failures on one rank that end every rank."""
import pytest

from mpi_launch import missing, require_part, run_ranks
from output_checks import MESHES as OUTPUT_MESHES, check_files

pytestmark = [pytest.mark.mpi, pytest.mark.skipif(bool(missing()), reason=missing() or "MPI available")]

CELLS = ("triangle", "quad", "tetra", "hexahedron")


@pytest.mark.parametrize("ranks", [1, 2, 3, 4])
def test_distributed_checks_on_ranks(ranks):
    r, _ = require_part(ranks, "all")
    lines = set(r.stdout.splitlines())
    checks = ("hierarchy", "halo", "prolongation", "colouring")
    expected = {f"OK {check} {cell}" for check in checks for cell in CELLS}
    expected |= {f"OK {check} {variant}" for check in checks
                 for variant in ("triangle scattered", "tetra scattered", "quad bisection")}
    expected |= {"OK hierarchy ball", "OK halo ball", "OK sums", "ALL OK"}
    assert expected <= lines, f"missing: {sorted(expected - lines)}\n{r.stdout}"
    # rank 0 alone reports
    assert r.stdout.count("ALL OK") == 1


@pytest.mark.parametrize("ranks", [2, 3])
def test_pvtu_and_gathered_vtu_on_ranks_equal_the_serial_mesh(ranks):
    r, folder = require_part(ranks, "output")
    for name in OUTPUT_MESHES:
        assert f"OK output {name}" in r.stdout.splitlines(), r.stdout
        check_files(folder, name, ranks)


def test_bad_input_on_one_rank_ends_every_rank_with_its_message():
    ranks = 3
    r = run_ranks(ranks, "error", timeout=30)
    assert r.returncode != 0
    for rank in range(ranks):
        assert f"rank {rank} stops: rank 1: ValueError: bad input on this rank" in r.stdout, r.stdout + r.stderr


def test_unguarded_failure_ends_every_rank():
    # the other ranks wait in a barrier that rank 1 never reaches: MPI_Abort must end them
    r = run_ranks(3, "uncaught", timeout=30)
    assert r.returncode != 0
    assert "rank 1: Traceback" in r.stderr and "an unguarded failure on one rank" in r.stderr, r.stderr
