"""Rigid obstacles: each gives, per contact node, the outward normal n (towards the obstacle) and
the gap g measured along n in the reference configuration. g >= 0 is the normal case; a negative gap
is an initial penetration, and it has a defined meaning: the constraint u_n <= g pushes the node
back out onto the obstacle surface (the solution has u_n = g < 0 there and a compressive force).

An obstacle is any object with gaps_and_normals(points) -> (gaps (m,), normals (m, d)) for the
contact nodes' coordinates; one that also has gaps_and_normals_at(nodes, points) is asked with the
contact nodes' mesh ids as well (NodalObstacle)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np

from .nodal import node_ids, rows_for


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
    """Any obstacle, given per node as gap and normal (curved obstacles, 3D). With `nodes` (mesh
    node ids of the finest mesh, one per row of gaps and normals, covering every contact node; more
    nodes are fine) the values are looked up by node id. Without it the rows follow the order of
    the contact nodes: ascending node id among the nodes of the contact facets that stay contact
    nodes (problem.contact.nodes)."""

    gaps: np.ndarray
    normals: np.ndarray
    nodes: Optional[Sequence[int]] = None

    def gaps_and_normals_at(self, nodes: np.ndarray, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        if self.nodes is None:
            return self.gaps_and_normals(x)
        given = node_ids(self.nodes, "NodalObstacle nodes")
        g = np.asarray(self.gaps, dtype=float)
        n = np.asarray(self.normals, dtype=float)
        if g.shape != given.shape or n.shape != (len(given), x.shape[1]):
            raise ValueError(f"NodalObstacle with {len(given)} node ids needs gaps of shape {given.shape} and normals "
                             f"of shape {(len(given), x.shape[1])}, got {g.shape} and {n.shape}")
        rows = rows_for(given, np.asarray(nodes), "NodalObstacle")
        return NodalObstacle(g[rows], n[rows]).gaps_and_normals(x)

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        if self.nodes is not None:
            raise ValueError("a NodalObstacle with node ids is evaluated through gaps_and_normals_at(nodes, points)")
        g = np.asarray(self.gaps, dtype=float)
        n = np.asarray(self.normals, dtype=float)
        if g.shape != (len(x),) or n.shape != x.shape:
            raise ValueError(f"NodalObstacle needs gaps of shape {(len(x),)} and normals of shape {x.shape}, "
                             f"got {g.shape} and {n.shape} (or give their mesh node ids as nodes=)")
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(n))):
            raise ValueError("NodalObstacle gaps and normals must be finite")
        length = np.linalg.norm(n, axis=1)
        if np.any(length == 0):
            raise ValueError("NodalObstacle normals must be non-zero")
        return g, n / length[:, None]
