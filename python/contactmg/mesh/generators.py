"""Coarse meshes: the Hertz half disk of the seed paper and rectangles, with boundary tags."""
from __future__ import annotations

from typing import Iterable, Tuple

import numpy as np

from ..mesh.mesh import Mesh

HERTZ_ARC, HERTZ_TOP = 1, 2
RECT_BOTTOM, RECT_RIGHT, RECT_TOP, RECT_LEFT = 1, 2, 3, 4


class CircleProjector:
    """Moves points whose facet tag is in `tags` radially onto the circle (center, radius); a
    boundary projection for refinement."""

    def __init__(self, center: Tuple[float, float], radius: float, tags: Iterable[int]):
        self.center = np.asarray(center, dtype=float)
        self.radius = float(radius)
        self.tags = tuple(tags)

    def __call__(self, points: np.ndarray, tags: np.ndarray) -> np.ndarray:
        out = np.array(points, dtype=float, copy=True)
        sel = np.isin(tags, self.tags)
        v = out[sel] - self.center
        r = np.linalg.norm(v, axis=1)
        if np.any(r == 0):
            raise ValueError("cannot project the centre onto the circle (sphere)")
        out[sel] = self.center + self.radius * v / r[:, None]
        return out


def hertz_projector(center=(0.0, 0.4), radius=0.4) -> CircleProjector:
    """The projector onto the Hertz benchmark's circular arc (boundary nodes of refined levels land on it)."""
    return CircleProjector(center, radius, tags=(HERTZ_ARC,))


