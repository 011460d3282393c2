"""Distributed memory: the same meshes, vectors and sums on any number of MPI ranks.

comm (the communicator, or a serial stand-in without MPI; errors that end every rank), partition
(the coarse cells among the ranks), hierarchy (each rank's part of every level, numbered as the
serial hierarchy), exchange (ghost values from their owners; sums independent of the rank count),
transfer (prolongation by the owners' rows), colouring (node colours independent of the partition),
output (results as a .pvtu of one piece per rank, or one gathered .vtu), problem (a contact problem
on the ranks and its solve by truncated monotone multigrid; its parts in fine_level, operators and
cycle), examples (the Hertz half disk and sphere on the ranks). mpi4py and pymetis are
imported only where they are used: the serial package needs neither."""
from .comm import DistributedError, SerialComm, abort_on_uncaught, collective, get_comm, raise_together, rank0_print
from .colouring import colour_level
from .exchange import Halo, exact_dot, exact_norm, exact_sum
from .hierarchy import DistributedHierarchy, LocalLevel, LocalTransfer
from .output import read_pvtu, write_gathered_vtu, write_pvtu
from .problem import DistributedProblem, DistributedResult, DistributedSolver
from .partition import coordinate_bisection, partition, partition_cells
from .transfer import prolong

__all__ = ["DistributedError", "SerialComm", "abort_on_uncaught", "collective", "get_comm", "raise_together",
           "rank0_print", "colour_level", "Halo", "exact_dot", "exact_norm", "exact_sum", "DistributedHierarchy",
           "LocalLevel", "LocalTransfer", "coordinate_bisection", "partition", "partition_cells", "prolong",
           "read_pvtu", "write_gathered_vtu", "write_pvtu", "DistributedProblem", "DistributedSolver",
           "DistributedResult"]


def __getattr__(name):
    if name == "DistributedOptions":  # deprecated: SolverOptions
        from . import problem

        return problem.__getattr__(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
