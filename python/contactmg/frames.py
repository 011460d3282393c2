"""The nodal contact frames Q_p = [n, t(, s)] (columns), the one Python place that builds them.

The core rotates each contact node into the frame built from its normal by the same rule
(cpp: frame_from_normal): in 2D t is n turned by +90 degrees; in 3D t is orthogonal to n, built
from the canonical axis least aligned with n, and s = n x t. Results carry these frames
(ContactResult.contact_frames); checks and outputs use them from there. A core that returns its
own frames (raw["frames"] of a solve) is taken at its word by ContactResult.from_raw; the
problem's frames (ContactBoundary.frames) come from here until they are switched to the core
solver's.
"""
from __future__ import annotations

import numpy as np


def contact_frames(normals: np.ndarray) -> np.ndarray:
    """Frames (nc, d, d) with columns n, t(, s) for the unit (or non-zero) normals (nc, d)."""
    normals = np.asarray(normals, dtype=float)
    nc, d = normals.shape
    Q = np.zeros((nc, d, d))
    if nc == 0:
        return Q
    n = normals / np.linalg.norm(normals, axis=1)[:, None]
    Q[:, :, 0] = n
    if d == 2:
        Q[:, 0, 1], Q[:, 1, 1] = -n[:, 1], n[:, 0]
        return Q
    k = np.argmin(np.abs(n), axis=1)
    e = np.zeros_like(n)
    e[np.arange(nc), k] = 1.0
    t = np.cross(n, e)
    t /= np.linalg.norm(t, axis=1)[:, None]
    Q[:, :, 1], Q[:, :, 2] = t, np.cross(n, t)
    return Q


def to_local(frames: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Canonical nodal vectors (nc, d) in the frames: Q^T v per node."""
    return np.einsum("cji,cj->ci", frames, v)


def to_canonical(frames: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Nodal vectors (nc, d) in the frames back to canonical coordinates: Q v per node."""
    return np.einsum("cij,cj->ci", frames, v)
