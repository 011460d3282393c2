"""The communicator: mpi4py's when the program runs on several ranks, a serial stand-in with the same
small interface otherwise, so that serial code needs neither MPI nor mpi4py. Also printing by rank 0
and errors that end every rank instead of leaving the others waiting in a collective.

mpi4py is imported inside functions only: `import contactmg` works without it."""
from __future__ import annotations

import contextlib
import os
import sys
import traceback
from typing import Any, Iterator, List, Optional


class SerialComm:
    """One rank: the lower-case (Python object) collectives of mpi4py that this package uses, each
    the identity or a list of one. Reductions of one value are that value, whatever the operation."""

    rank = 0
    size = 1

    def Get_rank(self) -> int:
        """0, as mpi4py's Get_rank."""
        return 0

    def Get_size(self) -> int:
        """1, as mpi4py's Get_size."""
        return 1

    def barrier(self) -> None:
        """Nothing to wait for."""

    def bcast(self, obj: Any, root: int = 0) -> Any:
        """`obj` itself."""
        return obj

    def allreduce(self, obj: Any, op: Any = None) -> Any:
        """`obj` itself: the reduction of one value."""
        return obj

    def allgather(self, obj: Any) -> List[Any]:
        """[obj]."""
        return [obj]

    def gather(self, obj: Any, root: int = 0) -> List[Any]:
        """[obj] (the root is this rank)."""
        return [obj]

    def alltoall(self, objs: List[Any]) -> List[Any]:
        """The list of one item given, which this rank sends to itself."""
        if len(objs) != 1:
            raise ValueError(f"alltoall on one rank takes a list of one item, got {len(objs)}")
        return list(objs)

    def Abort(self, errorcode: int = 1) -> None:
        """End the process with `errorcode`."""
        raise SystemExit(errorcode)

    def __repr__(self) -> str:
        return "SerialComm()"


def mpi_module():
    """mpi4py.MPI, or None where mpi4py or the MPI library it loads is missing."""
    try:
        from mpi4py import MPI
    except (ImportError, RuntimeError, OSError):  # mpi4py finds no MPI library: RuntimeError or OSError
        return None
    return MPI


# Variables that MPI launchers set in every rank's environment: Open MPI's mpirun, PMIx launchers
# (Open MPI 5, Slurm), MPICH's and Intel MPI's Hydra.
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK", "MPI_LOCALNRANKS")


def launched_by_mpi() -> bool:
    """Did an MPI launcher start this process (or has the program imported mpi4py.MPI itself)?"""
    return "mpi4py.MPI" in sys.modules or any(v in os.environ for v in LAUNCHER_VARIABLES)


def get_comm(comm: Optional[Any] = None):
    """`comm` if given; else mpi4py's COMM_WORLD when the program runs on more than one rank; else a
    SerialComm. On several ranks an exception that nothing catches then ends every rank
    (abort_on_uncaught), unless the program has set its own sys.excepthook. One process needs no MPI
    at all: a process that no launcher started (none of LAUNCHER_VARIABLES set) and that has not
    imported mpi4py.MPI itself does not initialize MPI. Under a launcher that sets none of them,
    import mpi4py.MPI first or pass comm=MPI.COMM_WORLD."""
    if comm is not None:
        if not (hasattr(comm, "rank") and hasattr(comm, "size") and hasattr(comm, "allgather")):
            raise TypeError(f"comm must be an mpi4py communicator or a SerialComm, got {type(comm).__name__}")
        return comm
    if not launched_by_mpi():
        return SerialComm()
    MPI = mpi_module()
    if MPI is not None and MPI.COMM_WORLD.size > 1:
        if sys.excepthook is sys.__excepthook__:  # unless the program has its own hook
            abort_on_uncaught(MPI.COMM_WORLD)
        return MPI.COMM_WORLD
    return SerialComm()


def is_serial(comm) -> bool:
    """One rank: no exchange and no reduction is needed."""
    return comm.size == 1


def op(comm, name: str):
    """The reduction `name` ("SUM", "MAX", "MIN") for comm's allreduce (ignored by a SerialComm; an
    mpi4py communicator of one rank still needs mpi4py's operation)."""
    if isinstance(comm, SerialComm):
        return name
    return getattr(mpi_module(), name)


def rank0_print(*args, comm=None, **kwargs) -> None:
    """print() on rank 0 only: progress and results appear once, not once per rank."""
    comm = get_comm(comm)
    if comm.rank == 0:
        kwargs.setdefault("flush", True)
        print(*args, **kwargs)


class DistributedError(RuntimeError):
    """An exception raised on some rank, raised again on every rank with that rank's message."""

    def __init__(self, rank: int, message: str):
        super().__init__(f"rank {rank}: {message}")
        self.rank = rank
        self.message = message


@contextlib.contextmanager
def raise_together(comm=None) -> Iterator[None]:
    """Run a block on every rank and meet at its end: if the block raised on any rank, every rank
    raises a DistributedError with the message of the lowest such rank (the failing rank's own
    exception is its cause). A rank that fails alone would otherwise leave the others waiting in
    the next collective for ever.

    The block itself must not call collectives that other ranks could still be waiting in when
    this one fails: wrap the local work (input checks, local assembly) between collective points.
    The end of the block is one allgather."""
    comm = get_comm(comm)
    error: Optional[BaseException] = None
    try:
        yield
    except BaseException as e:  # noqa: BLE001 - any failure, an exit too, must reach the other ranks
        error = e
    message = None if error is None else f"{type(error).__name__}: {error}"
    messages = comm.allgather(message)
    failed = [r for r, m in enumerate(messages) if m is not None]
    if error is not None and not isinstance(error, Exception):
        raise error  # SystemExit, KeyboardInterrupt: this rank goes on as asked, the others raise
    if failed:
        first = failed[0]
        raise DistributedError(first, messages[first]) from error


def collective(fn):
    """Decorator: `fn` runs inside raise_together on the communicator given as its `comm` keyword
    (COMM_WORLD or the serial stand-in when none): an exception on one rank is raised on all.
    For functions whose work is local up to their end (see raise_together)."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with raise_together(kwargs.get("comm")):
            return fn(*args, **kwargs)
    return wrapper


def abort_on_uncaught(comm=None) -> None:
    """Make an exception that nothing catches end every rank (MPI Abort after printing it) instead of
    ending this rank alone while the others wait: for scripts run under mpirun. A no-op on one rank."""
    comm = get_comm(comm)
    if is_serial(comm):
        return

    def hook(kind, value, tb):
        sys.stderr.write(f"rank {comm.rank}: " + "".join(traceback.format_exception(kind, value, tb)))
        sys.stderr.flush()
        comm.Abort(1)  # does not return: the MPI runtime ends every rank

    sys.excepthook = hook
