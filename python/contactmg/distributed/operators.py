"""The operators of a distributed cycle on one rank over its local nodes (owned and ghost): the
prolongation rows of every local node (set up as scipy matrices, then handed to the core's
DistributedTransfer), the Galerkin rows of every owned coarse node (the core's kernel on d x d
blocks, cpp/mg/distributed_galerkin.hpp), and the coarsest level gathered onto every rank.

Every sum is taken in an order that does not depend on the partition: a row's entries are stored by
ascending local index, which follows one global order of the nodes on every rank (hierarchy.py), and
a product adds them in that order, so each row has the same bits on every number of ranks. A row that a rank needs but does not own (the
prolongation and Galerkin rows of its ghost nodes) is computed by its owner and sent, never
recomputed from a partial neighbourhood.

Why the owner of a coarse node J has every fine row its Galerkin row needs: a fine node i with
P_iJ != 0 lies in a coarse cell containing J, so i is a vertex of a fine cell containing J; every
fine cell at an owned node is local (owned or in the ghost layer). Its row of (M A M) P reaches only
coarse nodes that share a coarse cell with J, and those are local on the coarse level too."""
from __future__ import annotations

from typing import List, Tuple

import numpy as np
import scipy.sparse as sp

from .comm import is_serial, op
from .exchange import local_index


def node_to_dof_rows(nodes: np.ndarray, d: int) -> np.ndarray:
    """The scalar dofs (node * d + a) of `nodes`, node-major."""
    return (np.asarray(nodes, np.int64)[:, None] * d + np.arange(d)).ravel()


def sorted_csr(M) -> sp.csr_matrix:
    """CSR with sorted column indices (the product order of every later sum)."""
    M = sp.csr_matrix(M)
    M.sort_indices()
    return M


def keep_rows(M: sp.csr_matrix, keep: np.ndarray) -> sp.csr_matrix:
    """M with every row not in the boolean mask `keep` (per scalar row) emptied; shape unchanged."""
    return sorted_csr(sp.diags(keep.astype(float)) @ M)


