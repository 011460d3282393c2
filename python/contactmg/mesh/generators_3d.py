"""Coarse 3D meshes: the Hertz half ball and the cork (a cylinder), with boundary tags and the
projectors that put new boundary nodes of a refinement onto the curved surfaces.

Tag numbering: the curved surface of each body has the smallest tag. The 3D refinement lists a new
node on a rim (an edge shared by a curved and a flat face) once, with the smallest tag of its facets,
so the curved projection wins there (and it keeps the rim in the flat face's plane)."""
from __future__ import annotations

from typing import Iterable, Tuple

import numpy as np

from ..mesh.generators import CircleProjector

from ..mesh.mesh import Mesh

BALL_SURFACE, BALL_TOP = 1, 2
CORK_SIDE, CORK_TOP, CORK_BOTTOM = 1, 2, 3


class SphereProjector(CircleProjector):
    """Moves points whose tag is in `tags` radially onto the sphere (center, radius): the circle
    projector of 2D, which works in any dimension."""

    def __init__(self, center, radius: float, tags: Iterable[int] = (BALL_SURFACE,)):
        super().__init__(center, radius, tags)


class CylinderProjector:
    """Moves points whose tag is in `tags` onto the cylinder of the given radius about the line
    through `point` along `axis`, perpendicular to the axis (their axial coordinate is kept)."""

    def __init__(self, radius: float, point=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), tags: Iterable[int] = (CORK_SIDE,)):
        self.radius = float(radius)
        self.point = np.asarray(point, dtype=float)
        a = np.asarray(axis, dtype=float)
        self.axis = a / np.linalg.norm(a)
        self.tags = tuple(tags)

    def __call__(self, points: np.ndarray, tags: np.ndarray) -> np.ndarray:
        out = np.array(points, dtype=float, copy=True)
        sel = np.isin(tags, self.tags)
        v = out[sel] - self.point
        along = v @ self.axis
        radial = v - along[:, None] * self.axis
        r = np.linalg.norm(radial, axis=1)
        if np.any(r == 0):
            raise ValueError("cannot project a point on the cylinder's axis onto the cylinder")
        out[sel] = self.point + along[:, None] * self.axis + self.radius * radial / r[:, None]
        return out


def _orient_hexes(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Reverse the bottom and top quads of hexahedra that came out left-handed (extruded quads of a
    surface have either orientation)."""
    X = points[hexes]
    vol = np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 3] - X[:, 0], X[:, 4] - X[:, 0]))
    out = hexes.copy()
    flip = vol < 0
    out[flip] = hexes[flip][:, [0, 3, 2, 1, 4, 7, 6, 5]]
    return out


def _hexes_to_tets(points: np.ndarray, hexes: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Conforming split of hexahedra into 12 tetrahedra each: every quad face is cut along the
    diagonal through its node of smallest global index (so both cells sharing it cut it alike) and
    its two triangles are coned to a new node at the cell centre."""
    faces = np.array([(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)])
    n = len(points)
    centres = points[hexes].mean(axis=1)
    tets = []
    for c, h in enumerate(hexes):
        ctr = n + c
        for f in faces:
            q = h[f]
            s = int(np.argmin(q))
            q = np.roll(q, -s)  # q[0] is the smallest: the diagonal q0-q2
            tets.append([q[0], q[1], q[2], ctr])
            tets.append([q[0], q[2], q[3], ctr])
    pts = np.vstack([points, centres])
    tets = np.array(tets, dtype=np.int64)
    X = pts[tets]
    vol = np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))
    tets[vol < 0] = tets[vol < 0][:, [0, 3, 2, 1]]
    return pts, tets


