"""Shape measures of cells, per cell: dihedral angles and the normalized radius ratio of
tetrahedra and triangles, the scaled Jacobian of hexahedra and quadrilaterals; and the smallest of
them on every level of a hierarchy. Used to watch that uniform refinement with boundary projection
keeps the mesh family non-degenerate."""
from __future__ import annotations

import numpy as np

from ..mesh.mesh import _LOCAL_FACETS, unique_rows

_TET_FACES = ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2))  # face i is opposite corner i
_TET_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


def _tets(points, cells):
    X = np.asarray(points, dtype=float)[np.asarray(cells)]
    if X.ndim != 3 or X.shape[1:] != (4, 3):
        raise ValueError(f"expected tetrahedra (m, 4) in 3D, got cells of shape {np.shape(cells)}")
    return X


def dihedral_angles(points, cells) -> np.ndarray:
    """The 6 interior dihedral angles (degrees) of each tetrahedron, shape (m, 6); 70.53 for the
    regular one."""
    X = _tets(points, cells)
    normals = []
    for i, (a, b, c) in enumerate(_TET_FACES):
        n = np.cross(X[:, b] - X[:, a], X[:, c] - X[:, a])
        n /= np.linalg.norm(n, axis=1)[:, None]
        outward = np.sign(np.einsum("ci,ci->c", n, X[:, a] - X[:, i]))
        normals.append(n * outward[:, None])
    # the dihedral angle at the edge shared by faces i and j is pi minus the angle of their normals
    out = [np.pi - np.arccos(np.clip(np.einsum("ci,ci->c", normals[i], normals[j]), -1.0, 1.0))
           for i in range(4) for j in range(i + 1, 4)]
    return np.degrees(np.stack(out, axis=1))


def radius_ratio(points, cells) -> np.ndarray:
    """2 sqrt(6) r / h_max per tetrahedron (inradius over longest edge, 1 for the regular one)."""
    X = _tets(points, cells)
    vol = np.abs(np.einsum("ci,ci->c", X[:, 1] - X[:, 0], np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))) / 6
    area = sum(0.5 * np.linalg.norm(np.cross(X[:, b] - X[:, a], X[:, c] - X[:, a]), axis=1) for a, b, c in _TET_FACES)
    hmax = np.max([np.linalg.norm(X[:, a] - X[:, b], axis=1) for a, b in _TET_EDGES], axis=0)
    return 2 * np.sqrt(6) * (3 * vol / area) / hmax


def scaled_jacobian(points, cells) -> np.ndarray:
    """The smallest corner value of det[e1, e2, e3] / (|e1||e2||e3|) per hexahedron (VTK order;
    1 for a box, <= 0 for a folded cell)."""
    X = np.asarray(points, dtype=float)[np.asarray(cells)]
    if X.ndim != 3 or X.shape[1:] != (8, 3):
        raise ValueError(f"expected hexahedra (m, 8) in 3D, got cells of shape {np.shape(cells)}")
    neighbours = ((1, 3, 4), (2, 0, 5), (3, 1, 6), (0, 2, 7), (7, 5, 0), (4, 6, 1), (5, 7, 2), (6, 4, 3))
    values = []
    for a, (i, j, k) in enumerate(neighbours):
        e = [X[:, q] - X[:, a] for q in (i, j, k)]
        e = [v / np.linalg.norm(v, axis=1)[:, None] for v in e]
        values.append(np.einsum("ci,ci->c", e[0], np.cross(e[1], e[2])))
    return np.min(values, axis=0)


def triangle_radius_ratio(points, cells) -> np.ndarray:
    """2 sqrt(3) r / h_max per triangle (inradius over longest edge, 1 for the equilateral one)."""
    X = np.asarray(points, dtype=float)[np.asarray(cells)]
    if X.ndim != 3 or X.shape[1:] != (3, 2):
        raise ValueError(f"expected triangles (m, 3) in 2D, got cells of shape {np.shape(cells)}")
    e = np.linalg.norm(X[:, [1, 2, 0]] - X, axis=2)
    a, b = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    area = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    return 2 * np.sqrt(3) * (2 * area / e.sum(axis=1)) / e.max(axis=1)


