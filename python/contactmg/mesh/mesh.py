"""The Python mesh type: points, cells of one type, boundary facets with integer tags."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np

CELL_NODES = {"triangle": 3, "quad": 4, "tetra": 4, "hexahedron": 8}
CELL_DIM = {"triangle": 2, "quad": 2, "tetra": 3, "hexahedron": 3}
FACET_NODES = {"triangle": 2, "quad": 2, "tetra": 3, "hexahedron": 4}
# the edges of each cell type (VTK node order)
CELL_EDGES = {
    "triangle": [(0, 1), (1, 2), (2, 0)],
    "quad": [(0, 1), (1, 2), (2, 3), (3, 0)],
    "tetra": [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)],
    "hexahedron": [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)],
}

# local facets of each cell type, ordered so that the outward normal follows (VTK node order)
_LOCAL_FACETS = {
    "triangle": [(0, 1), (1, 2), (2, 0)],
    "quad": [(0, 1), (1, 2), (2, 3), (3, 0)],
    "tetra": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
}


def unique_rows(rows: np.ndarray, **kw):
    """np.unique(rows, axis=0, **kw) for rows of non-negative node ids, through one int64 key per
    row where it fits (a 1D sort: several times faster than the row sort of axis=0)."""
    rows = np.asarray(rows, dtype=np.int64)
    k = rows.shape[1]
    base = int(rows.max(initial=0)) + 1
    if rows.size == 0 or base ** k >= 2 ** 63:
        return np.unique(rows, axis=0, **kw)
    key = rows[:, 0].copy()
    for j in range(1, k):
        key = key * base + rows[:, j]
    out = np.unique(key, **kw)
    if not isinstance(out, tuple):
        out = (out,)
    uniq = np.empty((len(out[0]), k), np.int64)
    rest = out[0]
    for j in range(k - 1, -1, -1):
        uniq[:, j] = rest % base
        rest = rest // base
    return (uniq,) + tuple(o.ravel() for o in out[1:]) if len(out) > 1 else uniq


def _check_not_folded(cells: np.ndarray) -> None:
    """Cells oriented counter-clockwise one by one still overlap if one was inverted (folded over
    its neighbour): then a shared edge is traversed twice in the same direction, where a valid
    mesh traverses every interior edge once each way."""
    k = cells.shape[1]
    e = np.stack([cells, np.roll(cells, -1, axis=1)], axis=-1).reshape(-1, 2)
    _, first, count = unique_rows(e, return_index=True, return_counts=True)
    if np.any(count > 1):
        a, b = e[first[np.argmax(count > 1)]]
        cell = int(first[np.argmax(count > 1)] // k)
        raise ValueError(f"the mesh is inverted or overlaps itself near cell {cell}: edge {a}-{b} is shared by "
                         "two cells on the same side")


def _check_manifold(cells: np.ndarray, cell_type: str) -> None:
    """Every facet of the cells belongs to one cell (boundary) or two (interior), never more."""
    local = np.array(_LOCAL_FACETS[cell_type])
    key = np.sort(cells[:, local].reshape(-1, local.shape[1]), axis=1)
    _, first, count = unique_rows(key, return_index=True, return_counts=True)
    if np.any(count > 2):
        i = int(np.argmax(count > 2))
        raise ValueError(f"the mesh is not a manifold: facet {key[first[i]].tolist()} is shared by {int(count[i])} cells "
                         f"(cell {int(first[i] // len(local))} and others); an interior facet belongs to exactly two")


def _box_pairs(lo: np.ndarray, hi: np.ndarray):
    """Pairs (a, b), a < b, of boxes [lo, hi] (m, 2) that overlap with positive area. Boxes go to
    grids of cell size 2^L s_min by their own size, so a graded mesh costs O(m log(s_max/s_min)):
    each box meets the boxes of its own or a coarser grid in the at most 4 grid cells it touches."""
    size = np.maximum((hi - lo).max(axis=1), 1e-300)
    smin = float(size.min())
    level = np.maximum(np.ceil(np.log2(size / smin) - 1e-12), 0).astype(np.int64)
    origin = lo.min(axis=0)
    found = []

    def buckets(sel, h):
        b0 = np.floor((lo[sel] - origin) / h).astype(np.int64)
        b1 = np.floor((hi[sel] - origin) / h).astype(np.int64)
        ids, keys = [], []
        for dx in (0, 1):
            for dy in (0, 1):
                ok = (b0[:, 0] + dx <= b1[:, 0]) & (b0[:, 1] + dy <= b1[:, 1])
                ids.append(sel[ok])
                keys.append((b0[ok, 0] + dx) * (2 ** 31) + (b0[ok, 1] + dy))
        return np.concatenate(ids), np.concatenate(keys)

    for L in np.unique(level):
        h = smin * 2.0 ** L
        big_ids, big_keys = buckets(np.flatnonzero(level == L), h)
        order = np.argsort(big_keys, kind="stable")
        big_ids, big_keys = big_ids[order], big_keys[order]
        q_ids, q_keys = buckets(np.flatnonzero(level <= L), h)
        start = np.searchsorted(big_keys, q_keys, side="left")
        count = np.searchsorted(big_keys, q_keys, side="right") - start
        a = np.repeat(q_ids, count)
        offset = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        b = big_ids[np.repeat(start, count) + offset]
        keep = (level[a] < L) | (a < b)  # a pair of one level once
        a, b = a[keep], b[keep]
        keep = np.all((lo[a] < hi[b]) & (lo[b] < hi[a]), axis=1)
        found.append(np.minimum(a[keep], b[keep]) * len(lo) + np.maximum(a[keep], b[keep]))
    pairs = np.sort(np.concatenate(found)) if found else np.zeros(0, np.int64)
    pairs = pairs[np.r_[True, pairs[1:] != pairs[:-1]]] if len(pairs) else pairs  # two boxes meet in several grid cells
    return pairs // len(lo), pairs % len(lo)


def _check_no_overlap_2d(pts: np.ndarray, cells: np.ndarray) -> None:
    """Cells that overlap without sharing an edge (the edge test of _check_not_folded cannot see
    them): no node lies inside a cell it does not belong to, and no two edges cross. Candidates
    are the pairs of cells whose bounding boxes overlap."""
    X = pts[cells]
    a, b = _box_pairs(X.min(axis=1), X.max(axis=1))
    # Positive convex cells that share an edge lie on either side of it (_check_not_folded saw to
    # the orientation): such neighbours cannot overlap and are most of the candidates.
    k = cells.shape[1]
    inb = np.stack([np.any(cells[a, i:i + 1] == cells[b], axis=1) for i in range(k)], axis=1)
    edge = np.zeros(len(a), bool)
    for i in range(k):
        edge |= inb[:, i] & inb[:, (i + 1) % k]
    a, b = a[~(edge & (inb.sum(axis=1) == 2))], b[~(edge & (inb.sum(axis=1) == 2))]
    radius = np.linalg.norm(X - X.mean(axis=1)[:, None, :], axis=-1).max(axis=1)
    # round-off in the cross products below, for the sizes of the two cells at hand
    tol = 1e-10 * radius[a] * radius[b]
    for p, q in ((a, b), (b, a)):
        # a node of cell q strictly inside cell p (cells are counter-clockwise and convex)
        for j in range(k):
            node = cells[q, j]
            y = pts[node]
            inside = np.ones(len(p), bool)
            for i in range(k):
                e0, e1 = X[p, i], X[p, (i + 1) % k]
                cross = (e1[:, 0] - e0[:, 0]) * (y[:, 1] - e0[:, 1]) - (e1[:, 1] - e0[:, 1]) * (y[:, 0] - e0[:, 0])
                inside &= cross > tol
            if np.any(inside):
                i = int(np.argmax(inside))
                raise ValueError(f"the mesh overlaps itself: node {int(node[i])} lies inside cell {int(p[i])}")

    def side(u, v, w):
        return (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])

    # two edges that cross at interior points of both
    for i in range(k):
        for j in range(k):
            p0, p1 = X[a, i], X[a, (i + 1) % k]
            q0, q1 = X[b, j], X[b, (j + 1) % k]
            d1, d2, d3, d4 = side(p0, p1, q0), side(p0, p1, q1), side(q0, q1, p0), side(q0, q1, p1)
            cross = (((d1 > tol) & (d2 < -tol)) | ((d1 < -tol) & (d2 > tol))) & \
                    (((d3 > tol) & (d4 < -tol)) | ((d3 < -tol) & (d4 > tol)))
            if np.any(cross):
                m = int(np.argmax(cross))
                raise ValueError(f"the mesh overlaps itself: an edge of cell {int(a[m])} crosses an edge of cell {int(b[m])}")


def connected_components(cells: np.ndarray, num_points: int):
    """(count, label): the connected pieces of the mesh (cells joined through shared nodes);
    label[i] is the piece of node i, -1 for a node that belongs to no cell. Union-find by hooking
    roots onto the smaller root and pointer jumping, in numpy."""
    k = cells.shape[1]
    u = np.repeat(cells[:, 0], k - 1)
    v = cells[:, 1:].ravel()
    parent = np.arange(num_points)
    while True:
        pu, pv = parent[u], parent[v]
        differ = pu != pv
        if not np.any(differ):
            break
        np.minimum.at(parent, np.maximum(pu[differ], pv[differ]), np.minimum(pu[differ], pv[differ]))
        while True:  # point every node at its root
            jumped = parent[parent]
            if np.array_equal(jumped, parent):
                break
            parent = jumped
    used = np.zeros(num_points, bool)
    used[cells.ravel()] = True
    label = np.full(num_points, -1, np.int64)
    ids, label[used] = np.unique(parent[used], return_inverse=True)
    return len(ids), label


def _check_not_folded_3d(cells: np.ndarray, cell_type: str) -> None:
    """The 3D analogue: with every cell positively oriented, the two cells sharing an interior face
    see it with opposite orientations; the same orientation twice means one is folded over the other."""
    local = np.array(_LOCAL_FACETS[cell_type])
    f = cells[:, local].reshape(-1, local.shape[1])
    rot = np.argmin(f, axis=1)
    f = _roll_rows(f, rot)
    sign = f[:, 1] < f[:, -1]
    key = np.c_[np.sort(f, axis=1), sign]
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    if np.any(count > 1):
        cell = int(first[np.argmax(count > 1)] // len(local))
        raise ValueError(f"the mesh is inverted or overlaps itself near cell {cell}: a face is shared by two cells "
                         "on the same side")


def _roll_rows(f: np.ndarray, shift: np.ndarray) -> np.ndarray:
    k = f.shape[1]
    idx = (np.arange(k)[None, :] + shift[:, None]) % k
    return np.take_along_axis(f, idx, axis=1)


def _signed_area(X: np.ndarray) -> np.ndarray:
    """Shoelace formula for polygons X (m, k, 2)."""
    x, y = X[..., 0], X[..., 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)


def _tet_volume(X: np.ndarray) -> np.ndarray:
    return np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0])) / 6.0


def boundary_facets(cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Facets that belong to exactly one cell, in the orientation of that cell (outward normal)."""
    local = np.array(_LOCAL_FACETS[cell_type])
    all_f = cells[:, local].reshape(-1, local.shape[1])
    key = np.sort(all_f, axis=1)
    _, inverse, counts = unique_rows(key, return_inverse=True, return_counts=True)
    return np.ascontiguousarray(all_f[counts[inverse.ravel()] == 1])


