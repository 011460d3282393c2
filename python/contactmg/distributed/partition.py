"""The partition of the coarse mesh's cells among the ranks: METIS (through pymetis) on the dual graph
(cells joined where they share a facet), or recursive coordinate bisection where pymetis is missing.
Only the coarse mesh is partitioned: every finer level's cells belong to the rank of their coarse
ancestor, so the finer levels need no partitioner and no migration."""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..mesh.mesh import _LOCAL_FACETS, Mesh, unique_rows
from .comm import get_comm

# METIS is randomized; a fixed seed makes its partition the same on every run and every rank
METIS_SEED = 17


def dual_graph(mesh: Mesh):
    """CSR (xadj, adjncy) of the cells' facet neighbours, each list in ascending cell order."""
    local = np.array(_LOCAL_FACETS[mesh.cell_type])
    nf = len(local)
    keys = np.sort(mesh.cells[:, local].reshape(-1, local.shape[1]).astype(np.int64), axis=1)
    _, inv = unique_rows(keys, return_inverse=True)
    cell = np.arange(len(keys)) // nf
    order = np.argsort(inv, kind="stable")
    inv_s, cell_s = inv[order], cell[order]
    pair = np.flatnonzero(inv_s[1:] == inv_s[:-1])  # an interior facet: two cells in a row
    a, b = cell_s[pair], cell_s[pair + 1]
    src, dst = np.r_[a, b], np.r_[b, a]
    order = np.lexsort((dst, src))
    src, dst = src[order], dst[order]
    xadj = np.zeros(mesh.num_cells + 1, np.int64)
    np.cumsum(np.bincount(src, minlength=mesh.num_cells), out=xadj[1:])
    return xadj, dst


def coordinate_bisection(points: np.ndarray, parts: int) -> np.ndarray:
    """Recursive coordinate bisection of `points` (the cell centres) into `parts` parts of sizes
    within one of each other: split across the widest extent, the counts in proportion to the parts
    on either side. Ties go by index (a stable sort): deterministic."""
    out = np.zeros(len(points), np.int64)

    def split(idx, first, count):
        if count == 1:
            out[idx] = first
            return
        x = points[idx]
        axis = int(np.argmax(x.max(axis=0) - x.min(axis=0)))
        order = idx[np.argsort(x[:, axis], kind="stable")]
        left = count // 2
        cut = (len(idx) * left) // count
        split(order[:cut], first, left)
        split(order[cut:], first + left, count - left)

    split(np.arange(len(points)), 0, parts)
    return out


def partition_cells(mesh: Mesh, parts: int, method: Optional[str] = None) -> np.ndarray:
    """The part (0..parts-1) of every cell of `mesh`, every part non-empty. method: "metis"
    (pymetis), "bisection" (recursive coordinate bisection of the cell centres) or None: METIS
    where pymetis is installed, else bisection. Deterministic for the same input."""
    if isinstance(parts, bool) or not isinstance(parts, (int, np.integer)) or parts < 1:
        raise ValueError(f"parts must be a positive integer, got {parts!r}")
    if mesh.num_cells < parts:
        raise ValueError(f"the coarse mesh has {mesh.num_cells} cells, fewer than the {parts} ranks: every rank needs "
                         "at least one coarse cell (use a finer coarse mesh or fewer ranks)")
    if method not in (None, "metis", "bisection"):
        raise ValueError(f"method must be 'metis', 'bisection' or None, got {method!r}")
    if parts == 1:
        return np.zeros(mesh.num_cells, np.int64)
    if method in (None, "metis"):
        try:
            import pymetis
        except ImportError:
            if method == "metis":
                raise ImportError("partitioning by METIS needs pymetis (a dependency of the "
                                  "package: pip install pymetis)") from None
            pymetis = None
        if pymetis is not None:
            xadj, adjncy = dual_graph(mesh)
            options = pymetis.Options(seed=METIS_SEED)
            if hasattr(pymetis, "CSRAdjacency"):  # pymetis 2025 on; the keywords are deprecated there
                result = pymetis.part_graph(parts, pymetis.CSRAdjacency(xadj, adjncy), options=options)
            else:
                result = pymetis.part_graph(parts, xadj=xadj, adjncy=adjncy, options=options)
            part = np.asarray(result.vertex_part if hasattr(result, "vertex_part") else result[1], np.int64)
            if len(np.unique(part)) == parts:
                return part
            # METIS may leave a part empty on a tiny graph: bisection never does
    centres = mesh.points[mesh.cells].mean(axis=1)
    return coordinate_bisection(centres, parts)


def partition(mesh: Mesh, comm=None, method: Optional[str] = None) -> np.ndarray:
    """partition_cells into comm.size parts, computed on rank 0 and broadcast: every rank has the
    same array whatever the partitioner does on different machines."""
    comm = get_comm(comm)
    part, error = None, None
    if comm.rank == 0:
        try:
            part = partition_cells(mesh, comm.size, method)
        except (ValueError, ImportError) as e:
            error = f"{type(e).__name__}: {e}"
    part, error = comm.bcast((part, error), root=0)
    if error is not None:
        raise ValueError(error)
    return part