def exchange_ghost_rows(comm, halo, M: sp.csr_matrix, owned_nodes_mask: np.ndarray, col_gid: np.ndarray,
                        d: int) -> sp.csr_matrix:
    """M (rows: local nodes x d, columns: dofs of another level's local nodes, whose global ids are
    col_gid) with the rows of the ghost nodes replaced by their owners' rows. Collective."""
    if is_serial(comm) or halo is None or not (halo.sources or halo.destinations):
        return sorted_csr(keep_rows(M, np.repeat(owned_nodes_mask, d)))
    M = sorted_csr(M)
    out = []
    for r in range(comm.size):
        if r not in halo.send:
            out.append(None)
            continue
        rows = node_to_dof_rows(halo.send[r], d)
        sub = M[rows]
        cols = sub.indices.astype(np.int64)
        out.append((sub.indptr.astype(np.int64), col_gid[cols // d] * d + cols % d, sub.data))
    received = comm.alltoall(out)
    own = keep_rows(M, np.repeat(owned_nodes_mask, d)).tocoo()
    rows_all, cols_all, vals_all = [own.row.astype(np.int64)], [own.col.astype(np.int64)], [own.data]
    for r, got in enumerate(received):
        if got is None:
            continue
        ptr, gcols, vals = got
        ghost_rows = node_to_dof_rows(halo.recv[r], d)
        counts = np.diff(ptr)
        J = local_index(col_gid, gcols // d)
        if np.any(J < 0):
            raise RuntimeError("a ghost row reaches a node this rank does not hold")  # pragma: no cover
        rows_all.append(np.repeat(ghost_rows, counts))
        cols_all.append(J * d + gcols % d)
        vals_all.append(vals)
    out_m = sp.csr_matrix((np.concatenate(vals_all), (np.concatenate(rows_all), np.concatenate(cols_all))),
                          shape=M.shape)
    return sorted_csr(out_m)


def local_transfer(fine_level, coarse_level, d: int, comm) -> sp.csr_matrix:
    """The prolongation onto every local fine node (scalar dofs; rows of ghost nodes from their owners)
    from the local nodes of the level below."""
    t = fine_level.transfer
    n_f, n_c = len(fine_level.gid), len(coarse_level.gid)
    counts = np.diff(t.ptr)
    rows = np.repeat(np.asarray(t.rows, np.int64), counts)
    Pn = sp.csr_matrix((np.asarray(t.weight, float), (rows, np.asarray(t.parent, np.int64))), shape=(n_f, n_c))
    P = sorted_csr(sp.kron(Pn, sp.identity(d), format="csr"))
    owned = fine_level.owner == fine_level.rank
    return exchange_ghost_rows(comm, fine_level.halo, P, owned, coarse_level.gid, d)


def rotate_rows(P: sp.csr_matrix, nodes: np.ndarray, frames: np.ndarray, d: int) -> sp.csr_matrix:
    """T^{-1} P: the rows of the contact nodes in their frames (local = Q^T canonical)."""
    n = P.shape[0] // d
    blocks = np.tile(np.eye(d), (n, 1, 1))
    blocks[np.asarray(nodes, np.int64)] = np.transpose(frames, (0, 2, 1))
    R = sp.bsr_matrix((blocks, np.arange(n), np.arange(n + 1)), shape=(n * d, n * d)).tocsr()
    return sorted_csr(R @ P)


def transfer_kernel(P: sp.csr_matrix, fine_level, coarse_level, d: int):
    """The core's DistributedTransfer of a local transfer (scalar CSR, rows of every local fine node):
    restriction, prolongation, bound restriction and the Galerkin rows it forms (it keeps a weight an
    entry where a block is w I). The scipy matrix is not kept (one copy of P per level)."""
    from .. import _core
    cls = _core.DistributedTransfer2D if d == 2 else _core.DistributedTransfer3D
    return cls(to_block_matrix(P, d), (fine_level.owner == fine_level.rank).astype(np.uint8),
               (coarse_level.owner == coarse_level.rank).astype(np.uint8))


def _exchange_z_rows(comm, fine_level, coarse_gid: np.ndarray, T, A) -> None:
    """The ghost rows of Z = (M A M) P from their owners: the patterns (columns as global ids) once,
    the blocks at every rebuild. A column this rank does not hold arrives as -1 (the core leaves that
    row out: no owned coarse row sums it). Collective."""
    halo = fine_level.halo
    empty = np.zeros(0, np.int64)
    if is_serial(comm) or halo is None or not (halo.sources or halo.destinations):
        if not T.has_ghost_pattern:
            T.set_ghost_pattern(empty, np.zeros(1, np.int64), empty)
        return
    if not T.has_ghost_pattern:
        sent = [None] * comm.size
        for r in halo.destinations:
            ptr, cols = T.z_pattern(A, halo.send[r])
            sent[r] = (ptr, coarse_gid[cols])
        got = comm.alltoall(sent)
        nodes, ptrs, cols = [empty], [np.zeros(1, np.int64)], [empty]
        for r in halo.sources:
            ptr, gcols = got[r]
            nodes.append(np.asarray(halo.recv[r], np.int64))
            ptrs.append(np.asarray(ptr[1:], np.int64) + ptrs[-1][-1])
            cols.append(local_index(coarse_gid, gcols))
        T.set_ghost_pattern(np.concatenate(nodes), np.concatenate(ptrs), np.concatenate(cols))
    got = comm.alltoall([T.z_values(A, halo.send[r]) if r in halo.send else None for r in range(comm.size)])
    if halo.sources:
        T.set_ghost_values(np.concatenate([np.asarray(got[r]).ravel() for r in halo.sources]))


def galerkin_rows(comm, fine_level, coarse_level, T, rows, d: int, A=None, mask=None, hess_nodes=None, hess=None,
                  above=None) -> None:
    """The owned rows of P^T M A M P on the coarse level into `rows` (the core's CoarseRows; ghost
    rows empty), P = T's transfer: the Z = (M A M) P rows of the ghosts sent by their owners, then
    each owned coarse row summed over its fine rows in ascending order, the owned Z rows formed where
    needed (the core's DistributedTransfer). A: the fine BlockMatrix with the mask (per fine dof, 0/1)
    and the Hessian blocks at hess_nodes; or above: the CoarseRows of the level above (no mask). Only
    the rows whose inputs changed are formed again, with the bits of a full rebuild. Collective."""
    if above is not None:
        T.set_fine(above)
        A = above
    else:
        if hess_nodes is None or not len(hess_nodes):
            hess_nodes, hess = np.zeros(0, np.int64), np.zeros((0, d, d))
        T.set_fine(A, np.ascontiguousarray(mask, np.uint8).ravel(), np.asarray(hess_nodes, np.int64),
                   np.ascontiguousarray(hess, float).reshape(-1, d, d))
    _exchange_z_rows(comm, fine_level, coarse_level.gid, T, A)
    T.form_coarse(A, rows, _gid_order(coarse_level))  # in ascending global id: fewer cache misses


def _gid_order(level) -> np.ndarray:
    """The local nodes of `level` in ascending global id, kept on the level for the next rebuild
    (formed again if its ids were renumbered)."""
    kept = getattr(level, "_gid_order", None)
    if kept is None or kept[0] is not level.gid:
        kept = (level.gid, np.argsort(level.gid).astype(np.int64))
        level._gid_order = kept
    return kept[1]


def rows_to_csr(rows, d: int) -> sp.csr_matrix:
    """A scalar CSR copy of a CoarseRows (for the gathered coarsest level), exact zeros dropped."""
    indptr, indices, blocks = rows.blocks()
    n = rows.n
    M = sp.bsr_matrix((blocks, indices, indptr), shape=(n * d, n * d)).tocsr()
    M.eliminate_zeros()
    return sorted_csr(M)


def to_block_matrix(M: sp.csr_matrix, d: int):
    """The core's BlockMatrix of a scalar CSR matrix with d x d blocks."""
    from .. import _core
    B = M.tobsr(blocksize=(d, d))
    B.sort_indices()
    n = M.shape[0] // d
    cls = _core.BlockMatrix2D if d == 2 else _core.BlockMatrix3D
    return cls(n, M.shape[1] // d, B.indptr.astype(np.int64), B.indices.astype(np.int64),
               np.ascontiguousarray(B.data.reshape(-1, d, d)))


class GatheredCoarsest:
    """The coarsest level on every rank: its owned rows gathered (global node order), factored by the
    core's sparse LDL^T and kept current across rebuilds by low-rank corrections (one thread, the
    same matrices in the same sequence on every rank: the same bits everywhere), solved redundantly.
    Inert dofs (a zero diagonal: every fine dof below truncated) get identity rows and stay zero."""

    def __init__(self, comm, level, d: int):
        from .. import _core
        self.comm, self.level, self.d = comm, level, d
        self.factor = _core.GatheredCoarsestFactor()
        self.A = None
        self._smoother = None  # the projected sweeps' (made when first needed, per matrix)

    def set_matrix(self, A_owned_rows: sp.csr_matrix) -> None:
        """The level's matrix from every rank's owned rows (collective)."""
        comm, level, d = self.comm, self.level, self.d
        n = level.num_global_nodes
        gid = level.gid
        if is_serial(comm) and np.array_equal(gid, np.arange(n)):
            A = A_owned_rows  # one rank: its local nodes are the global ones, in order
        else:
            coo = A_owned_rows.tocoo()
            rows = gid[coo.row // d] * d + coo.row % d
            cols = gid[coo.col // d] * d + coo.col % d
            parts = comm.allgather((rows, cols, coo.data))
            r = np.concatenate([p[0] for p in parts])
            c = np.concatenate([p[1] for p in parts])
            v = np.concatenate([p[2] for p in parts])
            order = np.lexsort((c, r))
            A = sorted_csr(sp.csr_matrix((v[order], (r[order], c[order])), shape=(n * d, n * d)))
        first = self.A is None
        self.A = A
        diag = A.diagonal()
        self.scale = float(diag.max()) if len(diag) else 0.0
        self.inert = diag <= 1e-12 * self.scale
        self.factor.set(A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data, self.inert.astype(np.uint8),
                        not first)
        self._smoother = None

    def gather(self, x_local: np.ndarray) -> np.ndarray:
        """The global vector (n * d) from the owned entries of every rank."""
        lev, d = self.level, self.d
        owned = np.flatnonzero(lev.owner == lev.rank)
        idx, vals = lev.gid[owned], x_local[owned]
        parts = [(idx, vals)] if is_serial(self.comm) else self.comm.allgather((idx, vals))
        out = np.zeros((lev.num_global_nodes, d))
        for i, v in parts:
            out[i] = v
        return out.ravel()

    def bound(self, x: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, omega: float) -> None:
        """x (n, d): the exact solution in, the correction within the bounds out, as the serial
        coarsest solve makes it (the core's bound_coarsest_solution: projected sweeps from the best
        start, the exact box solve where the level is semi-definite)."""
        d = self.d
        if self._smoother is None:
            from .. import _core
            cls = _core.GatheredCoarsestSmoother2D if d == 2 else _core.GatheredCoarsestSmoother3D
            self._smoother = cls(to_block_matrix(self.A, d), self.scale)
        self._smoother.bound(x, b, lo, hi, omega, self.factor.shifted)

    def memory_bytes(self) -> int:
        """The gathered matrix and its factor."""
        A = self.A
        total = 0 if A is None else A.data.nbytes + A.indices.nbytes + A.indptr.nbytes
        return int(total + self.factor.memory_bytes())

    def solve(self, b_global: np.ndarray) -> np.ndarray:
        """The exact solution for the global right-hand side (inert dofs zero)."""
        b = np.where(self.inert, 0.0, b_global)
        return self.factor.solve(b)
