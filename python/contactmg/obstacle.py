"""Rigid obstacles: each gives, per contact node, the outward normal n (towards the obstacle) and
the gap g measured along n in the reference configuration. g >= 0 is the normal case; a negative gap
is an initial penetration, and it has a defined meaning: the constraint u_n <= g pushes the node
back out onto the obstacle surface (the solution has u_n = g < 0 there and a compressive force)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple

import numpy as np


@dataclass(frozen=True)
class PlaneObstacle:
    """The half space {x : (x - point) . normal >= 0} is the obstacle; `normal` points from the
    body into the obstacle (for the Hertz benchmark: point (0, 0), normal (0, -1))."""

    point: Tuple[float, ...]
    normal: Tuple[float, ...]

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        n = np.asarray(self.normal, dtype=float)
        p = np.asarray(self.point, dtype=float)
        if n.shape != (x.shape[1],) or p.shape != (x.shape[1],):
            raise ValueError(f"obstacle point and normal must have {x.shape[1]} components")
        length = np.linalg.norm(n)
        if not np.isfinite(length) or length == 0:
            raise ValueError("the obstacle normal must be a finite non-zero vector")
        n = n / length
        return (p - x) @ n, np.tile(n, (len(x), 1))


@dataclass(frozen=True)
class NodalObstacle:
    """Any obstacle, given per contact node as gap and normal (curved obstacles, 3D)."""

    gaps: np.ndarray
    normals: np.ndarray

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        g = np.asarray(self.gaps, dtype=float)
        n = np.asarray(self.normals, dtype=float)
        if g.shape != (len(x),) or n.shape != x.shape:
            raise ValueError(f"NodalObstacle needs gaps of shape {(len(x),)} and normals of shape {x.shape}, "
                             f"got {g.shape} and {n.shape}")
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(n))):
            raise ValueError("NodalObstacle gaps and normals must be finite")
        length = np.linalg.norm(n, axis=1)
        if np.any(length == 0):
            raise ValueError("NodalObstacle normals must be non-zero")
        return g, n / length[:, None]
