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

from ..mesh.mesh import facet_area_vectors
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


@dataclass(frozen=True)
class CylinderObstacle:
    """A rigid circular cylinder (3D) of `radius` about the axis through `point` along `axis`,
    infinitely long. inside=False: the body is outside a rigid rod; inside=True: the body is inside a
    rigid bore. (In 2D a cylinder's section is a circle: SphereObstacle.)"""

    point: Tuple[float, ...]
    axis: Tuple[float, ...]
    radius: float
    inside: bool = False

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
        if x.shape[1] != 3:
            raise ValueError("CylinderObstacle is a 3D obstacle (in 2D use SphereObstacle, a circle)")
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"the cylinder's radius must be positive, got {self.radius}")
        a = _unit(self.axis, "the axis")
        p = np.asarray(self.point, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError("the cylinder's point must have 3 finite components")
        v = x - p
        radial = v - (v @ a)[:, None] * a
        rho = np.linalg.norm(radial, axis=1)
        if np.any(rho == 0):
            raise ValueError("a contact node sits on the cylinder's axis: its normal is undefined")
        e = radial / rho[:, None]
        if self.inside:
            return self.radius - rho, e
        return rho - self.radius, -e


class MeshObstacle:
    """A rigid obstacle given by its surface mesh: segments (2D) or triangles (3D), e.g. the
    boundary of a gmsh model of the obstacle (`MeshObstacle.read(path)`). Each contact node is
    projected onto its closest point on the surface; the gap is its distance along the surface's
    normal there. The surface may be open (a rigid floor of any shape) but must be oriented
    consistently; which side is solid is taken from the body: the side the contact nodes are not
    on (`body_side=+1`: the side the facet normals point to, -1: the other, None: decided from the
    nodes)."""

    def __init__(self, points, facets, body_side: Optional[int] = None):
        self.points = np.ascontiguousarray(np.asarray(points, dtype=float))
        self.facets = np.ascontiguousarray(np.asarray(facets, dtype=np.int64))
        d = self.points.shape[1] if self.points.ndim == 2 else 0
        if d not in (2, 3) or self.facets.ndim != 2 or self.facets.shape[1] != d or len(self.facets) == 0:
            raise ValueError("MeshObstacle needs points (n, 2) with segments (m, 2), or points (n, 3) with triangles "
                             f"(m, 3); got points {self.points.shape} and facets {self.facets.shape}")
        if np.any((self.facets < 0) | (self.facets >= len(self.points))) or not np.all(np.isfinite(self.points)):
            raise ValueError("MeshObstacle facets refer to nodes out of range, or its points are not finite")
        if body_side not in (None, 1, -1):
            raise ValueError(f"body_side must be +1, -1 or None, got {body_side!r}")
        n = facet_area_vectors(self.points, self.facets)
        length = np.linalg.norm(n, axis=1)
        if np.any(length == 0):
            raise ValueError(f"MeshObstacle facet {int(np.argmax(length == 0))} is degenerate")
        self.normals = n / length[:, None]
        self.body_side = body_side

    @classmethod
    def read(cls, path, body_side: Optional[int] = None) -> "MeshObstacle":
        """The surface of anything meshio reads: its lines (2D: the z coordinate must be 0) or
        triangles (quads split in two)."""
        import meshio

        m = meshio.read(path)
        tri = [b.data for b in m.cells if b.type == "triangle"]
        quad = [b.data for b in m.cells if b.type == "quad"]
        if tri or quad:
            facets = np.vstack(tri + [q[:, [0, 1, 2]] for q in quad] + [q[:, [0, 2, 3]] for q in quad])
            return cls(m.points[:, :3], facets, body_side)
        lines = [b.data for b in m.cells if b.type == "line"]
        if not lines:
            raise ValueError(f"{path} holds no surface of an obstacle (lines in 2D, triangles or quads in 3D)")
        pts = m.points
        if pts.shape[1] == 3 and np.any(pts[:, 2] != 0):
            raise ValueError(f"{path}: a 2D obstacle's lines need z = 0")
        return cls(pts[:, :2], np.vstack(lines), body_side)

    def _closest(self, x: np.ndarray):
        """(closest points (m, d), the facet of each) by a search over the facets whose centroids
        are nearest (enough of them to hold the closest facet of a reasonably graded surface)."""
        from scipy.spatial import cKDTree

        X = self.points[self.facets]
        centroid = X.mean(axis=1)
        k = min(len(self.facets), 16)
        _, cand = cKDTree(centroid).query(x, k=k)
        cand = cand.reshape(len(x), k)
        best = np.full(len(x), np.inf)
        point = np.zeros_like(x)
        facet = np.zeros(len(x), np.int64)
        for j in range(k):
            f = cand[:, j]
            c = _closest_on_segment(x, X[f, 0], X[f, 1]) if x.shape[1] == 2 else _closest_on_triangle(x, X[f])
            dist = np.linalg.norm(x - c, axis=1)
            better = dist < best
            best[better], point[better], facet[better] = dist[better], c[better], f[better]
        return point, facet

    def gaps_and_normals(self, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(gaps (m,), normals (m, d)) of the points `x` (m, d): distance to the obstacle along its normal and the body's outward normal there."""
        return self.gaps_and_normals_facing(x, None)

    def gaps_and_normals_facing(self, x: np.ndarray, body_normals: Optional[np.ndarray]):
        """gaps_and_normals of the points `x` of a body whose outward normals there are
        `body_normals` (None: unknown). The solid side, unless body_side fixes it: where the nodes
        lie off the surface, the side they are not on; where they lie on it, the side their
        outward normals point to."""
        if x.shape[1] != self.points.shape[1]:
            raise ValueError(f"a {self.points.shape[1]}D obstacle surface for a {x.shape[1]}D body")
        c, f = self._closest(x)
        nf = self.normals[f]
        signed = np.einsum("ij,ij->i", x - c, nf)           # > 0: the node on the side nf points to
        side = self.body_side
        if side is None:
            size = float(np.ptp(self.points, axis=0).max())
            off = np.abs(signed) > 1e-9 * size
            if body_normals is not None and not np.any(off):
                side = 1 if np.sum(np.einsum("ij,ij->i", nf, body_normals)) <= 0 else -1
            else:
                side = 1 if np.sum(signed[off]) >= 0 else -1
        n = -side * nf                                      # from the body into the obstacle
        return side * signed, n


def _closest_on_segment(x, a, b):
    t = b - a
    s = np.clip(np.einsum("ij,ij->i", x - a, t) / np.einsum("ij,ij->i", t, t), 0.0, 1.0)
    return a + s[:, None] * t


def _closest_on_triangle(p, T):
    """The closest points of the triangles T (m, 3, 3) to the points p (m, 3) (Ericson, Real-Time
    Collision Detection, 5.1.5), vectorized over the pairs."""
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    out = np.empty_like(p)
    done = np.zeros(len(p), bool)

    def put(mask, value):
        nonlocal done
        m = mask & ~done
        out[m] = value[m]
        done |= m

    put((d1 <= 0) & (d2 <= 0), a)
    put((d3 >= 0) & (d4 <= d3), b)
    with np.errstate(divide="ignore", invalid="ignore"):
        put((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + (d1 / (d1 - d3))[:, None] * ab)
        put((d6 >= 0) & (d5 <= d6), c)
        put((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + (d2 / (d2 - d6))[:, None] * ac)
        put((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), b + ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None] * (c - b))
        denom = 1.0 / (va + vb + vc)
        v, w = vb * denom, vc * denom
        put(np.ones(len(p), bool), a + v[:, None] * ab + w[:, None] * ac)
    return out
