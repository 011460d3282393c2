"""Loads and elastic supports of a body, assembled on its finest mesh: body forces and gravity,
tractions and normal pressure on tagged facets, point loads at nodes, and springs per unit area on
tagged facets. Everything is in the model's units and refers to the reference configuration."""
from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Sequence, Union

import numpy as np

from .. import _core
from .material import Material, cell_materials

VectorField = Union[Sequence[float], np.ndarray, Callable[[np.ndarray], np.ndarray]]


def tag_tuple(tags, name: str) -> tuple:
    """Facet tags as a tuple of ints: one integer, or a sequence of integers."""
    if isinstance(tags, (bool, np.bool_)) or isinstance(tags, (str, bytes)):
        raise TypeError(f"{name} must be an integer tag or a sequence of integer tags, got {tags!r}")
    if isinstance(tags, (int, np.integer)):
        return (int(tags),)
    try:
        items = list(tags)
    except TypeError:
        raise TypeError(f"{name} must be an integer tag or a sequence of integer tags, got {tags!r}") from None
    out = []
    for t in items:
        if isinstance(t, (bool, np.bool_)) or not isinstance(t, (int, np.integer)):
            raise TypeError(f"{name} must hold integer tags, got {t!r}")
        out.append(int(t))
    return tuple(out)


def _number(v, name: str) -> float:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real) or not np.isfinite(v):
        raise ValueError(f"{name} must be a finite number, got {v!r}")
    return float(v)


