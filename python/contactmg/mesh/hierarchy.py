"""Nested mesh hierarchies by uniform refinement or by adaptive newest-vertex bisection, with
boundary projection."""
from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass
from typing import Callable, List, Optional, Tuple

import numpy as np

from .. import _core
from ..mesh.mesh import Mesh, unique_rows
from ..mesh.quality import _MEASURES as _QUALITY
from ..mesh.quality import cell_quality, curved_facet_tags

# A projector moves the new boundary nodes of a refinement: projector(points (m, d), facet tags
# (m,)) -> moved points (m, d). One that also defines project_refinement(coarse, r) (CadModel's)
# is called that way instead: it gets the coarse mesh and the core's refinement dict r and returns
# the moved points of r["boundary_nodes"], so that it can follow which coarse facet (and which CAD
# entity) each new node came from.
Projector = Callable[[np.ndarray, np.ndarray], np.ndarray]

# MeshHierarchy.build warns when a level's smallest cell quality (mesh.quality.cell_quality) falls
# below this fraction of the coarse mesh's. Measured (benchmarks/model/cad_refinement.py, three
# refinements with CAD projection): a fillet cylinder and a torus meshed by gmsh and optimized by
# Netgen kept 0.77 and 0.72 of it; gmsh's own meshes of them, whose "caps" (tetrahedra with two
# faces on the curved surface) projection flattens, fell to 0.21 and 0.12, halving on every level.
# A quarter separates the two.
QUALITY_WARN_FRACTION = 0.25
# sweeps of the relaxation of new interior nodes next to projected boundary nodes: the smallest
# quality of the fillet cylinder after three refinements was 0.316 without, 0.323, 0.325, 0.326
# with 1, 2, 4 sweeps, the build 0.83 s without and 1.27, 1.65, 2.54 s with them
RELAX_SWEEPS = 2

# Bytes per fine node of a whole solve (fine matrix in the solver and in Python, coarse matrices,
# prolongations, meshes, work vectors, results), by cell type: the peak resident memory of a Python
# solve that keeps its hierarchy (release_hierarchy off), measured on Hertz triangles /
# quadrilaterals level 8 and sphere tetrahedra / hexahedra level 4 (909 / 891 / 2,065 / 3,181 B a
# node with the interpreter's ~70 MB), times 1.5 for what a problem of another shape holds more.
# It was 2,200 in 2D and 14,000 in 3D, 4.5x the measured 3D peak: it refused tetrahedral level 5
# (8.1M dofs, about 6 GB) on a 24 GB machine.
# Plus the interpreter, numpy, matplotlib's import and the core: _BASE_BYTES.
_BYTES_PER_NODE = {"triangle": 1400, "quad": 1400, "tetra": 3200, "hexahedron": 4800}
_BASE_BYTES = 150 * 2**20


def bytes_per_node(mesh: Mesh) -> int:
    """The memory estimate's bytes per fine node for this mesh's cell type."""
    return _BYTES_PER_NODE[mesh.cell_type]


# kinds of hierarchy whose coarse levels were made from the fine mesh alone (no coarse meshes)
FINE_MESH_KINDS = ("coarsening", "aggregation")


@dataclass
class Transfer:
    """Nodal interpolation from one level to the next: fine node i is the sum of
    weight[k] * coarse node parent[k] for k in ptr[i]:ptr[i+1]."""

    n_fine: int
    n_coarse: int
    ptr: np.ndarray
    parent: np.ndarray
    weight: np.ndarray

    @classmethod
    def from_matrix(cls, P) -> "Transfer":
        """The transfer of a sparse prolongation matrix P (fine x coarse; scipy), zero weights dropped."""
        import scipy.sparse as sp

        P = sp.csr_matrix(P)
        P.eliminate_zeros()
        P.sort_indices()
        return cls(P.shape[0], P.shape[1], P.indptr.astype(np.int64), P.indices.astype(np.int64),
                   P.data.astype(float))

    def as_tuple(self) -> Tuple:
        """The transfer as the core takes it: (n_fine, n_coarse, ptr, parent, weight)."""
        return (self.n_fine, self.n_coarse, self.ptr, self.parent, self.weight)

    def matrix(self):
        """The scalar interpolation matrix as a dense-free scipy.sparse CSR (for tests and users)."""
        import scipy.sparse as sp

        return sp.csr_matrix((self.weight, self.parent, self.ptr), shape=(self.n_fine, self.n_coarse))


