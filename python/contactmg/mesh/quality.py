"""Shape measures of 3D cells, per cell: dihedral angles and the normalized radius ratio of
tetrahedra, the scaled Jacobian of hexahedra. Used to watch that uniform refinement with boundary
projection keeps the mesh family non-degenerate."""
from __future__ import annotations

import numpy as np

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
