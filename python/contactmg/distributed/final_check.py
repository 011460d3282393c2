"""The final check of a distributed solve: the serial check's conditions (results/checks.py
condition_violations) on each rank's owned nodes, their maxima and sums reduced over the ranks
(sums exact), so every rank gets the same figures on any number of ranks."""
from __future__ import annotations

from typing import Dict

import numpy as np

from ..model.frames import to_local
from ..results.checks import condition_violations
from .comm import is_serial
from .exchange import exact_totals, local_fixed_point_sum


class RanksReduce:
    """Maxima (entry by entry) and exact sums (of every entry of each array) over the ranks of `comm`."""

    def __init__(self, comm):
        self.comm = comm

    def max(self, values) -> np.ndarray:
        """Each value's maximum over the ranks."""
        v = np.asarray(values, float)
        return v if is_serial(self.comm) else np.max(self.comm.allgather(v), axis=0)

    def sum(self, arrays) -> np.ndarray:
        """Each array's entries summed over the ranks, exactly: the totals do not depend on how the
        ranks share the entries."""
        return np.array(exact_totals([local_fixed_point_sum(np.ascontiguousarray(a, float)) for a in arrays], self.comm))


def frame_fixed(fixed: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """The frame components (c, d) of contact nodes whose canonical component along that frame
    axis is prescribed (frames (c, d, d): local = Q^T canonical, so axis a is column a)."""
    if not len(frames):
        return np.zeros(fixed.shape, bool)
    along = np.argmax(np.abs(frames), axis=1)  # (c, d): the canonical axis nearest each frame axis
    return np.take_along_axis(fixed, along, axis=1)


def final_check(fine, u: np.ndarray, comm) -> Dict[str, float]:
    """contact_conditions of the iterate u (local nodes, (n, d), contact nodes in their frames) of
    the distributed problem whose rank part is `fine` (fine_level.LocalFine), recomputed from the
    displacement alone as the serial check does: the residual A w - f of the canonical w with the
    stiffness assembled anew (the solver's matrix has the Dirichlet rows eliminated, and the
    reactions are needed), turned into the contact frames at the contact nodes. Collective."""
    from .. import _core

    level, core = fine.level, fine.core
    owned = np.flatnonzero(level.owner == level.rank).astype(np.int64)
    w = core.to_canonical(u)
    if level.halo is not None:
        level.halo.update(w)  # the ghosts as their owners hold them: an owned row reads them
    mesh, m = fine.mesh, fine.material
    A = _core.assemble_elasticity(mesh.points, mesh.cells, mesh.cell_type, m.E, m.nu)
    stiffness = float(RanksReduce(comm).max([A.max_abs()])[0])
    r = _block_product(A, w)[owned] - fine.canonical_load[owned]
    del A
    fixed = fine.fixed[owned]
    mine = fine.owned_contacts
    nodes = fine.contact_nodes[mine]
    at = np.searchsorted(owned, nodes)
    Q = fine.frames[mine]
    ul = to_local(Q, w[nodes])
    sl = to_local(Q, r[at])
    tied = frame_fixed(fine.fixed[nodes], Q)
    prescribed = np.where(fixed, fine.fixed_values[owned], 0.0)
    return condition_violations(r, w[owned], fine.canonical_load[owned], fixed, prescribed, at, fine.gaps[mine], ul, ul,
                                sl, tied, fine.coefficients[mine], fine.law, stiffness, np.zeros(len(owned), np.int64),
                                RanksReduce(comm))


def _block_product(A, w: np.ndarray) -> np.ndarray:
    """A w for a core BlockMatrix A and w (n, d)."""
    import scipy.sparse as sp

    d = w.shape[1]
    B = sp.bsr_matrix((A.data, A.indices, A.indptr), shape=A.shape)
    return (B @ w.ravel()).reshape(-1, d)