def _quads_to_triangles(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Split each quad along its shorter diagonal (a mirror-symmetric mesh stays symmetric)."""
    X = points[quads]
    d02 = np.linalg.norm(X[:, 2] - X[:, 0], axis=1)
    d13 = np.linalg.norm(X[:, 3] - X[:, 1], axis=1)
    use02 = d02 <= d13 * (1 - 1e-12)
    tris = np.where(use02[:, None, None], quads[:, [[0, 1, 2], [0, 2, 3]]], quads[:, [[0, 1, 3], [1, 2, 3]]])
    return tris.reshape(-1, 3)


def hertz_half_disk(cell: str = "triangle", center=(0.0, 0.4), radius: float = 0.4) -> Mesh:
    """The lower half of the disk (center, radius), the body of the Hertz benchmark. Triangles: a
    polar mesh of 3 rings with 4k segments on ring k (28 nodes, angles 39-85 degrees); quads: a
    block of 8 x 4 quads under the centre and 3 layers of 16 quads out to the arc (96 nodes,
    angles 60-135 degrees). Both were chosen among candidates by the contraction rate of the
    linear multigrid (benchmarks/methods/linear_multigrid.py): coarse cells of poor aspect ratio near the
    arc cost a lot (0.51 instead of 0.32 per V(3,3) cycle at level 7). Tags: HERTZ_ARC on the arc,
    HERTZ_TOP on the top edge. A node sits at the bottom point; the mesh is symmetric about
    x = center_x."""
    if cell == "triangle":
        return polar_half_disk(center, radius, rings=3, segments=4)
    if cell == "quad":
        return block_ring_half_disk(center, radius, k=4, ring_layers=3, inner=0.45)
    raise ValueError(f"cell must be 'triangle' or 'quad', got {cell!r}")


def _hertz_tagger(cy: float, radius: float):
    def tagger(mid):
        return np.where(np.abs(mid[:, 1] - cy) < 1e-12 * radius, HERTZ_TOP, HERTZ_ARC)
    return tagger


def polar_half_disk(center=(0.0, 0.4), radius: float = 0.4, rings: int = 3, segments: int = 4) -> Mesh:
    """Triangles on concentric half circles: ring k has segments*k arc segments; consecutive rings
    are zipped together choosing the shorter new edge (a Delaunay-like choice)."""
    cx, cy = center
    pts = [np.zeros((1, 2))]
    ids = [np.array([0])]
    n = 1
    for k in range(1, rings + 1):
        m = segments * k
        th = np.pi + np.pi * np.arange(m + 1) / m
        r = radius * (k / rings)  # exactly radius on the outer ring
        ring = r * np.c_[np.cos(th), np.sin(th)]
        ring[[0, -1], 1] = 0.0
        if m % 2 == 0:
            ring[m // 2] = [0.0, -r]
        pts.append(ring)
        ids.append(np.arange(n, n + m + 1))
        n += m + 1
    P = np.vstack(pts)
    tris = [[0, b, a] for a, b in zip(ids[1][:-1], ids[1][1:])]
    for k in range(1, rings):
        A, B = ids[k], ids[k + 1]
        i = j = 0
        while i < len(A) - 1 or j < len(B) - 1:
            if i == len(A) - 1:
                adv_b = True
            elif j == len(B) - 1:
                adv_b = False
            else:
                lb = np.linalg.norm(P[B[j + 1]] - P[A[i]])
                la = np.linalg.norm(P[A[i + 1]] - P[B[j]])
                adv_b = lb < la * (1 - 1e-12) or (abs(lb - la) <= 1e-12 * la and P[A[i], 0] < 0)
            if adv_b:
                tris.append([A[i], B[j + 1], B[j]])
                j += 1
            else:
                tris.append([A[i], A[i + 1], B[j]])
                i += 1
    return Mesh.from_cells(P + [cx, cy], np.array(tris, dtype=np.int64), "triangle", _hertz_tagger(cy, radius))


def block_ring_half_disk(center=(0.0, 0.4), radius: float = 0.4, k: int = 4, ring_layers: int = 3,
                         inner: float = 0.45, cell: str = "quad") -> Mesh:
    """A block of 2k x k quads of half-width inner*radius under the centre and a ring of
    ring_layers x 4k quads out to the arc (4k arc segments); cell="triangle" splits the quads."""
    if k < 1 or ring_layers < 1 or not (0 < inner < 1):
        raise ValueError("need k >= 1, ring_layers >= 1 and 0 < inner < 1")
    cx, cy = center
    a = inner * radius
    nb = 2 * k
    xs = np.linspace(-a, a, nb + 1)
    ys = np.linspace(-a, 0.0, k + 1)
    bx, by = np.meshgrid(xs, ys)
    block = np.c_[bx.ravel(), by.ravel()]
    bid = lambda i, j: j * (nb + 1) + i  # noqa: E731
    quads = [[bid(i, j), bid(i + 1, j), bid(i + 1, j + 1), bid(i, j + 1)] for j in range(k) for i in range(nb)]
    # the block's lower outline (left edge downwards, bottom, right edge upwards) is ring layer 0
    poly = [bid(0, j) for j in range(k, 0, -1)] + [bid(i, 0) for i in range(nb + 1)] + [bid(nb, j) for j in range(1, k + 1)]
    m = len(poly) - 1
    theta = np.pi + np.linspace(0.0, np.pi, m + 1)
    arc = np.c_[radius * np.cos(theta), radius * np.sin(theta)]
    arc[[0, -1], 1] = 0.0
    arc[m // 2] = [0.0, -radius]
    points = [block]
    layer_ids = [np.array(poly)]
    n = len(block)
    for layer in range(1, ring_layers + 1):
        t = layer / ring_layers
        points.append((1 - t) * block[poly] + t * arc)
        layer_ids.append(np.arange(n, n + m + 1))
        n += m + 1
    for layer in range(ring_layers):
        a_ids, b_ids = layer_ids[layer], layer_ids[layer + 1]
        quads += [[a_ids[s], b_ids[s], b_ids[s + 1], a_ids[s + 1]] for s in range(m)]
    pts = np.vstack(points) + [cx, cy]
    quads = np.array(quads, dtype=np.int64)
    cells = quads if cell == "quad" else _quads_to_triangles(pts, quads)
    return Mesh.from_cells(pts, cells, cell, _hertz_tagger(cy, radius))


def rectangle(nx: int, ny: int, lx: float = 1.0, ly: float = 1.0, cell: str = "triangle", origin=(0.0, 0.0),
              distort: float = 0.0, seed: int = 0) -> Mesh:
    """Structured nx x ny rectangle; triangles alternate their diagonal in a checkerboard. distort
    moves interior nodes randomly by up to distort * h (reproducible from seed). Tags:
    RECT_BOTTOM, RECT_RIGHT, RECT_TOP, RECT_LEFT."""
    if cell not in ("triangle", "quad"):
        raise ValueError(f"cell must be 'triangle' or 'quad', got {cell!r}")
    if nx < 1 or ny < 1 or not (lx > 0 and ly > 0):
        raise ValueError("need nx, ny >= 1 and positive side lengths")
    if not (0 <= distort < 0.35):
        raise ValueError(f"distort must lie in [0, 0.35), got {distort}")
    x, y = np.meshgrid(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1))
    pts = np.c_[x.ravel(), y.ravel()]
    if distort > 0:
        h = min(lx / nx, ly / ny)
        rng = np.random.default_rng(seed)
        interior = (pts[:, 0] > 0) & (pts[:, 0] < lx) & (pts[:, 1] > 0) & (pts[:, 1] < ly)
        pts[interior] += rng.uniform(-distort * h, distort * h, size=(int(interior.sum()), 2))
    pts += np.asarray(origin, dtype=float)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    i, j = i.ravel(), j.ravel()
    a = j * (nx + 1) + i
    quads = np.c_[a, a + 1, a + nx + 2, a + nx + 1]
    if cell == "quad":
        cells = quads
    else:
        even = (i + j) % 2 == 0
        t_even = quads[:, [[0, 1, 2], [0, 2, 3]]]
        t_odd = quads[:, [[0, 1, 3], [1, 2, 3]]]
        cells = np.where(even[:, None, None], t_even, t_odd).reshape(-1, 3)
    ox, oy = origin
    tol = 1e-9 * max(lx, ly)

    def tagger(mid):
        t = np.zeros(len(mid), np.int64)
        t[np.abs(mid[:, 1] - oy) < tol] = RECT_BOTTOM
        t[np.abs(mid[:, 0] - (ox + lx)) < tol] = RECT_RIGHT
        t[np.abs(mid[:, 1] - (oy + ly)) < tol] = RECT_TOP
        t[np.abs(mid[:, 0] - ox) < tol] = RECT_LEFT
        return t

    return Mesh.from_cells(pts, cells, cell, tagger)