def available_memory_bytes() -> int:
    """The memory the system says is available now (MemAvailable), in bytes."""
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
    """Peak resident bytes a solve on `levels` uniform levels of `mesh` is estimated to need."""
    return _BASE_BYTES + estimate_nodes(mesh, levels) * bytes_per_node(mesh)


class MeshHierarchy:
    """Meshes from coarse (index 0) to fine and the transfers between consecutive levels.

    A hierarchy made by `build` can give up its coarse meshes and all its transfers
    (release_coarse) once a core solver holds its own copies of what it needs: the finest mesh
    stays (results and output need it), and `meshes` / `transfers` are made again from the coarse
    mesh, the same refinement and projection (bit for bit) the next time they are asked for. At
    level 9 in 2D they were 66 bytes a dof of a solve's peak."""

    def __init__(self, meshes: List[Mesh], transfers: Optional[List[Transfer]] = None, build_seconds: float = 0.0,
                 kind: str = "uniform", estimated_error: Optional[List[float]] = None,
                 bisection_marks: Optional[np.ndarray] = None):
        self._meshes: Optional[List[Mesh]] = meshes
        self._transfers: Optional[List[Transfer]] = [] if transfers is None else transfers
        self.build_seconds = build_seconds
        self.kind = kind
        # adaptive hierarchies: the estimated error (hierarchical estimator, energy norm) of the solution
        # on each level, coarse to fine
        self.estimated_error: List[float] = [] if estimated_error is None else estimated_error
        # adaptive tetrahedral hierarchies: the bisection state of the finest mesh's cells (the marks of
        # _core.bisect), so that a further level continues the same bisection tree
        self.bisection_marks = bisection_marks
        # build(): (coarse mesh, projector, relax) to make the levels again after release_coarse
        self._recipe: Optional[Tuple[Mesh, Optional[Projector], bool]] = None
        # build() with a projector: the smallest cell quality of every level (hierarchy_quality)
        self.min_quality: Optional[List[float]] = None
        # the boundary projection of build() (the curved surfaces the meshes approximate), or None:
        # contact pairs measure their gaps between those surfaces
        self.projector: Optional[Projector] = None
        self._finest: Optional[Mesh] = None  # the finest mesh while the others are released
        self._levels = 0

    def __setstate__(self, state: dict) -> None:
        # a hierarchy pickled when this was a dataclass (older scripts cached one)
        if "meshes" in state:
            state["_meshes"], state["_transfers"] = state.pop("meshes"), state.pop("transfers")
        for key, default in (("_recipe", None), ("_finest", None), ("_levels", 0), ("bisection_marks", None),
                             ("min_quality", None)):
            state.setdefault(key, default)
        self.__dict__.update(state)

    def __repr__(self) -> str:
        state = ", coarse levels released" if self.released else ""
        return f"MeshHierarchy({self.kind}, {self.levels} levels, {self.finest.num_points} fine nodes{state})"

    @property
    def meshes(self) -> List[Mesh]:
        """The meshes, coarsest first (released coarse meshes are made again when asked for)."""
        if self._meshes is None:
            self._restore()
        return self._meshes

    @meshes.setter
    def meshes(self, value: List[Mesh]) -> None:
        self._meshes, self._finest, self._recipe = value, None, None

    @property
    def transfers(self) -> List[Transfer]:
        """The transfers between consecutive levels, coarsest first (made again when released)."""
        if self._transfers is None:
            self._restore()
        return self._transfers

    @transfers.setter
    def transfers(self, value: List[Transfer]) -> None:
        if self._meshes is None:
            self._restore()
        self._transfers = value
        self._recipe = None  # no longer what build() made

    @property
    def released(self) -> bool:
        """Are the coarse meshes and the transfers released (made again when asked for)?"""
        return self._meshes is None

    def can_release(self) -> bool:
        """A hierarchy of build() (uniform refinement) can make its levels again; an adaptive one
        (its marks came from solves) or one assembled by hand cannot."""
        return self._recipe is not None

    def release_coarse(self) -> bool:
        """Drop the coarse meshes and the transfers, keep the finest mesh (the same object). They
        are made again, bit for bit, when `meshes` or `transfers` is next read. Returns whether
        they were released (False for a hierarchy that cannot make them again: can_release)."""
        if self._recipe is None:
            return False
        if self._meshes is not None:
            self._levels = len(self._meshes)
            self._finest = self._meshes[-1]
            self._meshes, self._transfers = None, None
        return True

    def _restore(self) -> None:
        coarse, projector, relax = self._recipe
        meshes, transfers = _refine_uniformly(coarse, self._levels, projector, relax)
        fine = meshes[-1]
        if not (np.array_equal(fine.points, self._finest.points) and np.array_equal(fine.cells, self._finest.cells)):
            raise RuntimeError("the released hierarchy was not made again identically")  # pragma: no cover
        meshes[-1] = self._finest  # the object the problem and its results hold
        self._meshes, self._transfers, self._finest = meshes, transfers, None

    def memory_bytes(self) -> dict:
        """Bytes of the arrays this hierarchy holds now: {"meshes": ..., "transfers": ...} (the
        finest mesh alone, no transfers, while released). Reads nothing back."""
        def nb(*arrays):
            return int(sum(a.nbytes for a in arrays if isinstance(a, np.ndarray)))

        meshes = [self._finest] if self._meshes is None else self._meshes
        return {"meshes": sum(nb(m.points, m.cells, m.facets, m.facet_tags) for m in meshes),
                "transfers": sum(nb(t.ptr, t.parent, t.weight) for t in (self._transfers or []))}

    @property
    def finest(self) -> Mesh:
        """The finest mesh."""
        return self._finest if self._meshes is None else self._meshes[-1]

    @property
    def levels(self) -> int:
        """The number of levels."""
        if self._meshes is None:
            return self._levels
        return len(self._transfers) + 1 if self.from_fine_mesh else len(self._meshes)

    @classmethod
    def coarsened(cls, mesh: Mesh, coarsest: Optional[int] = None) -> "MeshHierarchy":
        """Coarse levels made from the fine `mesh` alone by geometric coarsening
        (mesh/coarsening.py): nested node sets chosen from the mesh's nodes, the boundary's edges
        and corners first, interpolated by barycentric coordinates in their Delaunay simplices,
        down to at most `coarsest` nodes (None: 200, and an eighth of a mesh of fewer). For a mesh as it comes from a mesher, with no coarse
        mesh to refine; the default of a fine mesh alone (0029-geometric-coarsening). The
        hierarchy holds the fine mesh and the transfers (kind "coarsening")."""
        from .coarsening import coarsening_prolongations

        return cls._from_fine(mesh, "coarsening", lambda: coarsening_prolongations(mesh, coarsest=coarsest))

    @classmethod
    def aggregated(cls, mesh: Mesh, coarsest: Optional[int] = None, omega: float = 1.0) -> "MeshHierarchy":
        """Coarse levels made from the fine `mesh` alone, by nonnegative smoothed aggregation
        (mesh/aggregation.py) down to at most `coarsest` nodes (None: as `coarsened`). Fewer cycles than the geometric
        coarsening on some meshes, but wider coarse stencils and a slower cycle
        (0025-aggregation-coarse-spaces). The hierarchy holds the fine mesh and the transfers
        (kind "aggregation")."""
        from .aggregation import aggregation_prolongations

        return cls._from_fine(mesh, "aggregation",
                              lambda: aggregation_prolongations(mesh, coarsest=coarsest, omega=omega))

    @classmethod
    def _from_fine(cls, mesh: Mesh, kind: str, prolongations) -> "MeshHierarchy":
        if not isinstance(mesh, Mesh):
            raise TypeError(f"mesh must be a Mesh, got {type(mesh).__name__}")
        t0 = time.perf_counter()
        _core.check_cells(mesh.points, mesh.cells, mesh.cell_type)
        transfers = [Transfer.from_matrix(P) for P in prolongations()]
        return cls([mesh], transfers, time.perf_counter() - t0, kind=kind)

    @property
    def from_fine_mesh(self) -> bool:
        """Whether the coarse levels were made from the fine mesh alone (no coarse meshes)."""
        return self.kind in FINE_MESH_KINDS

    def _has_coarse_meshes(self, what: str) -> None:
        if self.from_fine_mesh:
            raise ValueError(f"{what} needs the coarse meshes, and a hierarchy made from the fine mesh alone "
                             f"({self.kind}) has none")

    @classmethod
    def build(cls, mesh: Mesh, levels: int, projector: Optional[Projector] = None,
              memory_fraction: float = 0.8, relax: Optional[bool] = None) -> "MeshHierarchy":
        """Refine `mesh` uniformly until there are `levels` levels in all (level 1 is `mesh`).
        New nodes on boundary facets are passed through `projector(points, tags)` so that they land
        on a curved boundary (a CadModel's projector() follows the CAD geometry). With `relax` (None:
        the projector's own `relax` attribute, True for a CadModel's projector, else False: the
        analytic projectors' hierarchies stay as they were), each
        new interior node of the cells that touch a projected node takes the mean displacement of
        its neighbours where that raises the smallest quality of its cells (the level's smallest
        quality never drops; on the fillet cylinder it rose from 0.316 to 0.326 after three
        refinements); the transfers keep their midpoint weights (the nodes move as projected ones
        do: geometry only). With a projector, the smallest cell quality of every level
        is kept in `min_quality` and a UserWarning is given when a level falls below
        QUALITY_WARN_FRACTION of the coarse mesh's. Raises MemoryError before allocating if the
        estimate does not fit."""
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
        if relax is None:
            relax = bool(getattr(projector, "relax", False))
        h = cls(*_refine_uniformly(mesh, levels, projector, relax), time.perf_counter() - t0)
        h._recipe = (mesh, projector, bool(relax))
        h.projector = projector
        if projector is None and levels > 1:
            curved = curved_facet_tags(mesh)
            if curved:
                turns = ", ".join(f"{t} ({deg:.1f} degrees)" for t, deg in sorted(curved.items()))
                warnings.warn(f"the facets tagged {turns} approximate a curved surface (neighbouring facets turn by up to "
                              "the angle given), and refinement without a projector keeps them faceted: contact on them "
                              "sees the coarse facets, not the surface. Give MeshHierarchy.build(..., projector=...) (an "
                              "analytic projector, or a CadModel's projector()) to follow the surface", UserWarning,
                              stacklevel=2)
        if projector is not None:
            h.min_quality = [float(cell_quality(m).min()) for m in h.meshes]
            q0 = h.min_quality[0]
            low = [k for k, q in enumerate(h.min_quality) if q < QUALITY_WARN_FRACTION * q0]
            if low:
                warnings.warn(f"boundary projection degrades the mesh: level {low[0] + 1} has smallest cell quality "
                              f"{h.min_quality[low[0]]:.3g}, the coarse mesh {q0:.3g} (per level: "
                              f"{', '.join(f'{q:.3g}' for q in h.min_quality)}); a finer coarse mesh near the "
                              "curved boundary keeps it", UserWarning, stacklevel=2)
        return h

    def truncated(self, levels: int) -> "MeshHierarchy":
        """The first `levels` levels (coarse to fine) of this hierarchy, sharing its meshes."""
        self._has_coarse_meshes("truncated()")
        if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or not 1 <= levels <= self.levels:
            raise ValueError(f"levels must lie in 1..{self.levels}, got {levels!r}")
        return MeshHierarchy(self.meshes[:levels], self.transfers[:levels - 1], self.build_seconds, self.kind,
                             self.estimated_error[:levels],
                             self.bisection_marks if levels == self.levels else None)

    def thinned(self, min_growth: float = 2.0) -> "MeshHierarchy":
        """The same finest and coarsest meshes with the levels in between kept only where the
        node count has grown by at least `min_growth` since the last kept level (transfers
        composed: still nested, the fine nodes interpolated from the kept coarse ones). A strongly
        graded hierarchy (small Doerfler theta, growth 1.2-1.5 per level) becomes one with
        geometric growth, so that a cycle over it costs O(n_L) even with full smoothing."""
        self._has_coarse_meshes("thinned()")
        if isinstance(min_growth, bool) or not isinstance(min_growth, (int, float)) or not min_growth >= 1:
            raise ValueError(f"min_growth must be a number >= 1, got {min_growth!r}")
        keep = [0]
        for k in range(1, self.levels):
            if k == self.levels - 1 or self.meshes[k].num_points >= min_growth * self.meshes[keep[-1]].num_points:
                keep.append(k)
        transfers = []
        for a, b in zip(keep[:-1], keep[1:]):
            P = self.transfers[a].matrix()
            for t in self.transfers[a + 1:b]:
                P = t.matrix() @ P
            P = P.tocsr()
            P.sort_indices()
            transfers.append(Transfer(P.shape[0], P.shape[1], P.indptr.astype(np.int64), P.indices.astype(np.int64),
                                      P.data.astype(float)))
        est = [self.estimated_error[k] for k in keep if k < len(self.estimated_error)]
        return MeshHierarchy([self.meshes[k] for k in keep], transfers, self.build_seconds, self.kind, est)

    def new_nodes(self, level: int) -> np.ndarray:
        """Nodes that level `level` (an index into meshes; 0 is the coarse mesh) adds to the one below."""
        self._check_level(level)
        start = 0 if level == 0 else self.meshes[level - 1].num_points
        return np.arange(start, self.meshes[level].num_points, dtype=np.int64)

    def changed_nodes(self, level: int) -> np.ndarray:
        """Nodes whose hat functions on level `level` differ from the level below: the new nodes and
        their neighbours (every node of a cell that has a new node). Level 0 changes every node.
        Local smoothing needs only these rows on an adaptive hierarchy (a cycle costs O(n_L))."""
        self._check_level(level)
        if level == 0:
            return np.arange(self.meshes[0].num_points, dtype=np.int64)
        cells = self.meshes[level].cells
        n_below = self.meshes[level - 1].num_points
        touched = cells[np.any(cells >= n_below, axis=1)]
        return np.unique(touched).astype(np.int64)

    def _check_level(self, level):
        self._has_coarse_meshes("a level's nodes")
        if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or not 0 <= level < self.levels:
            raise ValueError(f"level must be an index 0..{self.levels - 1}, got {level!r}")


