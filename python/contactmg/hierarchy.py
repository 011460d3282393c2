"""Nested mesh hierarchies by uniform refinement, with boundary projection."""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Tuple

import numpy as np

from . import _core
from .mesh import Mesh

Projector = Callable[[np.ndarray, np.ndarray], np.ndarray]

# Rough bytes per fine node for a 2D solve (fine matrix in the solver and in Python, coarse matrices,
# prolongations, meshes, work vectors), measured on P1/Q1 hierarchies; 3D needs about 6x more.
_BYTES_PER_NODE = {2: 2200, 3: 14000}


@dataclass
class Transfer:
    """Nodal interpolation from one level to the next: fine node i is the sum of
    weight[k] * coarse node parent[k] for k in ptr[i]:ptr[i+1]."""

    n_fine: int
    n_coarse: int
    ptr: np.ndarray
    parent: np.ndarray
    weight: np.ndarray

    def as_tuple(self) -> Tuple:
        return (self.n_fine, self.n_coarse, self.ptr, self.parent, self.weight)

    def matrix(self):
        """The scalar interpolation matrix as a dense-free scipy.sparse CSR (for tests and users)."""
        import scipy.sparse as sp

        return sp.csr_matrix((self.weight, self.parent, self.ptr), shape=(self.n_fine, self.n_coarse))


def available_memory_bytes() -> int:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def _unique_count(cells: np.ndarray, local) -> int:
    sub = np.sort(cells[:, np.array(local)].reshape(-1, len(local[0])), axis=1)
    return len(np.unique(sub, axis=0))


def estimate_nodes(mesh: Mesh, levels: int) -> int:
    """Nodes of the finest level after levels - 1 uniform refinements (exact)."""
    k = mesh.cells.shape[1]
    n, m = mesh.num_points, mesh.num_cells
    if mesh.dim == 2:
        e = np.sort(np.stack([mesh.cells, np.roll(mesh.cells, -1, axis=1)], -1).reshape(-1, 2), axis=1)
        e = len(np.unique(e, axis=0))
        for _ in range(levels - 1):
            if k == 3:
                n, e, m = n + e, 2 * e + 3 * m, 4 * m
            else:
                n, e, m = n + e + m, 2 * e + 4 * m, 4 * m
        return int(n)
    if k == 4:  # tetrahedra (red): a face gets 3 inner edges, a cell 1 edge (the diagonal) and 8 faces
        e = _unique_count(mesh.cells, [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
        f = _unique_count(mesh.cells, [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)])
        for _ in range(levels - 1):
            n, e, f, m = n + e, 2 * e + 3 * f + m, 4 * f + 8 * m, 8 * m
    else:  # hexahedra: a face gets a centre and 4 half edges, a cell a centre, 6 edges and 12 faces
        e = _unique_count(mesh.cells, [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                                       (0, 4), (1, 5), (2, 6), (3, 7)])
        f = _unique_count(mesh.cells, [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)])
        for _ in range(levels - 1):
            n, e, f, m = n + e + f + m, 2 * e + 4 * f + 6 * m, 4 * f + 12 * m, 8 * m
    return int(n)


def estimate_memory_bytes(mesh: Mesh, levels: int) -> int:
    return estimate_nodes(mesh, levels) * _BYTES_PER_NODE[mesh.dim]


@dataclass
class MeshHierarchy:
    """Meshes from coarse (index 0) to fine and the transfers between consecutive levels."""

    meshes: List[Mesh]
    transfers: List[Transfer] = field(default_factory=list)
    build_seconds: float = 0.0

    @property
    def finest(self) -> Mesh:
        return self.meshes[-1]

    @property
    def levels(self) -> int:
        return len(self.meshes)

    @classmethod
    def build(cls, mesh: Mesh, levels: int, projector: Optional[Projector] = None,
              memory_fraction: float = 0.8) -> "MeshHierarchy":
        """Refine `mesh` uniformly until there are `levels` levels in all (level 1 is `mesh`).
        New nodes on boundary facets are passed through `projector(points, tags)` so that they land
        on a curved boundary. Raises MemoryError before allocating if the estimate does not fit."""
        if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)):
            raise TypeError(f"levels must be an integer, got {type(levels).__name__}")
        if levels < 1:
            raise ValueError(f"levels must be at least 1, got {levels}")
        t0 = time.perf_counter()
        need = estimate_memory_bytes(mesh, levels)
        have = available_memory_bytes()
        if need > memory_fraction * have:
            raise MemoryError(
                f"{levels} levels need about {need / 2**30:.1f} GiB ({estimate_nodes(mesh, levels):,} nodes), "
                f"more than {memory_fraction:.0%} of the {have / 2**30:.1f} GiB available")
        _core.check_cells(mesh.points, mesh.cells, mesh.cell_type)
        meshes, transfers = [mesh], []
        for _ in range(levels - 1):
            m = meshes[-1]
            r = _core.refine(m.points, m.cells, m.cell_type, m.facets, m.facet_tags)
            points = r["points"]
            nb = r["boundary_nodes"]
            if projector is not None and len(nb):
                moved = np.asarray(projector(points[nb], r["boundary_tags"]), dtype=float)
                if moved.shape != (len(nb), m.dim):
                    raise ValueError(f"the boundary projector returned shape {moved.shape}, expected {(len(nb), m.dim)}")
                points[nb] = moved
            _core.check_cells(points, r["cells"], m.cell_type)
            fine = Mesh._trusted(points, r["cells"], m.cell_type, r["facets"], r["facet_tags"])
            meshes.append(fine)
            transfers.append(Transfer(fine.num_points, m.num_points, r["ptr"], r["parent"], r["weight"]))
        return cls(meshes, transfers, time.perf_counter() - t0)
