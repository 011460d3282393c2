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

from ..model.nodal import node_ids, rows_for


@dataclass(frozen=True)
class PlaneObstacle:
    """The half space {x : (x - point) . normal >= 0} is the obstacle; `normal` points from the
    body into the obstacle (for the Hertz benchmark: point (0, 0), normal (0, -1))."""

    point: Tuple[float, ...]
    normal: Tuple[float, ...]

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
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
        """gaps_and_normals of the given nodes (their ids and points)."""
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
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
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


# -- curved obstacles ---------------------------------------------------------------------------
# Gaps and normals by closest-point projection onto the obstacle surface: n is the unit vector from
# the node to its closest point (the gradient of the distance), g the signed distance. A node that
# starts inside the obstacle has g < 0 and n pointing on into it, away from its closest point: u . n
# <= g then moves it back out by at least |g|. Closest-point rather than the body's own normal because it is defined for every
# node (the body's normal is not, at rims and edges) and because it is the obstacle that resists: in
# the cork example the body's normal is radial, and only the tilted normal of the conical neck makes
# an axial push meet resistance. For a node on the surface (g = 0) the surface normal is used.

def _unit(v, name):
    v = np.asarray(v, dtype=float)
    length = np.linalg.norm(v)
    if v.shape != (3,) or not np.isfinite(length) or length == 0:
        raise ValueError(f"{name} must be a finite non-zero 3-vector")
    return v / length


@dataclass(frozen=True)
class SphereObstacle:
    """A rigid sphere (center, radius). inside=False: the body is outside a rigid ball (the ball is
    the obstacle); inside=True: the body is inside a spherical cavity (everything outside the
    sphere is the obstacle)."""

    center: Tuple[float, ...]
    radius: float
    inside: bool = False

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
        c = np.asarray(self.center, dtype=float)
        if c.shape != (x.shape[1],) or not np.all(np.isfinite(c)):
            raise ValueError(f"the sphere's centre must have {x.shape[1]} finite components")
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"the sphere's radius must be positive, got {self.radius}")
        v = x - c
        r = np.linalg.norm(v, axis=1)
        if np.any(r == 0):
            raise ValueError("a contact node sits at the sphere's centre: its normal is undefined")
        e = v / r[:, None]
        if self.inside:
            return self.radius - r, e
        return r - self.radius, -e


@dataclass(frozen=True)
class RevolutionObstacle:
    """The rigid wall of a surface of revolution about the axis through `point` along `axis`, with
    radius profile r(z) piecewise linear through (z[i], r[i]) (z increasing along the axis,
    constant beyond the ends); the body is inside (a bottle neck: a cylinder with a conical
    narrowing is three profile points). Closest-point gaps and normals, computed exactly in the
    meridian half-plane of each node."""

    z: Tuple[float, ...]
    r: Tuple[float, ...]
    point: Tuple[float, ...] = (0.0, 0.0, 0.0)
    axis: Tuple[float, ...] = (0.0, 0.0, 1.0)

    def _profile(self):
        z, r = np.asarray(self.z, dtype=float), np.asarray(self.r, dtype=float)
        if z.ndim != 1 or z.shape != r.shape or len(z) < 1:
            raise ValueError("the radius profile needs matching 1D sequences z and r with at least one point")
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(r))) or np.any(r <= 0):
            raise ValueError("the radius profile must be finite with positive radii")
        if np.any(np.diff(z) <= 0):
            raise ValueError("the profile's z values must increase strictly")
        return z, r

    def radius(self, zeta: np.ndarray) -> np.ndarray:
        """The radius of the surface of revolution at the axial coordinates `zeta`."""
        z, r = self._profile()
        return np.interp(zeta, z, r)

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
        if x.shape[1] != 3:
            raise ValueError("a surface of revolution is a 3D obstacle")
        z, r = self._profile()
        a = _unit(self.axis, "the axis")
        p = np.asarray(self.point, dtype=float)
        v = x - p
        zeta = v @ a
        radial = v - zeta[:, None] * a
        rho = np.linalg.norm(radial, axis=1)
        if np.any(rho == 0):
            raise ValueError("a contact node sits on the axis of the surface of revolution: its normal is undefined")
        e_rho = radial / rho[:, None]
        # the meridian polyline, extended far beyond its ends with the end radii
        span = max(float(z[-1] - z[0]), float(r.max()), float(np.abs(zeta).max()), 1.0)
        Z = np.r_[min(z[0], zeta.min()) - 10 * span, z, max(z[-1], zeta.max()) + 10 * span]
        Rr = np.r_[r[0], r, r[-1]]
        A = np.c_[Rr[:-1], Z[:-1]]
        T = np.c_[Rr[1:], Z[1:]] - A  # segment vectors in (rho, zeta)
        q = np.c_[rho, zeta]
        s = np.clip(np.einsum("nsi,si->ns", q[:, None, :] - A[None], T) / np.einsum("si,si->s", T, T), 0, 1)
        foot = A[None] + s[..., None] * T[None]
        dist = np.linalg.norm(q[:, None, :] - foot, axis=2)
        k = np.argmin(dist, axis=1)
        idx = np.arange(len(x))
        d, f = dist[idx, k], foot[idx, k]
        inside = rho < np.interp(zeta, z, r)
        # the outward normal of the closest segment (positive radial part), for nodes on the wall
        seg_n = np.c_[T[k, 1], -T[k, 0]]
        seg_n /= np.linalg.norm(seg_n, axis=1)[:, None]
        seg_n *= np.sign(seg_n[:, 0])[:, None]
        scale = max(float(r.max()), 1e-300)
        on = d <= 1e-12 * scale
        sign = np.where(inside, 1.0, -1.0)
        m = np.where(on[:, None], seg_n, sign[:, None] * (f - q) / np.where(on, 1.0, d)[:, None])
        normals = m[:, :1] * e_rho + m[:, 1:] * a
        return np.where(on, 0.0, sign * d), normals / np.linalg.norm(normals, axis=1)[:, None]