def _vector(v, d: int, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float) if not isinstance(v, (str, bytes)) else np.zeros(0)
    if a.shape != (d,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {d} finite numbers, got {v!r}")
    return a


def field_values(value: Optional[VectorField], x: np.ndarray, name: str) -> np.ndarray:
    """A vector field at the points `x` (m, d): a constant vector or a callable x -> (m, d)."""
    d = x.shape[1]
    if value is None:
        return np.zeros((len(x), d))
    v = value(x) if callable(value) else np.broadcast_to(np.asarray(value, dtype=float), (len(x), d))
    v = np.asarray(v, dtype=float)
    if v.shape != (len(x), d):
        raise ValueError(f"{name} must give {d} components per point, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} has non-finite values")
    return np.ascontiguousarray(v)


@dataclass(frozen=True)
class PointLoad:
    """A force (d,) at the mesh node at `point` (d,): the node must lie there (to 1e-9 of the mesh's
    extent), as a gmsh point of the geometry does."""

    point: Sequence[float]
    force: Sequence[float]


def _facets_of(mesh, tag, what: str) -> np.ndarray:
    (tag,) = tag_tuple(tag, f"a {what} tag")
    sel = mesh.facet_tags == tag
    if not np.any(sel):
        raise ValueError(f"no boundary facet carries the {what} tag {tag}")
    return sel


def _per_facet_load(mesh, facets: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The consistent nodal load of a traction constant on each facet (values (f, d)): every facet
    gets its own copies of its nodes, so a field that jumps between facets (a pressure's normal) is
    integrated exactly on each."""
    k, d = facets.shape[1], mesh.dim
    pts = np.ascontiguousarray(mesh.points[facets].reshape(-1, d))
    local = np.arange(len(facets) * k, dtype=np.int64).reshape(-1, k)
    per_node = np.ascontiguousarray(np.repeat(values, k, axis=0))
    f = _core.assemble_facet_load(pts, local, per_node)
    out = np.zeros((mesh.num_points, d))
    np.add.at(out, facets.ravel(), f)
    return out


def point_load_nodes(mesh, point_loads: Sequence[PointLoad]) -> np.ndarray:
    """The mesh node of each point load."""
    x = mesh.points
    extent = float(np.ptp(x, axis=0).max())
    nodes = []
    for k, pl in enumerate(point_loads):
        if not isinstance(pl, PointLoad):
            raise TypeError(f"point_loads must hold PointLoad(point, force), got {pl!r}")
        p = _vector(pl.point, mesh.dim, f"point_loads[{k}].point")
        dist = np.linalg.norm(x - p, axis=1)
        i = int(np.argmin(dist))
        if dist[i] > 1e-9 * extent:
            raise ValueError(f"point_loads[{k}]: no mesh node at {p.tolist()} (the nearest, node {i}, is {dist[i]:.3g} "
                             "away): a point load acts at a node of the coarse mesh")
        nodes.append(i)
    return np.asarray(nodes, np.int64)


def assemble_load(mesh, body_force: Optional[VectorField] = None, traction: Optional[Dict[int, VectorField]] = None,
                  pressure: Optional[Dict[int, float]] = None, point_loads: Sequence[PointLoad] = (),
                  gravity: Optional[Sequence[float]] = None, material=None) -> np.ndarray:
    """The nodal load (n, d) of a body: body force (per volume) and gravity (density x
    acceleration, per region), tractions {tag: vector or callable(x)} and pressures {tag: p} on
    tagged facets (p > 0 pushes into the body: traction -p n with n the outward normal of the
    reference configuration), and point loads."""
    d = mesh.dim
    load = _core.assemble_mass_load(mesh.points, mesh.cells, mesh.cell_type, field_values(body_force, mesh.points, "body_force"))
    if gravity is not None:
        g = _vector(gravity, d, "gravity")
        if material is None:
            raise ValueError("gravity needs the body's material (its density)")
        for mat, sel in cell_materials(mesh, material):
            if mat.density is None:
                raise ValueError("gravity needs a density: give Material(E, nu, density=...)" +
                                 ("" if isinstance(material, Material) else " for every region"))
            if mat.density and np.any(sel):
                rho_g = np.ascontiguousarray(np.broadcast_to(mat.density * g, (mesh.num_points, d)))
                load += _core.assemble_mass_load(mesh.points, np.ascontiguousarray(mesh.cells[sel]), mesh.cell_type, rho_g)
    for tag, value in (traction or {}).items():
        sel = _facets_of(mesh, tag, "traction")
        load += _core.assemble_facet_load(mesh.points, mesh.facets[sel], field_values(value, mesh.points, f"traction[{tag}]"))
    if pressure:
        normals = mesh.facet_normals()
        for tag, p in pressure.items():
            sel = _facets_of(mesh, tag, "pressure")
            p = _number(p, f"pressure[{tag}]")
            load += _per_facet_load(mesh, mesh.facets[sel], -p * normals[sel])
    if point_loads:
        nodes = point_load_nodes(mesh, point_loads)
        for k, (i, pl) in enumerate(zip(nodes, point_loads)):
            load[i] += _vector(pl.force, d, f"point_loads[{k}].force")
    return load


def spring_blocks(mesh, springs: Dict[int, Union[float, Sequence[float]]]) -> np.ndarray:
    """The diagonal blocks (n, d, d) of elastic supports: on the facets of each tag a stiffness per
    unit area k (a number: the same in every direction; or one per global axis), lumped onto the
    nodes (k times the node's share of the facets' measure): a positive diagonal, so every
    smoother and coarse level keeps its meaning."""
    d, n = mesh.dim, mesh.num_points
    share = np.zeros((n, d))
    for tag, k in springs.items():
        sel = _facets_of(mesh, tag, "spring")
        if isinstance(k, numbers.Real) and not isinstance(k, (bool, np.bool_)):
            kv = np.full(d, _number(k, f"springs[{tag}]"))
        else:
            kv = _vector(k, d, f"springs[{tag}]")
        if np.any(kv < 0):
            raise ValueError(f"springs[{tag}]: a spring stiffness must not be negative, got {k!r}")
        share += _core.assemble_facet_load(mesh.points, mesh.facets[sel], np.ones((n, 1))) * kv
    blocks = np.zeros((n, d, d))
    blocks[:, np.arange(d), np.arange(d)] = share
    return blocks