def facet_area_vectors(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Each facet's outward normal times its measure (length in 2D, area in 3D; a quadrilateral as
    two triangles), for facets ordered as the boundary facets of the cells."""
    X = points[facets]
    if points.shape[1] == 2:
        t = X[:, 1] - X[:, 0]
        return np.c_[t[:, 1], -t[:, 0]]
    a = 0.5 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    if facets.shape[1] == 4:
        a = a + 0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0])
    return a


def _integer_tags(tags, count: int, what: str = "facet") -> np.ndarray:
    """Facet (or cell) tags as int64; floats are accepted only when they hold integers (NaN is no tag)."""
    tags = np.asarray(tags)
    if tags.shape != (count,):
        raise ValueError(f"{what}_tags must have shape ({count},), got {tags.shape}")
    if count == 0:
        return np.zeros(0, np.int64)
    if tags.dtype.kind == "b" or not (np.issubdtype(tags.dtype, np.integer) or np.issubdtype(tags.dtype, np.floating)):
        raise ValueError(f"{what}_tags must be integers, got dtype {tags.dtype}")
    if np.issubdtype(tags.dtype, np.floating):
        bad = ~np.isfinite(tags) | (tags != np.round(tags)) | (np.abs(tags) >= 2.0 ** 63)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(f"{what} tag {i} is {tags[i]!r}: {what} tags must be integers")
    return tags.astype(np.int64)


def _boundary_facets_as_given(cells: np.ndarray, cell_type: str, facets: np.ndarray) -> np.ndarray:
    """The given facets, checked to be distinct boundary facets of the cells and returned in the
    orientation of their cell (outward normal). A repeated facet would count twice in the lumped
    boundary measure; an interior facet is no boundary at all."""
    if len(facets) == 0:
        return facets
    key = np.sort(facets, axis=1)
    _, first, count = unique_rows(key, return_index=True, return_counts=True)
    if np.any(count > 1):
        i = int(first[np.argmax(count > 1)])
        raise ValueError(f"facet {i} ({facets[i].tolist()}) is given {int(count.max())} times: each boundary facet once")
    bnd = boundary_facets(cells, cell_type)
    bkey = np.sort(bnd, axis=1)
    both = np.concatenate([bkey, key])
    _, inverse = unique_rows(both, return_inverse=True)
    inverse = inverse.ravel()
    row_of = np.full(len(bnd) + len(facets), -1, np.int64)
    row_of[inverse[:len(bnd)]] = np.arange(len(bnd))
    rows = row_of[inverse[len(bnd):]]
    if np.any(rows < 0):
        i = int(np.argmax(rows < 0))
        raise ValueError(f"facet {i} ({facets[i].tolist()}) is not a boundary facet of the cells "
                         "(an interior facet, or nodes that form no facet of any cell)")
    return bnd[rows]


@dataclass
class Mesh:
    points: np.ndarray
    cells: np.ndarray
    cell_type: str
    facets: np.ndarray
    facet_tags: np.ndarray
    # the region of each cell (gmsh's physical volume or surface tag; 0 where none is given):
    # materials are assigned per region
    cell_tags: Optional[np.ndarray] = None

    def __post_init__(self):
        if self.cell_type not in CELL_NODES:
            raise ValueError(f"unknown cell type {self.cell_type!r} (expected one of {sorted(CELL_NODES)})")
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3):
            raise ValueError(f"points must have shape (n, 2) or (n, 3), got {pts.shape}")
        d = CELL_DIM[self.cell_type]
        if pts.shape[1] != d:
            raise ValueError(f"{self.cell_type} cells need {d}D points, got {pts.shape[1]}D")
        bad = ~np.all(np.isfinite(pts), axis=1)
        if np.any(bad):
            raise ValueError(f"point {int(np.argmax(bad))} has a non-finite coordinate")
        cells = np.asarray(self.cells)
        k = CELL_NODES[self.cell_type]
        if cells.ndim != 2 or cells.shape[1] != k:
            raise ValueError(f"{self.cell_type} cells must have shape (m, {k}), got {cells.shape}")
        if cells.size and not np.issubdtype(cells.dtype, np.integer):
            raise ValueError("cells must hold integer node indices")
        cells = cells.astype(np.int64)
        if len(cells) == 0:
            raise ValueError("the mesh has no cells")
        out = (cells < 0) | (cells >= len(pts))
        if np.any(out):
            c = int(np.argmax(out.any(axis=1)))
            raise ValueError(f"cell {c} refers to node {int(cells[c][out[c]][0])}, outside 0..{len(pts) - 1}")
        srt = np.sort(cells, axis=1)
        rep = np.any(srt[:, 1:] == srt[:, :-1], axis=1)
        if np.any(rep):
            raise ValueError(f"cell {int(np.argmax(rep))} repeats a node")
        cells = self._orient(pts, cells)
        facets = np.asarray(self.facets)
        kf = FACET_NODES[self.cell_type]
        if facets.size == 0:
            facets = np.zeros((0, kf), np.int64)
        if facets.ndim != 2 or facets.shape[1] != kf:
            raise ValueError(f"facets of {self.cell_type} meshes must have shape (f, {kf}), got {facets.shape}")
        if facets.size and not np.issubdtype(facets.dtype, np.integer):
            raise ValueError("facets must hold integer node indices")
        facets = facets.astype(np.int64)
        if np.any((facets < 0) | (facets >= len(pts))):
            raise ValueError("a facet refers to a node out of range")
        tags = _integer_tags(self.facet_tags, len(facets))
        facets = _boundary_facets_as_given(cells, self.cell_type, facets)
        self.points = np.ascontiguousarray(pts)
        self.cells = np.ascontiguousarray(cells)
        self.facets = np.ascontiguousarray(facets)
        self.facet_tags = np.ascontiguousarray(tags)
        self.cell_tags = np.zeros(len(cells), np.int64) if self.cell_tags is None else _integer_tags(self.cell_tags, len(cells), "cell")

    def _orient(self, pts, cells):
        _check_manifold(cells, self.cell_type)
        X = pts[cells]
        h = np.max(np.linalg.norm(X[:, :, None, :] - X[:, None, :, :], axis=-1), axis=(1, 2))
        if self.cell_type in ("triangle", "quad"):
            area = _signed_area(X)
            small = np.abs(area) <= 1e-12 * h ** 2
            if np.any(small):
                raise ValueError(f"cell {int(np.argmax(small))} ({self.cell_type}) is degenerate (area {area[small][0]:.3g})")
            flip = area < 0
            if np.any(flip):
                cells = cells.copy()
                cells[flip] = cells[flip][:, ::-1]
                X = pts[cells]
                area = np.abs(area)
            if self.cell_type == "quad":
                corner = np.stack([_signed_area(X[:, [(i - 1) % 4, i, (i + 1) % 4]]) for i in range(4)], 1)
                bad = np.any(corner <= 1e-12 * h[:, None] ** 2, axis=1)
                if np.any(bad):
                    raise ValueError(f"cell {int(np.argmax(bad))} (quad) is not convex or intersects itself")
            _check_not_folded(cells)
            _check_no_overlap_2d(pts, cells)
        elif self.cell_type == "tetra":
            vol = _tet_volume(X)
            small = np.abs(vol) <= 1e-12 * h ** 3
            if np.any(small):
                raise ValueError(f"cell {int(np.argmax(small))} (tetra) is degenerate")
            flip = vol < 0
            if np.any(flip):
                cells = cells.copy()
                # swapping v1 and v3 keeps the edge pair (v0 v2, v1 v3) on which Bey's red refinement
                # puts its interior diagonal (v0 v2 / v1 v3 swap would change the children's shapes and
                # the multigrid rate: 0.34 against 0.48 on a refined Kuhn box)
                cells[flip] = cells[flip][:, [0, 3, 2, 1]]
            _check_not_folded_3d(cells, "tetra")
        else:
            split = [(0, 1, 3, 4), (1, 2, 3, 6), (1, 3, 4, 6), (3, 4, 6, 7), (1, 4, 5, 6)]
            vol = sum(_tet_volume(X[:, list(t)]) for t in split)
            if np.any(vol <= 1e-12 * h ** 3):
                raise ValueError(f"cell {int(np.argmax(vol <= 1e-12 * h ** 3))} (hexahedron) is inverted or degenerate")
            _check_not_folded_3d(cells, "hexahedron")
        return cells

    # -- construction ---------------------------------------------------------------------------
    @classmethod
    def _trusted(cls, points, cells, cell_type, facets, facet_tags, cell_tags=None) -> "Mesh":
        """A mesh whose arrays are known valid: refined by the core, whose cells the core has
        checked (positive Jacobians), or cells validated here with facets made by
        boundary_facets. Skips the Python validation, which costs seconds on million-node levels."""
        m = object.__new__(cls)
        m.points, m.cells, m.cell_type, m.facets, m.facet_tags = points, cells, cell_type, facets, facet_tags
        m.cell_tags = np.zeros(len(cells), np.int32) if cell_tags is None else cell_tags
        return m

    @classmethod
    def from_cells(cls, points, cells, cell_type: str,
                   tagger: Optional[Callable[[np.ndarray], np.ndarray]] = None) -> "Mesh":
        """Mesh with boundary facets computed from the cells; `tagger(midpoints) -> tags`."""
        if cell_type not in CELL_NODES:
            raise ValueError(f"unknown cell type {cell_type!r} (expected one of {sorted(CELL_NODES)})")
        tmp = cls(points, cells, cell_type, np.zeros((0, FACET_NODES[cell_type]), np.int64), np.zeros(0, np.int64))
        facets = boundary_facets(tmp.cells, cell_type)
        tags = np.zeros(len(facets), np.int64)
        if tagger is not None:
            tags = np.asarray(tagger(tmp.points[facets].mean(axis=1)))
            if tags.shape != (len(facets),):
                raise ValueError(f"the tagger returned shape {tags.shape}, expected ({len(facets)},)")
            tags = _integer_tags(tags, len(facets))
        # the cells are checked and the facets are the boundary facets by construction
        return cls._trusted(tmp.points, tmp.cells, cell_type, facets, tags)

    # -- queries --------------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        """The space dimension (2 or 3)."""
        return self.points.shape[1]

    @property
    def num_points(self) -> int:
        """The number of nodes."""
        return len(self.points)

    @property
    def num_cells(self) -> int:
        """The number of cells."""
        return len(self.cells)

    def boundary_nodes(self, tags: Optional[Sequence[int]] = None) -> np.ndarray:
        """The ids (ascending) of the nodes of the boundary facets carrying one of `tags`."""
        sel = np.ones(len(self.facets), bool) if tags is None else np.isin(self.facet_tags, list(tags))
        return np.unique(self.facets[sel]).astype(np.int64)

    def facet_normals(self) -> np.ndarray:
        """The outward unit normals of the boundary facets."""
        a = facet_area_vectors(self.points, self.facets)
        return a / np.linalg.norm(a, axis=1)[:, None]

    def facet_measures(self) -> np.ndarray:
        """The lengths (2D) or areas (3D) of the boundary facets."""
        return np.linalg.norm(facet_area_vectors(self.points, self.facets), axis=1)

    def cell_measures(self) -> np.ndarray:
        """The areas (2D) or volumes (3D) of the cells."""
        X = self.points[self.cells]
        if self.dim == 2:
            return _signed_area(X)
        if self.cell_type == "tetra":
            return _tet_volume(X)
        split = [(0, 1, 3, 4), (1, 2, 3, 6), (1, 3, 4, 6), (3, 4, 6, 7), (1, 4, 5, 6)]
        return sum(_tet_volume(X[:, list(t)]) for t in split)

    def copy(self) -> "Mesh":
        """An independent copy of the mesh."""
        return Mesh(self.points.copy(), self.cells.copy(), self.cell_type, self.facets.copy(), self.facet_tags.copy(),
                    self.cell_tags.copy())