def longest_edge_first(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Triangles rotated (orientation kept) so that their longest edge joins the first two
    vertices: the refinement edge of newest-vertex bisection. Ties go to the first edge."""
    X = points[cells]
    length = np.linalg.norm(X[:, [1, 2, 0]] - X, axis=2)  # edge a joins vertices a and a+1
    best = np.argmax(length >= length.max(axis=1, keepdims=True) * (1 - 1e-12), axis=1)
    return np.ascontiguousarray(np.take_along_axis(cells, (best[:, None] + np.arange(3)) % 3, axis=1))


def _refine_uniformly(mesh: Mesh, levels: int, projector: Optional[Projector],
                      relax: bool = True) -> Tuple[List[Mesh], List[Transfer]]:
    """`mesh` and levels - 1 uniform refinements of it, with the transfers between them."""
    meshes, transfers = [mesh], []
    for _ in range(levels - 1):
        m = meshes[-1]
        fine, t = _refined(m, _core.refine(m.points, m.cells, m.cell_type, m.facets, m.facet_tags), projector, relax)
        meshes.append(fine)
        transfers.append(t)
    return meshes, transfers


def index_dtype(largest: int):
    """int32 for node, cell and entry ids up to `largest` that fit (half the bytes of int64: the
    cells of a refined mesh and the transfers' pointers and parents), int64 otherwise."""
    return np.int32 if largest < 2 ** 31 - 1 else np.int64


def _refined(m: Mesh, r: dict, projector: Optional[Projector], relax: bool = False) -> Tuple[Mesh, Transfer]:
    """The fine mesh and transfer of a refinement result of the core, boundary nodes projected."""
    points = r["points"]
    nb = r["boundary_nodes"]
    if projector is not None and len(nb):
        hook = getattr(projector, "project_refinement", None)
        moved = hook(m, r) if hook is not None else projector(points[nb], r["boundary_tags"])
        moved = np.asarray(moved, dtype=float)
        if moved.shape != (len(nb), m.dim):
            raise ValueError(f"the boundary projector returned shape {moved.shape}, expected {(len(nb), m.dim)}")
        if not np.all(np.isfinite(moved)):
            raise ValueError("the boundary projector returned a non-finite coordinate")
        shift = moved - points[nb]
        points[nb] = moved
        if relax:
            _relax_near(points, r["cells"], m.cell_type, m.num_points, r["facets"], nb, shift)
    _core.check_cells(points, r["cells"], m.cell_type)
    # 32-bit ids where they fit: the core reads any integer array (a 64-bit copy while it
    # works on it, none kept); the Python side keeps half the bytes
    ids = index_dtype(len(points))
    # uniform refinement writes the children of each cell one after another: they inherit its region
    children = len(r["cells"]) // m.num_cells
    fine = Mesh._trusted(points, r["cells"].astype(ids), m.cell_type, r["facets"].astype(ids), r["facet_tags"],
                         np.repeat(m.cell_tags, children))
    ptr = r["ptr"].astype(index_dtype(int(r["ptr"][-1])))
    return fine, Transfer(fine.num_points, m.num_points, ptr, r["parent"].astype(index_dtype(m.num_points)), r["weight"])


def _relax_near(points: np.ndarray, cells: np.ndarray, cell_type: str, n_coarse: int, facets: np.ndarray,
                nb: np.ndarray, shift: np.ndarray, sweeps: Optional[int] = None) -> None:
    """Move the new interior nodes of the cells that touch a projected boundary node (in place):
    each takes the mean displacement (from its refinement position) of its cell neighbours, the
    projected nodes carrying their projection's shift and the others none, but only where that
    raises the smallest (signed) quality of its cells, so the smallest quality of the level never
    drops. Nodes further away keep their midpoint positions: an uncurved part of the mesh is
    untouched, and unguarded averaging lowered the smallest quality on a torus (0.343 to 0.324)."""
    sweeps = RELAX_SWEEPS if sweeps is None else sweeps
    n = len(points)
    moved = np.zeros(n, bool)
    moved[nb[np.any(shift != 0, axis=1)]] = True
    if not moved.any():
        return
    near = cells[moved[cells].any(axis=1)]
    free = np.zeros(n, bool)
    free[near.ravel()] = True
    free[:n_coarse] = False
    free[facets.ravel()] = False
    if not free.any():
        return
    near = near[free[near].any(axis=1)]
    k = near.shape[1]
    a, b = np.nonzero(~np.eye(k, dtype=bool))
    i, j = near[:, a].ravel(), near[:, b].ravel()
    keep = free[i]
    i, j = i[keep], j[keep]
    count = np.bincount(i, minlength=n)
    idx = np.flatnonzero(free)
    measure = _QUALITY[cell_type]

    def quality(x, c):
        q = measure(x, c)
        if cell_type in ("tetra", "triangle"):  # radius ratios are of |volume|: a folded cell is the worst
            X = x[c]
            q = np.where(np.linalg.det(X[:, 1:] - X[:, :1]) > 0, q, -np.abs(q))
        return q

    # the cells around each free node, as (node, cell) pairs
    rows, cols = np.nonzero(free[near])
    node, cell = near[rows, cols], rows

    def node_min(q):
        out = np.full(n, np.inf)
        np.minimum.at(out, node, q[cell])
        return out[idx]

    d = np.zeros_like(points)
    d[nb] = shift

    for _ in range(sweeps):
        q_old = quality(points, near)
        mean = np.stack([np.bincount(i, weights=d[j, c], minlength=n) for c in range(points.shape[1])], axis=1)
        trial = points.copy()
        trial[idx] = points[idx] - d[idx] + mean[idx] / count[idx, None]
        better = node_min(quality(trial, near)) > node_min(q_old)
        if not better.any():
            break
        new = points.copy()
        new[idx[better]] = trial[idx[better]]
        # neighbours moved together can undo each other's gain: keep a node's move only where none
        # of its cells ends below its smallest quality before the sweep
        for _ in range(4):
            q_new = quality(new, near)
            worse = np.zeros(n, bool)
            lost = q_new[cell] < node_min(q_old)[np.searchsorted(idx, node)]
            worse[node[lost]] = True
            back = idx[worse[idx] & np.any(new[idx] != points[idx], axis=1)]
            if not len(back):
                break
            new[back] = points[back]
        d[idx] += new[idx] - points[idx]
        points[idx] = new[idx]


def facet_parents(coarse: Mesh, r: dict) -> np.ndarray:
    """For every facet of a uniform refinement r of `coarse` (the dict of _core.refine), the index
    of the coarse facet it lies in: the coarse nodes its nodes interpolate from (nonzero transfer
    weights) are exactly the nodes of that facet, for simplices and hexahedra alike."""
    ptr, parent, weight = r["ptr"], r["parent"], r["weight"]
    n_fine = len(ptr) - 1
    counts = np.diff(ptr)
    width = int(counts.max(initial=1))
    pad = np.full((n_fine, width), -1, np.int64)
    rows = np.repeat(np.arange(n_fine), counts)
    cols = np.arange(len(parent)) - np.repeat(ptr[:-1], counts)
    pad[rows, cols] = np.where(weight != 0, parent, -1)
    facets = np.asarray(r["facets"], np.int64)
    kf = facets.shape[1]
    cand = np.sort(pad[facets].reshape(len(facets), -1), axis=1)
    dup = np.zeros_like(cand, bool)
    dup[:, 1:] = cand[:, 1:] == cand[:, :-1]
    cand[dup] = -1
    cand = np.sort(cand, axis=1)
    if np.any(cand[:, -kf - 1] >= 0) if cand.shape[1] > kf else False:
        raise ValueError("a fine facet interpolates from more coarse nodes than one facet has: not a uniform refinement")
    own = cand[:, -kf:]
    ref = np.sort(np.asarray(coarse.facets, np.int64), axis=1)
    uniq, inv = unique_rows(np.vstack([ref, own]), return_inverse=True)
    where = np.full(len(uniq), -1, np.int64)
    where[inv[:len(ref)]] = np.arange(len(ref))
    out = where[inv[len(ref):]]
    if np.any(out < 0):
        raise ValueError(f"fine facet {int(np.argmax(out < 0))} lies in no coarse facet")
    return out


def _node_cells(cells: np.ndarray, n: int) -> Tuple[np.ndarray, np.ndarray]:
    """CSR of the cells around each node: cells ptr[i]:ptr[i+1] of `order` hold node i."""
    flat = cells.ravel()
    order = np.argsort(flat, kind="stable") // cells.shape[1]
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(flat, minlength=n), out=ptr[1:])
    return ptr, order


def boundary_interpolation(coarse: Mesh, fine_points: np.ndarray, t: Transfer, tol: float = 1e-12) -> Transfer:
    """The transfer `t` with the rows of moved nodes (fine nodes not at the weighted mean of their
    parents: new boundary nodes projected onto a curved boundary) replaced by the coarse P1
    function evaluated at the node's actual position: its barycentric coordinates in the coarse
    simplex that holds all its parents (of several, the one the point lies least outside of).
    Why: with the refinement weights (1/2, 1/2) the prolongation of a linear field (a rigid
    rotation, a constant strain) is not that field at a projected node, so the coarse spaces miss
    exactly the smooth modes multigrid relies on them for; with barycentric weights P reproduces
    every linear field on every level. A projected node lies outside its coarse cell on a convex
    boundary: one weight is negative (about -h / (8 R)), so P is no averaging map there
    (bound_restriction.hpp scales by the row's sum of |weights|, which covers it).
    Not used by default: it was the suspected cause of the cycle growth on the Hertz hierarchies,
    and measured it is not (linear rates the same to 0.005 in 2D and 3D, Algorithm 2 the same or up
    to 4 cycles worse: the negative weights tighten the restricted obstacles; 0018-adaptive-estimator). Kept for that comparison and for meshes whose
    projection moves nodes by more than h^2 / (8 R)."""
    if coarse.cell_type not in ("triangle", "tetra"):
        raise ValueError(f"boundary interpolation is for simplices, got {coarse.cell_type}")
    d = coarse.dim
    P = t.matrix()
    moved = np.flatnonzero(np.linalg.norm(fine_points - P @ coarse.points, axis=1) >
                           tol * max(1.0, float(np.abs(coarse.points).max())))
    if not len(moved):
        return t
    nptr, ncells = _node_cells(coarse.cells, coarse.num_points)
    count = np.diff(t.ptr)
    new_count = count.copy()
    new_rows = {}
    for i in moved:
        sl = slice(t.ptr[i], t.ptr[i + 1])
        par = t.parent[sl][t.weight[sl] != 0]
        cand = ncells[nptr[par[0]]:nptr[par[0] + 1]]
        cand = cand[[bool(np.all(np.isin(par, coarse.cells[c]))) for c in cand]]
        if not len(cand):
            raise ValueError(f"fine node {i}: no coarse cell holds all its parents {par.tolist()}")
        X = coarse.points[coarse.cells[cand]]                      # (k, d+1, d)
        J = np.transpose(X[:, 1:] - X[:, :1], (0, 2, 1))           # (k, d, d)
        lam = np.linalg.solve(J, (fine_points[i] - X[:, 0])[:, :, None])[:, :, 0]
        bary = np.concatenate([1 - lam.sum(axis=1, keepdims=True), lam], axis=1)
        best = int(np.argmax(bary.min(axis=1)))
        new_rows[int(i)] = (coarse.cells[cand[best]], bary[best])
        new_count[i] = d + 1
    ptr = np.zeros(t.n_fine + 1, dtype=np.int64)
    np.cumsum(new_count, out=ptr[1:])
    keep = np.ones(t.n_fine, dtype=bool)
    keep[moved] = False
    src = np.repeat(keep, count)
    dst = np.repeat(keep, new_count)
    parent = np.empty(ptr[-1], dtype=np.int64)
    weight = np.empty(ptr[-1], dtype=float)
    parent[dst], weight[dst] = t.parent[src], t.weight[src]
    for i, (p, w) in new_rows.items():
        parent[ptr[i]:ptr[i + 1]], weight[ptr[i]:ptr[i + 1]] = p, w
    return Transfer(t.n_fine, t.n_coarse, ptr, parent, weight)