def _hexes_to_tets_24(points: np.ndarray, hexes: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Conforming split of hexahedra into 24 tetrahedra each: a node at every face centre (shared
    by the two cells of the face) and at the cell centre; each face edge, its face centre and the
    cell centre make one tetrahedron (for a cube all 24 are congruent)."""
    faces = np.array([(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)])
    n, m = len(points), len(hexes)
    all_f = hexes[:, faces].reshape(-1, 4)
    key = np.sort(all_f, axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    face_pts = points[uniq].mean(axis=1)
    centres = points[hexes].mean(axis=1)
    fid = n + inv.reshape(m, 6)
    cid = n + len(uniq) + np.arange(m)
    tets = []
    for f in range(6):
        for a in range(4):
            tets.append(np.c_[hexes[:, faces[f, a]], hexes[:, faces[f, (a + 1) % 4]], fid[:, f], cid])
    pts = np.vstack([points, face_pts, centres])
    tets = np.vstack(tets).astype(np.int64)
    X = pts[tets]
    vol = np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))
    tets[vol < 0] = tets[vol < 0][:, [0, 3, 2, 1]]
    return pts, tets


def _block_ring_half_ball(radius: float, k: int, ring_layers: int, inner: float) -> Tuple[np.ndarray, np.ndarray]:
    """Hexahedra of the lower half ball of `radius` centred at the origin: a block [-a, a]^2 x [-a, 0]
    (a = inner * radius) of 2k x 2k x k cubes and ring_layers layers of hexahedra between the block's
    lower surface and its radial projection onto the sphere (a cube-sphere mapping)."""
    a = inner * radius
    g = np.linspace(-a, a, 2 * k + 1)
    gz = np.linspace(-a, 0.0, k + 1)
    I, J, L = np.meshgrid(np.arange(2 * k + 1), np.arange(2 * k + 1), np.arange(k + 1), indexing="ij")
    bid = lambda i, j, l: (i * (2 * k + 1) + j) * (k + 1) + l  # noqa: E731
    block = np.c_[g[I.ravel()], g[J.ravel()], gz[L.ravel()]]
    hexes = []
    for i in range(2 * k):
        for j in range(2 * k):
            for l in range(k):
                hexes.append([bid(i, j, l), bid(i + 1, j, l), bid(i + 1, j + 1, l), bid(i, j + 1, l),
                              bid(i, j, l + 1), bid(i + 1, j, l + 1), bid(i + 1, j + 1, l + 1), bid(i, j + 1, l + 1)])
    # the block's lower surface: bottom and the four sides (as quads of block node ids)
    quads = []
    for i in range(2 * k):
        for j in range(2 * k):
            quads.append([bid(i, j, 0), bid(i + 1, j, 0), bid(i + 1, j + 1, 0), bid(i, j + 1, 0)])
    for t in range(2 * k):
        for l in range(k):
            quads.append([bid(0, t, l), bid(0, t + 1, l), bid(0, t + 1, l + 1), bid(0, t, l + 1)])
            quads.append([bid(2 * k, t, l), bid(2 * k, t + 1, l), bid(2 * k, t + 1, l + 1), bid(2 * k, t, l + 1)])
            quads.append([bid(t, 0, l), bid(t + 1, 0, l), bid(t + 1, 0, l + 1), bid(t, 0, l + 1)])
            quads.append([bid(t, 2 * k, l), bid(t + 1, 2 * k, l), bid(t + 1, 2 * k, l + 1), bid(t, 2 * k, l + 1)])
    quads = np.array(quads)
    surf = np.unique(quads)
    local = {int(s): i for i, s in enumerate(surf)}
    b = block[surf]
    outer = radius * b / np.linalg.norm(b, axis=1)[:, None]
    pts = [block]
    layer_ids = [surf]
    n = len(block)
    for layer in range(1, ring_layers + 1):
        t = layer / ring_layers
        pts.append((1 - t) * b + t * outer)
        layer_ids.append(np.arange(n, n + len(surf)))
        n += len(surf)
    qloc = np.vectorize(local.get)(quads)
    for layer in range(ring_layers):
        A, B = layer_ids[layer][qloc], layer_ids[layer + 1][qloc]
        hexes += np.c_[A, B].tolist()
    P = np.vstack(pts)
    P[np.abs(P[:, 2]) < 1e-14 * radius, 2] = 0.0
    return P, _orient_hexes(P, np.array(hexes, dtype=np.int64))


def half_ball(cell: str = "hexahedron", center=(0.0, 0.0, 0.4), radius: float = 0.4, k: int = 3,
              ring_layers: int = 2, inner: float = 0.5, tet_split: int = 12) -> Mesh:
    """The lower half of the ball (center, radius) with its flat top z = center_z, the body of the
    Hertz sphere. Hexahedra: a block of 2k x 2k x k cubes under the centre and ring_layers layers out
    to the sphere (k = 3: 324 cells, 438 nodes); tetrahedra: each of those hexahedra cut into 12
    (tet_split=12: a centre node each; 3888 cells, 762 nodes) or 24 (also a node at every face
    centre). Chosen by the measured cycle counts of the contact problem (F = 0.4, tol 1e-11):
    hexahedra k = 3: 11, 14, 15 cycles on levels 2, 3, 4; k = 2: 16, 22, 26; k = 4: 12, 14 (levels
    2, 3); k = 3 with 3 ring layers: 16, 22. Tetrahedra k = 3: 20, 28; k = 2: 23, 38 (24-split: 22,
    37), measured with Bey's fixed octahedron diagonal (the shortest one since: 22, 28, 29 on levels
    2-4 for k = 3). A finer coarse mesh that resolves the contact zone helps more than cell shape here. A node
    sits at the bottom point. Tags: BALL_SURFACE on the sphere, BALL_TOP on the top. Refine with
    `ball_projector`. The block's corners must stay inside the ball (inner < 1/sqrt(3))."""
    if cell not in ("tetra", "hexahedron"):
        raise ValueError(f"cell must be 'tetra' or 'hexahedron', got {cell!r}")
    if k < 1 or ring_layers < 1 or not (0 < inner < 3 ** -0.5) or not radius > 0:
        raise ValueError("need k >= 1, ring_layers >= 1, 0 < inner < 1/sqrt(3) and radius > 0")
    P, hexes = _block_ring_half_ball(radius, k, ring_layers, inner)
    if tet_split not in (12, 24):
        raise ValueError(f"tet_split must be 12 or 24, got {tet_split!r}")
    if cell == "tetra":
        P, cells = (_hexes_to_tets if tet_split == 12 else _hexes_to_tets_24)(P, hexes)
    else:
        cells = hexes
    P = P + np.asarray(center, dtype=float)
    cz = float(center[2])

    def tagger(mid):
        return np.where(np.abs(mid[:, 2] - cz) < 1e-9 * radius, BALL_TOP, BALL_SURFACE)

    return Mesh.from_cells(P, cells, cell, tagger)


