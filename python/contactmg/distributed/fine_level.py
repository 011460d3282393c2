"""One rank's fine level of a distributed problem: the stiffness, load, Dirichlet data and contact
nodes of its local cells (owned and ghost layer), in the form of the serial Problem.

An owned node has every cell around it locally, so its row of the matrix and of the load is the
serial one. What a rank may not see for a ghost node (a Dirichlet facet, a contact facet, the facets
that weigh a Tresca bound) its owner sees: the Dirichlet data and the contact data of every node are
taken from the owner before the level is built, so that an owned row reads its ghost neighbours with
their true boundary conditions and in their contact frames."""
from __future__ import annotations

from types import SimpleNamespace
from typing import Optional, Sequence

import numpy as np

from .. import _core
from ..mesh.mesh import FACET_NODES, Mesh
from ..model.friction import Coulomb, Frictionless, Tresca
from ..model.loads import assemble_load
from ..model.material import Material
from ..model.problem import ContactBoundary, Dirichlet, Problem, dirichlet_arrays


def local_mesh(level, cell_type: str) -> Mesh:
    """The local cells of a LocalLevel as a Mesh (its facets: the physical boundary facets of the
    local cells with their tags). Trusted, as the serial hierarchy trusts its refined levels: the
    cells and facets are the core's refinement of the validated coarse mesh (or its own cells), a
    subset of the serial level's; the Python validation took 2.0 of the 2.1 s of the fine level's
    set-up on the Hertz half disk at level 7."""
    facets = np.asarray(level.facets, np.int64)
    if not facets.size:  # a rank whose cells reach no boundary
        facets = np.zeros((0, FACET_NODES[cell_type]), np.int64)
    return Mesh._trusted(np.ascontiguousarray(level.points, float), np.ascontiguousarray(level.cells, np.int64), cell_type,
                         np.ascontiguousarray(facets), np.ascontiguousarray(level.facet_tags, np.int64))


def _owners_values(level, values: np.ndarray) -> np.ndarray:
    """`values` (rows = local nodes) with every ghost row replaced by its owner's."""
    v = np.ascontiguousarray(values, dtype=float).copy()
    if level.halo is not None:
        level.halo.update(v)
    return v


def _contact_boundary(mesh: Mesh, fixed, fixed_values, tags, obstacle) -> ContactBoundary:
    """The serial Problem's contact boundary of the local facets tagged `tags` (empty where this rank
    has none of them)."""
    d = mesh.dim
    if not len(tags) or not np.any(np.isin(mesh.facet_tags, list(tags))):
        return ContactBoundary(np.zeros(0, np.int64), np.zeros((0, d)), np.zeros(0), np.zeros(0),
                               facets=np.zeros((0, mesh.facets.shape[1]), np.int64))
    view = SimpleNamespace(mesh=mesh, fixed=fixed, fixed_values=fixed_values)
    # every local contact node fixed: none here (whether the whole boundary is empty, the ranks decide together)
    return Problem._contact_boundary(view, tags, obstacle, allow_empty=True)


def _local_dirichlet(mesh: Mesh, dirichlet: Sequence[Dirichlet]):
    """dirichlet_arrays of the conditions whose tags this rank's facets carry; and per condition
    whether they do (a tag no rank has is an error of the description, decided by all ranks)."""
    found = np.array([len(mesh.boundary_nodes(bc.tags)) > 0 for bc in dirichlet], bool)
    fixed, values = dirichlet_arrays(mesh, [bc for bc, f in zip(dirichlet, found) if f])
    return fixed, values, found


class LocalFine:
    """The fine level of one rank: `core` (the core's LocalContactLevel: the matrix in the contact
    frames with the Dirichlet dofs eliminated, the load, the contact nodes) and the arrays the cycle
    needs beside it."""

    def __init__(self, level, cell_type: str, material: Material, dirichlet: Sequence[Dirichlet],
                 contact_tags: Sequence[int], obstacle, friction, body_force=None, traction=None, pressure=None,
                 gravity=None):
        mesh = local_mesh(level, cell_type)
        d = self.d = mesh.dim
        n = mesh.num_points
        self.level, self.mesh, self.material = level, mesh, material
        self.law = "linear" if not len(contact_tags) else friction.law
        A = _core.assemble_elasticity(mesh.points, mesh.cells, mesh.cell_type, material.E, material.nu)
        self.canonical_load = assemble_load(mesh, body_force, traction, pressure, (), gravity, material)
        fixed, values, self.found_dirichlet = _local_dirichlet(mesh, dirichlet)
        both = _owners_values(level, np.hstack([fixed.astype(float), values]))
        self.fixed = both[:, :d] > 0.5
        self.fixed_values = np.ascontiguousarray(both[:, d:])
        contact = _contact_boundary(mesh, self.fixed, self.fixed_values, contact_tags, obstacle)
        # whether a local facet carries the contact tags (with no contact node on any rank: a tag no
        # rank has, or a boundary that Dirichlet data fixes everywhere)
        self.found_contact = bool(len(contact_tags)) and bool(np.any(np.isin(mesh.facet_tags, list(contact_tags))))
        # (a bound given per node names global node ids)
        coef = friction.coefficients(level.gid[contact.nodes], contact.measure) if len(contact.nodes) else np.zeros(0)
        # per node: is it a contact node, gap, normal, coefficient -- the owner's
        table = np.zeros((n, 4 + d))
        table[contact.nodes, 0] = 1.0
        table[contact.nodes, 1] = contact.gaps
        table[contact.nodes, 2] = coef
        table[contact.nodes, 3] = contact.measure
        table[contact.nodes, 4:] = contact.normals
        table = _owners_values(level, table)
        self.contact_nodes = np.flatnonzero(table[:, 0] > 0.5).astype(np.int64)
        self.gaps = np.ascontiguousarray(table[self.contact_nodes, 1])
        self.coefficients = np.ascontiguousarray(table[self.contact_nodes, 2])
        self.measure = np.ascontiguousarray(table[self.contact_nodes, 3])
        self.normals = np.ascontiguousarray(table[self.contact_nodes, 4:])
        cls = _core.LocalContactLevel2D if d == 2 else _core.LocalContactLevel3D
        self.core = cls(A, self.canonical_load, self.fixed.astype(np.uint8), self.fixed_values, self.contact_nodes,
                        self.normals, self.gaps, self.coefficients, self.law)
        owned = level.owner == level.rank
        self.owned_contacts = np.flatnonzero(owned[self.contact_nodes]).astype(np.int64)
        self.frames = self.core.frames()


def check_description(material, friction, point_loads=(), springs=None) -> None:
    """What the distributed solve takes: one material, no point loads or springs, frictionless,
    Tresca or Coulomb contact. Raises a ValueError saying what is not distributed yet."""
    if not isinstance(material, Material):
        raise ValueError("materials per region are not distributed yet: give one Material, or solve on one rank")
    if point_loads:
        raise ValueError("point loads are not distributed yet: solve on one rank")
    if springs:
        raise ValueError("elastic supports (springs) are not distributed yet: solve on one rank")
    if friction is not None and not isinstance(friction, (Frictionless, Tresca, Coulomb)):
        raise TypeError("friction must be Frictionless(), Tresca(bound) or Coulomb(coefficient)")
