"""Moving values between ranks: the halo exchange of nodal vectors (every ghost node gets its owner's
value) and global sums whose result does not depend on the number of ranks or the partition.

A floating-point sum rounds after every addition, so its value depends on the order: a sum of
per-rank partial sums changes with the partition. exact_sum and exact_dot instead add every term
exactly, as integers (each double is m * 2^e with an integer m of at most 53 bits), combine the
ranks' integers exactly and round once at the end: the correctly rounded sum, the same on every
rank count and equal to math.fsum of all the terms in one place. The cycle's sums (node_dots) add
one value a node exactly: its products summed in a fixed order by its owner. The local sums run in
the compiled core (cpp/base/exact_sum.hpp); the numpy versions here are the tests' reference."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from .. import _core
from .comm import get_comm, is_serial, mpi_module

# x = m * 2^e with |m| < 2^53 integer: e of the smallest subnormal, 2^-1074 = 2^-1 * 2^-1073 (frexp),
# is -1073 - 53; products of two such terms reach twice that
_E_MIN = -2 * (1073 + 53)
# terms of one exponent are added in int64 in runs of this length: 2^53 * 2^9 = 2^62 < 2^63 (the
# cross terms of a product are below 2^54: 2^54 * 2^8 = 2^62)
_RUN = 256


def _check_finite(x: np.ndarray, what: str) -> None:
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{what} has a non-finite entry (index {int(np.argmax(~np.isfinite(x)))}): an exact sum "
                         "needs finite values")


def _mantissas(x: np.ndarray):
    """(m, e) with x = m * 2^e exactly, m int64 with |m| < 2^53."""
    frac, ex = np.frexp(x)
    return np.ldexp(frac, 53).astype(np.int64), ex.astype(np.int64) - 53


def _fixed_point(m: np.ndarray, e: np.ndarray) -> int:
    """sum(m * 2^e) exactly, as the integer T with sum = T * 2^_E_MIN. Terms are sorted by exponent
    and added in int64 in runs of at most _RUN equal exponents (|m| < 2^54), the run sums shifted
    into one Python integer: numpy does the bulk, Python adds about n / _RUN integers."""
    keep = m != 0
    m, e = m[keep], e[keep]
    if not len(m):
        return 0
    order = np.argsort(e, kind="stable")
    m, e = m[order], e[order]
    n = len(m)
    new_run = np.r_[True, e[1:] != e[:-1]]
    run_start = np.maximum.accumulate(np.where(new_run, np.arange(n), 0))
    starts = np.flatnonzero(new_run | ((np.arange(n) - run_start) % _RUN == 0))
    sums = np.add.reduceat(m, starts)
    shifts = e[starts] - _E_MIN
    return sum(int(s) << int(k) for s, k in zip(sums.tolist(), shifts.tolist()))


def _round(total: int) -> float:
    """total * 2^_E_MIN as the nearest double (Python's integer division rounds correctly)."""
    try:
        return total / (1 << -_E_MIN)
    except OverflowError:
        raise OverflowError("the exact sum is beyond the largest double") from None


def local_fixed_point_sum(x) -> int:
    """This rank's terms summed exactly: the integer T with sum = T * 2^_E_MIN, from the compiled
    core's long accumulator."""
    return _core.exact_sum_limbs(np.ascontiguousarray(x, dtype=float).ravel())


def local_fixed_point_dot(x, y, rows=None) -> int:
    """sum(x * y) exactly, every product exact: the integer T with sum = T * 2^_E_MIN, from the
    compiled core's long accumulator. rows: a flag per row of x (the rows counted), or None: all."""
    x = np.ascontiguousarray(x, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    if rows is None:
        return _core.exact_dot_limbs(x.ravel(), y.ravel())
    return _core.exact_dot_limbs(x, y, np.ascontiguousarray(rows, np.uint8))


def local_node_dot(x, y, rows=None) -> int:
    """The node values fl(x_i . y_i) of (nodes, d) arrays (rows: a flag per node, the nodes counted;
    None: all) summed exactly: the integer T with sum = T * 2^_E_MIN (node_dots says why)."""
    x = np.ascontiguousarray(x, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    return _core.exact_node_dot_limbs(x.reshape(len(x), -1), y.reshape(len(y), -1),
                                      None if rows is None else np.ascontiguousarray(rows, np.uint8))


def _numpy_fixed_point_sum(x) -> int:
    """local_fixed_point_sum in numpy: the reference the core's integer is tested against."""
    x = np.ascontiguousarray(x, dtype=float).ravel()
    _check_finite(x, "the array")
    return _fixed_point(*_mantissas(x))


def _numpy_fixed_point_dot(x, y) -> int:
    """local_fixed_point_dot in numpy, the reference of the tests: each product split into four
    partial products of half mantissas (26 and 27 bits), each exact in int64."""
    x = np.ascontiguousarray(x, dtype=float).ravel()
    y = np.ascontiguousarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"exact_dot needs arrays of one length, got {x.shape[0]} and {y.shape[0]}")
    _check_finite(x, "the first array")
    _check_finite(y, "the second array")
    mx, ex = _mantissas(x)
    my, ey = _mantissas(y)
    sign = np.sign(mx) * np.sign(my)
    ax, ay = np.abs(mx), np.abs(my)
    low = (1 << 27) - 1
    hx, lx, hy, ly = ax >> 27, ax & low, ay >> 27, ay & low
    e = ex + ey
    m = np.concatenate([sign * hx * hy, sign * (hx * ly), sign * (lx * hy), sign * lx * ly])
    return _fixed_point(m, np.concatenate([e + 54, e + 27, e + 27, e]))


def exact_sum(x, comm=None) -> float:
    """The sum over all ranks of every rank's entries of `x` (each entry counted once: pass owned
    values only), correctly rounded: independent of the number of ranks and the partition."""
    comm = get_comm(comm)
    total = local_fixed_point_sum(x)
    if not is_serial(comm):
        total = sum(comm.allgather(total))
    return _round(total)


def exact_dot(x, y, comm=None, rows=None) -> float:
    """sum over all ranks of x . y (owned entries: pass those, or flag the owned rows of x in
    `rows`), correctly rounded: the exact products are summed exactly; independent of the number of
    ranks and the partition."""
    return exact_dots([(x, y)], comm, rows)[0]


def exact_dots(pairs, comm=None, rows=None) -> List[float]:
    """exact_dot of every pair (x, y), or of every sum of pairs [(k, x, y), ...] with integer
    coefficients k, with one collective for all."""
    return _dots(pairs, comm, lambda x, y: local_fixed_point_dot(x, y, rows))


def node_dots(pairs, comm=None, rows=None) -> List[float]:
    """The nodal dots of the cycle, with one collective for all: for each pair (x, y) of (nodes, d)
    arrays (or each sum of pairs [(k, x, y), ...], integer k), the node values fl(x_i . y_i) (the d
    products of node i summed left to right, as numpy's (x * y).sum(axis=1)) of the nodes flagged in
    `rows` (the owned ones), summed exactly over all ranks and rounded once. A node has one owner,
    which forms its value by the same operations on any partition: the same result on every rank
    count, as exact_dot's, at a third of its cost (one term a node, not two a product)."""
    return _dots(pairs, comm, lambda x, y: local_node_dot(x, y, rows))


def exact_totals(totals, comm=None) -> List[float]:
    """Local exact integers (T, with sum = T * 2^_E_MIN: the core's *_limbs kernels) summed over the
    ranks and rounded once each, with one collective for all."""
    comm = get_comm(comm)
    totals = list(totals)
    if not is_serial(comm):
        totals = [sum(t) for t in zip(*comm.allgather(totals))]
    return [_round(t) for t in totals]


def _dots(pairs, comm, local_dot) -> List[float]:
    totals, known = [], {}  # a pair of arrays met twice is summed once

    def local(x, y):
        key = (id(x), id(y))
        if key not in known:
            known[key] = local_dot(x, y)
        return known[key]

    for p in pairs:
        terms = p if isinstance(p, list) else [(1, p[0], p[1])]
        totals.append(sum(int(k) * local(x, y) for k, x, y in terms))
    return exact_totals(totals, comm)


def exact_norm(x, comm=None) -> float:
    """The Euclidean norm from exact_dot (one rounding in the sum of squares, one in the root)."""
    return float(np.sqrt(exact_dot(x, x, comm)))


def local_index(gid: np.ndarray, want: np.ndarray) -> np.ndarray:
    """The local index of each global id in `want` among the local nodes' ids `gid` (distinct, in
    any order), -1 where this rank does not hold it."""
    gid = np.asarray(gid, np.int64)
    want = np.asarray(want, np.int64)
    if not len(gid):
        return np.full(len(want), -1, np.int64)
    order = np.argsort(gid, kind="stable")
    at = np.minimum(np.searchsorted(gid[order], want), len(gid) - 1)
    idx = order[at]
    return np.where(gid[idx] == want, idx, -1).astype(np.int64)


@dataclass
class Halo:
    """Who sends which owned nodes to whom, and where the ghosts of each owner are received: local
    node indices, per neighbour rank in ascending rank order, each list in the receiver's local order.

    update(v) gives every ghost row of v (n_local, ...) its owner's value, in one neighbourhood
    collective (MPI_Neighbor_alltoallv on a distributed graph of the neighbours), always in the same
    order: the result does not depend on message timing."""

    comm: object
    sources: List[int]                       # ranks this one receives ghosts from
    destinations: List[int]                  # ranks this one sends owned values to
    recv: Dict[int, np.ndarray] = field(default_factory=dict)   # source rank -> local ghost indices
    send: Dict[int, np.ndarray] = field(default_factory=dict)   # destination rank -> local owned indices
    _graph: object = None
    exchanges: int = 0  # the exchanges made so far (the cost that grows with the ranks: latency)
    _lists: object = None  # (every send row, every ghost row), formed on the first update

    @classmethod
    def build(cls, comm, gid: np.ndarray, owner: np.ndarray) -> "Halo":
        """The exchange lists of one level from each local node's global id and owner rank. Collective: each rank tells the owners which of their nodes it holds as ghosts."""
        comm = get_comm(comm)
        gid = np.asarray(gid, np.int64)
        owner = np.asarray(owner, np.int64)
        if len(np.unique(gid)) != len(gid):
            raise ValueError("the global ids of a halo must be distinct")
        ghost = np.flatnonzero(owner != comm.rank)
        recv = {int(r): ghost[owner[ghost] == r] for r in np.unique(owner[ghost])}
        if is_serial(comm):
            if recv:
                raise ValueError(f"a serial halo has nodes owned by rank(s) {sorted(recv)}")
            return cls(comm, [], [])
        asked = comm.alltoall([gid[recv[r]] if r in recv else None for r in range(comm.size)])
        send = {}
        for r, want in enumerate(asked):
            if want is None:
                continue
            idx = local_index(gid, want)
            if np.any(idx < 0) or np.any(owner[idx] != comm.rank):
                raise RuntimeError(f"rank {r} holds ghosts that rank {comm.rank} does not own")
            send[r] = idx
        sources, destinations = sorted(recv), sorted(send)
        graph = comm.Create_dist_graph_adjacent(sources, destinations, reorder=False)
        return cls(comm, sources, destinations, recv, send, graph)

    @property
    def ghosts(self) -> np.ndarray:
        """Local indices of all ghost nodes (by source rank, then global id)."""
        parts = [self.recv[r] for r in self.sources]
        return np.concatenate(parts) if parts else np.zeros(0, np.int64)

    def update(self, values: np.ndarray) -> np.ndarray:
        """Overwrite the ghost rows of `values` (rows = local nodes, any trailing shape, float64)
        with the owners' rows, in place; returns `values`."""
        if self._graph is None:
            return values
        if values.dtype != np.float64 or not values.flags.c_contiguous:
            raise TypeError("a halo exchanges C-contiguous float64 arrays")
        width = int(np.prod(values.shape[1:], dtype=np.int64))
        rows = values.reshape(len(values), width)
        # the sweeps exchange after every colour: one gather, one exchange, one scatter
        send_all, recv_all = self._all()
        sendbuf = np.ascontiguousarray(rows[send_all]).ravel()
        recvbuf = np.empty(len(recv_all) * width)
        self._alltoallv(sendbuf, recvbuf, width)
        rows[recv_all] = recvbuf.reshape(-1, width)
        return values

    def start(self, values: np.ndarray) -> "PendingUpdate":
        """update(values) begun: the owned rows are packed now, the ghost rows written by finish().
        Between the two the caller may change owned rows (the values sent are those at start) but
        must not read ghost rows. Lets a sweep update the rows that read no ghost while the ghost
        values are on their way."""
        if self._graph is None:
            return PendingUpdate(None, None, None, None)
        width = int(np.prod(values.shape[1:], dtype=np.int64))
        rows = values.reshape(len(values), width)
        send_all, recv_all = self._all()
        sendbuf = np.ascontiguousarray(rows[send_all]).ravel()
        recvbuf = np.empty(len(recv_all) * width)
        MPI = mpi_module()
        self.exchanges += 1
        send_counts = [len(self.send[r]) * width for r in self.destinations]
        recv_counts = [len(self.recv[r]) * width for r in self.sources]
        request = self._graph.Ineighbor_alltoallv([sendbuf, (send_counts, None), MPI.DOUBLE],
                                                  [recvbuf, (recv_counts, None), MPI.DOUBLE])
        return PendingUpdate(request, (sendbuf, recvbuf), rows, recv_all)

    def update_many(self, *arrays: np.ndarray) -> None:
        """update() of several arrays of one length (rows = local nodes; any dtype whose values a
        double holds exactly, such as 0/1 flags) in one exchange."""
        if self._graph is None:
            return
        widths = [int(np.prod(a.shape[1:], dtype=np.int64)) for a in arrays]
        send_all, recv_all = self._all()
        sendbuf = np.hstack([a[send_all].reshape(len(send_all), w).astype(float) for a, w in zip(arrays, widths)]).ravel()
        recvbuf = np.empty(len(recv_all) * sum(widths))
        self._alltoallv(sendbuf, recvbuf, sum(widths))
        got, at = recvbuf.reshape(len(recv_all), sum(widths)), 0
        for a, w in zip(arrays, widths):
            a[recv_all] = got[:, at:at + w].reshape((-1,) + a.shape[1:])
            at += w

    def _all(self):
        """Every destination's send rows and every source's ghost rows, each in rank order."""
        if self._lists is None:
            cat = lambda parts: np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, np.int64)  # noqa: E731
            self._lists = (cat([self.send[r] for r in self.destinations]), cat([self.recv[r] for r in self.sources]))
        return self._lists

    def _alltoallv(self, sendbuf: np.ndarray, recvbuf: np.ndarray, width: int) -> None:
        self.exchanges += 1
        MPI = mpi_module()
        send_counts = [len(self.send[r]) * width for r in self.destinations]
        recv_counts = [len(self.recv[r]) * width for r in self.sources]
        self._graph.Neighbor_alltoallv([sendbuf, (send_counts, None), MPI.DOUBLE],
                                       [recvbuf, (recv_counts, None), MPI.DOUBLE])

    def free(self) -> None:
        """Release the neighbourhood communicator."""
        if self._graph is not None:
            self._graph.Free()
            self._graph = None


class PendingUpdate:
    """A halo update on its way (Halo.start); finish() waits and writes the ghost rows."""

    def __init__(self, request, buffers, rows, recv_all):
        self.request, self.buffers, self.rows, self.recv_all = request, buffers, rows, recv_all

    def finish(self) -> None:
        """Wait for the exchange and write the ghost rows (once; later calls do nothing)."""
        if self.request is None:
            return
        self.request.Wait()
        self.rows[self.recv_all] = self.buffers[1].reshape(len(self.recv_all), -1)
        self.request = None
