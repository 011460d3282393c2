"""The nodal contact frames Q_p = [n, t(, s)] (columns): the Python face of the core's one
construction (cpp/model/contact_frames.hpp). In 2D t is n turned by +90 degrees; in 3D t lies along a
Dirichlet-fixed axis orthogonal to n where there is one, else it is built from the canonical axis
least aligned with n, and s = n x t. The problem's ContactBoundary.frames and every result's
contact_frames are these; checks and outputs use them from there.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from .. import _core


def contact_frames(normals: np.ndarray, fixed: Optional[np.ndarray] = None) -> np.ndarray:
    """Frames (nc, d, d) with columns n, t(, s) for the (non-zero) normals (nc, d), as the core
    builds them (one construction, cpp/model/contact_frames.hpp): `fixed` (nc, d), the canonical
    components fixed by Dirichlet data, makes a fixed axis orthogonal to n a frame tangent in 3D."""
    normals = np.ascontiguousarray(normals, dtype=float)
    if normals.ndim != 2 or normals.shape[1] not in (2, 3):
        raise ValueError(f"normals must have shape (nc, 2) or (nc, 3), got {normals.shape}")
    build = _core.contact_frames_2D if normals.shape[1] == 2 else _core.contact_frames_3D
    return build(normals, None if fixed is None else np.ascontiguousarray(fixed, dtype=np.uint8))


def to_local(frames: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Canonical nodal vectors (nc, d) in the frames: Q^T v per node."""
    return np.einsum("cji,cj->ci", frames, v)


def to_canonical(frames: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Nodal vectors (nc, d) in the frames back to canonical coordinates: Q v per node."""
    return np.einsum("cij,cj->ci", frames, v)