def ball_projector(center=(0.0, 0.0, 0.4), radius: float = 0.4) -> SphereProjector:
    """The projector onto the half ball's spherical surface (boundary nodes of refined levels land on it)."""
    return SphereProjector(center, radius, (BALL_SURFACE,))


def cylinder(radius: float = 1.0, height: float = 2.0, k: int = 2, ring_layers: int = 1, nz: int = 4,
             inner: float = 0.5, cell: str = "hexahedron") -> Mesh:
    """The cylinder {x^2 + y^2 <= radius^2, 0 <= z <= height}: a cross-section of a 2k x 2k square
    block and ring_layers layers out to the circle (8k segments), extruded in nz layers. Tags:
    CORK_SIDE, CORK_TOP (z = height), CORK_BOTTOM (z = 0). Refine with `CylinderProjector(radius)`."""
    if cell not in ("tetra", "hexahedron"):
        raise ValueError(f"cell must be 'tetra' or 'hexahedron', got {cell!r}")
    if k < 1 or ring_layers < 1 or nz < 1 or not (0 < inner < 1) or not (radius > 0 and height > 0):
        raise ValueError("need k, ring_layers, nz >= 1, 0 < inner < 1 and positive radius and height")
    a = inner * radius
    g = np.linspace(-a, a, 2 * k + 1)
    X, Y = np.meshgrid(g, g, indexing="ij")
    sq = np.c_[X.ravel(), Y.ravel()]
    sid = lambda i, j: i * (2 * k + 1) + j  # noqa: E731
    quads = [[sid(i, j), sid(i + 1, j), sid(i + 1, j + 1), sid(i, j + 1)] for i in range(2 * k) for j in range(2 * k)]
    # the square's outline, counterclockwise, as ring layer 0
    m = 2 * k
    loop = ([sid(i, 0) for i in range(m)] + [sid(m, j) for j in range(m)] + [sid(i, m) for i in range(m, 0, -1)]
            + [sid(0, j) for j in range(m, 0, -1)])
    b = sq[loop]
    outer = radius * b / np.linalg.norm(b, axis=1)[:, None]
    pts2 = [sq]
    ids = [np.array(loop)]
    n = len(sq)
    for layer in range(1, ring_layers + 1):
        t = layer / ring_layers
        pts2.append((1 - t) * b + t * outer)
        ids.append(np.arange(n, n + len(loop)))
        n += len(loop)
    nl = len(loop)
    for layer in range(ring_layers):
        A, B = ids[layer], ids[layer + 1]
        quads += [[A[s], A[(s + 1) % nl], B[(s + 1) % nl], B[s]] for s in range(nl)]
    P2 = np.vstack(pts2)
    quads = np.array(quads)
    z = np.linspace(0.0, height, nz + 1)
    n2 = len(P2)
    P = np.vstack([np.c_[P2, np.full(n2, zz)] for zz in z])
    hexes = np.vstack([np.c_[quads + l * n2, quads + (l + 1) * n2] for l in range(nz)])
    hexes = _orient_hexes(P, hexes)
    cells = hexes
    if cell == "tetra":
        P, cells = _hexes_to_tets(P, hexes)

    def tagger(mid):
        t = np.full(len(mid), CORK_SIDE, np.int64)
        t[np.abs(mid[:, 2] - height) < 1e-9 * height] = CORK_TOP
        t[np.abs(mid[:, 2]) < 1e-9 * height] = CORK_BOTTOM
        return t

    return Mesh.from_cells(P, cells, cell, tagger)


