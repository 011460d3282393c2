"""The Python mesh type: points, cells of one type, boundary facets with integer tags."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np

CELL_NODES = {"triangle": 3, "quad": 4, "tetra": 4, "hexahedron": 8}
CELL_DIM = {"triangle": 2, "quad": 2, "tetra": 3, "hexahedron": 3}
FACET_NODES = {"triangle": 2, "quad": 2, "tetra": 3, "hexahedron": 4}

# local facets of each cell type, ordered so that the outward normal follows (VTK node order)
_LOCAL_FACETS = {
    "triangle": [(0, 1), (1, 2), (2, 0)],
    "quad": [(0, 1), (1, 2), (2, 3), (3, 0)],
    "tetra": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
}


def _check_not_folded(cells: np.ndarray) -> None:
    """Cells oriented counter-clockwise one by one still overlap if one was inverted (folded over
    its neighbour): then a shared edge is traversed twice in the same direction, where a valid
    mesh traverses every interior edge once each way."""
    k = cells.shape[1]
    e = np.stack([cells, np.roll(cells, -1, axis=1)], axis=-1).reshape(-1, 2)
    _, first, count = np.unique(e, axis=0, return_index=True, return_counts=True)
    if np.any(count > 1):
        a, b = e[first[np.argmax(count > 1)]]
        cell = int(first[np.argmax(count > 1)] // k)
        raise ValueError(f"the mesh is inverted or overlaps itself near cell {cell}: edge {a}-{b} is shared by "
                         "two cells on the same side")


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
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return np.ascontiguousarray(all_f[counts[inverse.ravel()] == 1])


@dataclass
class Mesh:
    points: np.ndarray
    cells: np.ndarray
    cell_type: str
    facets: np.ndarray
    facet_tags: np.ndarray

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
        facets = facets.astype(np.int64)
        if np.any((facets < 0) | (facets >= len(pts))):
            raise ValueError("a facet refers to a node out of range")
        tags = np.asarray(self.facet_tags)
        if tags.shape != (len(facets),):
            raise ValueError(f"facet_tags must have shape ({len(facets)},), got {tags.shape}")
        self.points = np.ascontiguousarray(pts)
        self.cells = np.ascontiguousarray(cells)
        self.facets = np.ascontiguousarray(facets)
        self.facet_tags = np.ascontiguousarray(tags.astype(np.int64))

    def _orient(self, pts, cells):
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
        elif self.cell_type == "tetra":
            vol = _tet_volume(X)
            small = np.abs(vol) <= 1e-12 * h ** 3
            if np.any(small):
                raise ValueError(f"cell {int(np.argmax(small))} (tetra) is degenerate")
            flip = vol < 0
            if np.any(flip):
                cells = cells.copy()
                cells[flip] = cells[flip][:, [0, 2, 1, 3]]
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
    def _trusted(cls, points, cells, cell_type, facets, facet_tags) -> "Mesh":
        """A mesh made by the core's refinement, whose cells the core has checked (positive
        Jacobians): skips the Python validation, which costs seconds on million-node levels."""
        m = object.__new__(cls)
        m.points, m.cells, m.cell_type, m.facets, m.facet_tags = points, cells, cell_type, facets, facet_tags
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
            tags = np.asarray(tagger(tmp.points[facets].mean(axis=1)), dtype=np.int64)
            if tags.shape != (len(facets),):
                raise ValueError(f"the tagger returned shape {tags.shape}, expected ({len(facets)},)")
        return cls(tmp.points, tmp.cells, cell_type, facets, tags)

    # -- queries --------------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.points.shape[1]

    @property
    def num_points(self) -> int:
        return len(self.points)

    @property
    def num_cells(self) -> int:
        return len(self.cells)

    def boundary_nodes(self, tags: Optional[Sequence[int]] = None) -> np.ndarray:
        sel = np.ones(len(self.facets), bool) if tags is None else np.isin(self.facet_tags, list(tags))
        return np.unique(self.facets[sel]).astype(np.int64)

    def facet_normals(self) -> np.ndarray:
        X = self.points[self.facets]
        if self.dim == 2:
            t = X[:, 1] - X[:, 0]
            n = np.c_[t[:, 1], -t[:, 0]]
        else:
            n = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        return n / np.linalg.norm(n, axis=1)[:, None]

    def facet_measures(self) -> np.ndarray:
        X = self.points[self.facets]
        if self.dim == 2:
            return np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
        area = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
        if self.facets.shape[1] == 4:
            area += 0.5 * np.linalg.norm(np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]), axis=1)
        return area

    def cell_measures(self) -> np.ndarray:
        X = self.points[self.cells]
        if self.dim == 2:
            return _signed_area(X)
        if self.cell_type == "tetra":
            return _tet_volume(X)
        split = [(0, 1, 3, 4), (1, 2, 3, 6), (1, 3, 4, 6), (3, 4, 6, 7), (1, 4, 5, 6)]
        return sum(_tet_volume(X[:, list(t)]) for t in split)

    def copy(self) -> "Mesh":
        return Mesh(self.points.copy(), self.cells.copy(), self.cell_type, self.facets.copy(), self.facet_tags.copy())