def scaled_jacobian_2d(points, cells) -> np.ndarray:
    """The smallest corner value of cross(e1, e2) / (|e1||e2|) per quadrilateral (counter-clockwise
    order; 1 for a rectangle, <= 0 for a folded cell)."""
    X = np.asarray(points, dtype=float)[np.asarray(cells)]
    if X.ndim != 3 or X.shape[1:] != (4, 2):
        raise ValueError(f"expected quadrilaterals (m, 4) in 2D, got cells of shape {np.shape(cells)}")
    e1 = X[:, [1, 2, 3, 0]] - X
    e2 = X[:, [3, 0, 1, 2]] - X
    cross = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
    return np.min(cross / (np.linalg.norm(e1, axis=2) * np.linalg.norm(e2, axis=2)), axis=1)


_MEASURES = {"tetra": radius_ratio, "hexahedron": scaled_jacobian, "triangle": triangle_radius_ratio,
             "quad": scaled_jacobian_2d}


def cell_quality(mesh) -> np.ndarray:
    """The shape measure of every cell of a Mesh, 1 for the ideal cell and towards 0 (or below:
    folded) for a degenerate one: the normalized radius ratio of tetrahedra and triangles, the
    scaled Jacobian of hexahedra and quadrilaterals."""
    return _MEASURES[mesh.cell_type](mesh.points, mesh.cells)


def hierarchy_quality(hierarchy) -> list:
    """The smallest cell quality (cell_quality) of every level of a MeshHierarchy, coarse first."""
    return [float(cell_quality(m).min()) for m in hierarchy.meshes]


def boundary_caps(mesh, facet_mask=None) -> int:
    """The number of cells of a Mesh with two or more facets on the boundary ("caps": on a curved
    boundary all their nodes lie on the surface, and boundary projection flattens their children at
    the shared edge on every level). With facet_mask (a bool per boundary facet), only caps with
    one of their boundary facets in the mask count (the curved ones: caps on planes do not move)."""
    local = np.array(_LOCAL_FACETS[mesh.cell_type])
    keys = np.sort(mesh.cells[:, local].reshape(-1, local.shape[1]), axis=1)
    ref = np.sort(mesh.facets, axis=1)
    if not len(ref):
        return 0
    mask = np.ones(len(ref), bool) if facet_mask is None else np.asarray(facet_mask, bool)
    if mask.shape != (len(ref),):
        raise ValueError(f"facet_mask needs one entry per boundary facet ({len(ref)}), got shape {mask.shape}")
    _, inv = unique_rows(np.vstack([ref, keys]), return_inverse=True)
    state = np.zeros(inv.max() + 1, np.int8)  # 0 interior, 1 boundary, 2 boundary and in the mask
    state[inv[:len(ref)]] = 1 + mask
    s = state[inv[len(ref):]].reshape(-1, len(local))
    return int(np.sum(((s > 0).sum(axis=1) >= 2) & (s == 2).any(axis=1)))


# Neighbouring boundary facets of one tag whose normals turn by more than CURVED_MIN_DEG and less
# than CURVED_MAX_DEG approximate a curved surface (a sharp edge turns by more, a flat face not at all).
CURVED_MIN_DEG, CURVED_MAX_DEG = 0.5, 30.0


def curved_facet_tags(mesh) -> dict:
    """{tag: largest turn in degrees} of the facet tags whose facets approximate a curved surface:
    some two facets of the tag that share a node have normals between CURVED_MIN_DEG and
    CURVED_MAX_DEG apart."""
    from ..mesh.mesh import facet_area_vectors

    if len(mesh.facets) == 0:
        return {}
    n = facet_area_vectors(mesh.points, mesh.facets)
    n = n / np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    out = {}
    for tag in np.unique(mesh.facet_tags):
        sel = np.flatnonzero(mesh.facet_tags == tag)
        f = mesh.facets[sel]
        # pairs of facets of the tag that share a node: sort (node, facet) and pair neighbours
        node = f.ravel()
        fac = np.repeat(np.arange(len(sel)), f.shape[1])
        order = np.argsort(node, kind="stable")
        node, fac = node[order], fac[order]
        same = node[1:] == node[:-1]
        a, b = fac[:-1][same], fac[1:][same]
        if len(a) == 0:
            continue
        cos = np.clip(np.einsum("ij,ij->i", n[sel[a]], n[sel[b]]), -1.0, 1.0)
        deg = np.degrees(np.arccos(cos))
        smooth = deg[(deg > CURVED_MIN_DEG) & (deg < CURVED_MAX_DEG)]
        if len(smooth):
            out[int(tag)] = float(smooth.max())
    return out