def box(nx: int, ny: int, nz: int, lx: float = 1.0, ly: float = 1.0, lz: float = 1.0, cell: str = "hexahedron",
        origin=(0.0, 0.0, 0.0)) -> Mesh:
    """Structured box; tetrahedra by the 6-tetrahedra Kuhn split of every cube along its main
    diagonal (conforming). Tags: 1..6 for x = 0, x = lx, y = 0, y = ly, z = 0, z = lz."""
    if cell not in ("tetra", "hexahedron"):
        raise ValueError(f"cell must be 'tetra' or 'hexahedron', got {cell!r}")
    if min(nx, ny, nz) < 1 or not (lx > 0 and ly > 0 and lz > 0):
        raise ValueError("need nx, ny, nz >= 1 and positive side lengths")
    x, y, z = (np.linspace(0, l, n + 1) for l, n in ((lx, nx), (ly, ny), (lz, nz)))
    I, J, K = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    P = np.c_[x[I.ravel()], y[J.ravel()], z[K.ravel()]] + np.asarray(origin, dtype=float)
    nid = lambda i, j, k: (i * (ny + 1) + j) * (nz + 1) + k  # noqa: E731
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    hexes = np.c_[nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k),
                  nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1), nid(i, j + 1, k + 1)]
    if cell == "hexahedron":
        cells = hexes
    else:
        # Kuhn: the 6 monotone paths from corner 0 to corner 6 (VTK numbering)
        paths = [(0, 1, 2, 6), (0, 3, 2, 6), (0, 3, 7, 6), (0, 4, 7, 6), (0, 4, 5, 6), (0, 1, 5, 6)]
        cells = np.vstack([hexes[:, list(p)] for p in paths])
        X = P[cells]
        vol = np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))
        # orient by swapping v1 and v3: that keeps Bey's diagonal (v0v2-v1v3), so the refinement of
        # this box is again the Kuhn box (a swap of v1 and v2 does not, and its multigrid is worse)
        cells[vol < 0] = cells[vol < 0][:, [0, 3, 2, 1]]
    o = np.asarray(origin, dtype=float)
    L = np.array([lx, ly, lz])

    def tagger(mid):
        t = np.zeros(len(mid), np.int64)
        tol = 1e-9 * L.max()
        for a in range(3):
            t[np.abs(mid[:, a] - o[a]) < tol] = 2 * a + 1
            t[np.abs(mid[:, a] - o[a] - L[a]) < tol] = 2 * a + 2
        return t

    return Mesh.from_cells(P, cells, cell, tagger)
