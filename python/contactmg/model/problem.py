"""The description of a contact problem: N >= 1 elastic bodies (mesh hierarchy, material, Dirichlet
data, loads), the rigid obstacle of a body's contact facets, the body-to-body contact pairs and the
friction law. Assembled once; no solver lives here (see contactmg.solve.solver.Solver).

Several bodies are coupled through the dual mortar basis transformation of Wohlmuth & Krause (2003).
The bodies are assembled one by one into a block-diagonal A. Each contact pair couples the nonmortar
boundary of one body with the mortar boundary of another (mortar.py). The change of basis u = T w,
T = I + N (N = D^{-1} M on the nonmortar contact rows and mortar columns of every pair), makes the
nonmortar unknowns the relative displacements w_p = u_p - (D^{-1} M u_m)_p, and the coupled
conditions nodal: the core then solves T^T A T, T^T f with its own nodal solvers, truncation and
monotone multigrid, in the nodal frames of the nonmortar normals. T^{-1} = I - N (N^2 = 0: no node is
both nonmortar and mortar), so the fine prolongation T^{-1} P is again a scalar interpolation, and
each body keeps its own coarse levels, coupled only through the transformed fine level. The friction
law acts on the tangential part of w: the relative tangential displacement.
"""
from __future__ import annotations

import numbers
import time
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from .. import _core
from ..mesh.hierarchy import MeshHierarchy, Transfer
from ..mesh.mesh import Mesh, connected_components, facet_area_vectors
from .frames import contact_frames
from .friction import Coulomb, Frictionless, Tresca
from .loads import PointLoad, VectorField, assemble_load, field_values, spring_blocks, tag_tuple
from .material import Material, Materials, check_materials, core_moduli
from .rigid_motion import FreeMotion, check_held, check_held_by_contact, free_modes

if TYPE_CHECKING:
    from .mortar import MortarCoupling

@dataclass(frozen=True)
class Dirichlet:
    """Prescribed displacement on the nodes of the boundary facets with the given tags (one
    integer or a sequence): a constant vector (a component given as None stays free) or a callable
    x (m, d) -> (m, d) values, which fixes every component."""

    tags: Sequence[int]
    value: Union[Sequence[Optional[float]], Callable[[np.ndarray], np.ndarray]]

    def __post_init__(self):
        object.__setattr__(self, "tags", tag_tuple(self.tags, "Dirichlet tags"))


@dataclass
class ContactBoundary:
    """Contact nodes of the finest mesh (ascending node id) with their outward normals, gaps,
    lumped boundary measure (integral of the hat function over the contact boundary), frames
    (nc, d, d; columns n, t(, s)) and the contact facets they come from."""

    nodes: np.ndarray
    normals: np.ndarray
    gaps: np.ndarray
    measure: np.ndarray
    frames: Optional[np.ndarray] = None
    facets: Optional[np.ndarray] = None

    def __post_init__(self):
        if self.frames is None:
            self.frames = contact_frames(self.normals)


def dirichlet_arrays(mesh, dirichlet: Sequence[Dirichlet]):
    """(fixed (n, d) uint8, fixed_values (n, d)) of a sequence of Dirichlet conditions."""
    d, n = mesh.dim, mesh.num_points
    fixed = np.zeros((n, d), dtype=np.uint8)
    values = np.zeros((n, d))
    for bc in dirichlet:
        nodes = mesh.boundary_nodes(bc.tags)
        if len(nodes) == 0:
            raise ValueError(f"no boundary facet carries the Dirichlet tags {list(bc.tags)}")
        if callable(bc.value):
            fixed[nodes] = 1
            values[nodes] = field_values(bc.value, mesh.points[nodes], "Dirichlet value")
            continue
        if len(bc.value) != d:
            raise ValueError(f"a Dirichlet value needs {d} components (None for free), got {len(bc.value)}")
        for a, v in enumerate(bc.value):
            if v is not None:
                if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real) or not np.isfinite(v):
                    raise ValueError(f"Dirichlet values must be finite numbers (None for free), got {v!r}")
                fixed[nodes, a] = 1
                values[nodes, a] = v
    return fixed, values




@dataclass
class Body:
    """One elastic body: its mesh hierarchy; its material (a Material, or {region tag: Material}
    for a mesh of several regions, the cell tags of read_mesh); Dirichlet data (a sequence of
    Dirichlet); the facet tags that may touch the problem's rigid obstacle (`contact_tags`); loads:
    a body force per volume, gravity (an acceleration vector; the materials give the density),
    tractions {tag: vector or callable(x)}, normal pressures {tag: p} (p > 0 pushes into the body),
    point loads (PointLoad); and elastic supports {tag: stiffness per unit area} (a number, or one
    per global axis)."""

    hierarchy: MeshHierarchy
    material: Materials
    dirichlet: Sequence[Dirichlet] = ()
    contact_tags: Sequence[int] = ()
    body_force: Optional[VectorField] = None
    traction: Optional[Dict[int, VectorField]] = None
    pressure: Optional[Dict[int, float]] = None
    springs: Optional[Dict[int, Union[float, Sequence[float]]]] = None
    point_loads: Optional[Sequence[PointLoad]] = ()
    gravity: Optional[Sequence[float]] = None

    def __post_init__(self):
        if not isinstance(self.hierarchy, MeshHierarchy):
            raise TypeError("hierarchy must be a MeshHierarchy")
        if not isinstance(self.material, (Material, dict)):
            raise TypeError("material must be a Material or a dict {region tag: Material}")
        check_materials(self.hierarchy.finest, self.material)
        for name in ("traction", "pressure", "springs"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, dict):
                raise TypeError(f"{name} must be a dict {{facet tag: value}}, got {type(v).__name__}")
        # None means no point loads, as it means no load for every other optional load
        if self.point_loads is None:
            self.point_loads = []
        elif isinstance(self.point_loads, PointLoad):
            self.point_loads = [self.point_loads]
        elif isinstance(self.point_loads, (str, bytes, dict)) or not hasattr(self.point_loads, "__iter__"):
            raise TypeError("point_loads must be a PointLoad or a sequence of PointLoad (None: no point loads), "
                            f"got {type(self.point_loads).__name__}")
        else:
            self.point_loads = list(self.point_loads)
        dirichlet = [self.dirichlet] if isinstance(self.dirichlet, Dirichlet) else list(self.dirichlet)
        for bc in dirichlet:
            if not isinstance(bc, Dirichlet):
                raise TypeError(f"dirichlet must be a sequence of Dirichlet(tags, value), got a {type(bc).__name__}")
            if not callable(bc.value) and (np.ndim(bc.value) != 1 or isinstance(bc.value, (str, bytes))):
                raise TypeError("a Dirichlet value must be a vector (None for a free component) or a callable, "
                                f"got {bc.value!r}")
        self.dirichlet = dirichlet
        self.contact_tags = tag_tuple(self.contact_tags, "contact_tags")


@dataclass
class ContactPair:
    """Body `nonmortar` (the slave side, carrying the multiplier) against body `mortar` (the master
    side), on the facets with the given tags; `region(midpoints) -> bool` restricts the nonmortar
    facets (the possible contact zone); `search`: how far along its normal a nonmortar point looks
    for the mortar boundary."""

    nonmortar: int
    mortar: int
    nonmortar_tags: Sequence[int]
    mortar_tags: Sequence[int]
    search: float
    region: Optional[Callable[[np.ndarray], np.ndarray]] = None


@dataclass(frozen=True)
class ObstacleContact:
    """Body `body` (its index in the problem) may touch the rigid `obstacle` with its facets of the
    given tags. A body may touch several obstacles (one ObstacleContact each); a node that two of
    them claim takes the one it is nearer to. The obstacle's normal points from the body into the
    obstacle (away from the body; the opposite of an Abaqus rigid surface's normal): one given the
    other way round is refused. Nodes that start inside the obstacle deeper than the size of their
    contact facets are reported (a UserWarning) unless `allow_penetration` (an intended
    interference fit); the solve pushes them out onto the obstacle."""

    body: int
    tags: Sequence[int]
    obstacle: object
    allow_penetration: bool = False

    def __post_init__(self):
        if isinstance(self.body, (bool, np.bool_)) or not isinstance(self.body, (int, np.integer)):
            raise TypeError(f"ObstacleContact body must be the index of a body, got {self.body!r}")
        object.__setattr__(self, "tags", tag_tuple(self.tags, "ObstacleContact tags"))
        if not self.tags:
            raise ValueError("an ObstacleContact needs at least one facet tag")
        if not callable(getattr(self.obstacle, "gaps_and_normals", None)) and \
                not callable(getattr(self.obstacle, "gaps_and_normals_at", None)):
            raise TypeError("obstacle must be a PlaneObstacle, SphereObstacle, RevolutionObstacle, NodalObstacle or an "
                            f"object with gaps_and_normals(points), got {type(self.obstacle).__name__}")


class Problem:
    """Linear elasticity of one or more bodies with contact and friction: the description.

    `bodies`: one Body or a sequence of them. One body: contact on its `contact_tags` facets against
    the rigid `obstacle` (without contact tags: a linear elasticity problem). Several bodies: contact
    through the mortar `pairs` (ContactPair); the displacement of results is the canonical u = T w on
    the union mesh (`mesh`, `body_id` per node), the contact quantities those of the nonmortar nodes
    of all pairs (`pair_of_contact[c]`: the pair of contact node c). `friction`: Frictionless() (the
    default), Tresca(bound) or Coulomb(F). `tied_correction` (several bodies): after each coarse
    correction of "nmg" and "fixed-point", a second one without bounds in the space where every
    contact dof is frozen: it moves touching bodies together (0009-tied-correction).

    Read-only facts: mesh, bodies, hierarchy, material, contact, friction, law, coefficients, load,
    fixed, fixed_values, transfers, rotated_frames(). Solving: contactmg.Solver(problem, options), or
    problem.solve(...) through the Solver the problem keeps (problem.solver)."""

    # The SolverOptions that problem.solve starts from when it is given none (None: the defaults);
    # the description does not use it.
    default_options = None

    def __init__(self, bodies, obstacle=None, friction=None, pairs=None, tied_correction: bool = True,
                 contacts=None, *, _part_of_many: bool = False):
        t0 = time.perf_counter()
        single = isinstance(bodies, Body)
        bodies = [bodies] if single else bodies
        try:
            bodies = list(bodies)
        except TypeError:
            raise TypeError(f"bodies must be a Body or a sequence of Body, got {type(bodies).__name__}") from None
        if not bodies or not all(isinstance(b, Body) for b in bodies):
            raise TypeError("bodies must be a Body or a non-empty sequence of Body")
        friction = Frictionless() if friction is None else friction
        if not isinstance(friction, (Frictionless, Tresca, Coulomb)):
            raise TypeError("friction must be Frictionless(), Tresca(bound) or Coulomb(F)")
        if not isinstance(tied_correction, (bool, np.bool_)):
            raise TypeError(f"tied_correction must be True or False, got {tied_correction!r}")
        self.bodies, self.friction = bodies, friction
        self.benchmark: Optional[str] = None  # "hertz" for the Hertz benchmark (its zones are centred on x = 0)
        obstacle_contacts, pairs = _split_contacts(bodies, obstacle, pairs, contacts)
        self.obstacle_contacts: List[ObstacleContact] = obstacle_contacts
        if len(bodies) == 1:
            if pairs:
                raise ValueError("pairs couple two bodies of the problem: give several bodies")
            self.pairs: List[ContactPair] = []
            self.tied_correction = False
            self._init_one(bodies[0], obstacle, _part_of_many)
        else:
            if not pairs:
                raise TypeError("several bodies need pairs: a ContactPair or a non-empty sequence of ContactPair")
            self.tied_correction = bool(tied_correction)
            self._init_many(bodies, pairs)
        self.assembly_seconds = time.perf_counter() - t0 + sum(b.hierarchy.build_seconds for b in bodies)

    # -- one body ---------------------------------------------------------------------------------
    def _init_one(self, b: Body, obstacle, part_of_many: bool = False) -> None:
        self.hierarchy, self.material, self.obstacle = b.hierarchy, b.material, obstacle
        mesh = self.mesh = b.hierarchy.finest
        self.springs = b.springs or {}
        self._A = self._assemble_matrix()
        self.load = assemble_load(mesh, b.body_force, b.traction, b.pressure, b.point_loads, b.gravity, b.material)
        self.fixed, self.fixed_values = dirichlet_arrays(mesh, b.dirichlet)
        # how to make load and fixed_values again once released (a value set from outside is kept:
        # the setters clear these)
        self._load_recipe, self._values_recipe = (b.body_force, b.traction, b.pressure, b.point_loads, b.gravity,
                                                  b.material), list(b.dirichlet)
        # a body of several may be held by its pairs: the problem of all of them decides (_init_many)
        floating = self._check_rigid_motion(held_by_contact=bool(self.obstacle_contacts) or part_of_many)
        self.floating = floating
        self.contact, self.contact_source = self._obstacle_boundary(self.obstacle_contacts)
        self.coefficients = friction_coefficients(self.friction, self.contact)
        if not part_of_many:
            self._check_held_by_contact(floating)
        self.body_id = np.zeros(mesh.num_points, np.int32)
        self.transfers = list(b.hierarchy.transfers)
        self._coarsen_below(b.hierarchy)

    # -- several bodies ---------------------------------------------------------------------------
    def _init_many(self, bodies: List[Body], pairs) -> None:
        import scipy.sparse as sp  # only several bodies need it (a one-body process need not load scipy)
        for q in pairs:
            if q.nonmortar == q.mortar or not all(0 <= k < len(bodies) for k in (q.nonmortar, q.mortar)):
                raise ValueError("a contact pair needs two different bodies of the problem")
        dims = {b.hierarchy.finest.dim for b in bodies}
        if len(dims) != 1:
            raise ValueError(f"the bodies need one dimension, got {sorted(dims)}")
        self.pairs, self.obstacle = pairs, None
        # each body on its own: assembly, Dirichlet data; its rigid motions held by its supports, or
        # left to its contacts if it has any (checked for all bodies together below)
        touching = {k for q in pairs for k in (q.nonmortar, q.mortar)} | {oc.body for oc in self.obstacle_contacts}
        self.parts = []
        for k, b in enumerate(bodies):
            try:
                self.parts.append(Problem(Body(b.hierarchy, b.material, b.dirichlet, body_force=b.body_force,
                                               traction=b.traction, pressure=b.pressure, springs=b.springs,
                                               point_loads=b.point_loads, gravity=b.gravity),
                                          _part_of_many=k in touching))
            except ValueError as e:
                raise ValueError(f"body {k}: {e}") from None
        d = dims.pop()
        sizes = [p.mesh.num_points for p in self.parts]
        self.offsets = np.r_[0, np.cumsum(sizes)].astype(np.int64)
        n = int(self.offsets[-1])
        self.mesh = _union_mesh([p.mesh for p in self.parts], self.offsets)
        self.body_id = np.repeat(np.arange(len(bodies)), sizes).astype(np.int32)
        self.hierarchy = bodies[pairs[0].nonmortar].hierarchy  # for reports (kind, levels)
        self.material = bodies[pairs[0].nonmortar].material
        fine = self._level_coupling(None, [p.fixed for p in self.parts])
        self.couplings = fine["couplings"]
        self.N, self.Nk = fine["N"], fine["Nk"]
        Tk = (sp.identity(n * d, format="csr") + self.Nk).tocsr()
        self.A_canonical = sp.block_diag([_bsr(p.A, p.mesh.num_points, d) for p in self.parts], format="csr")
        self.load_canonical = np.vstack([p.load for p in self.parts])
        self._Tk = Tk
        self._A = self._assemble_matrix()
        self.load = (Tk.T @ self.load_canonical.ravel()).reshape(n, d)
        self.fixed = np.vstack([p.fixed for p in self.parts])
        self.fixed_values = np.vstack([p.fixed_values for p in self.parts])
        # the nodes against rigid obstacles: w = u there (no nonmortar node may be one of them)
        nodes, normals, gaps, measure = fine["nodes"], fine["normals"], fine["gaps"], fine["measure"]
        source, facets = fine["pair"], [fine["facets"]]
        for j, oc in enumerate(self.obstacle_contacts):
            part = self.parts[oc.body]
            b = part._contact_boundary(oc.tags, oc.obstacle, oc)
            onodes = b.nodes + self.offsets[oc.body]
            if np.any(np.isin(onodes, fine["nodes"])):
                raise ValueError(f"obstacle contact {j} (body {oc.body}, tags {list(oc.tags)}) shares nodes with the "
                                 "nonmortar side of a contact pair: a node touches one thing (make that body the mortar "
                                 "side, or give the obstacle other facets)")
            nodes, normals = np.r_[nodes, onodes], np.vstack([normals, b.normals])
            gaps, measure = np.r_[gaps, b.gaps], np.r_[measure, b.measure]
            source = np.r_[source, np.full(len(onodes), -1 - j, np.int32)]
            facets.append(b.facets + self.offsets[oc.body])
        nodes, keep = _nearest_obstacle(nodes, gaps, source)
        order = np.argsort(nodes, kind="stable")  # contact nodes ascending
        keep = keep[order]
        nodes, normals = nodes[order], np.ascontiguousarray(normals[keep])
        measure, gaps = measure[keep], np.ascontiguousarray(gaps[keep])
        self.contact_source = source[keep].astype(np.int32)
        self.pair_of_contact = self.contact_source  # pair k >= 0; -1 - j: obstacle contact j
        self.contact = ContactBoundary(nodes.astype(np.int64), normals, gaps, measure,
                                       facets=np.ascontiguousarray(np.vstack(facets)),
                                       frames=contact_frames(normals, self.fixed[nodes]))
        self.coefficients = friction_coefficients(self.friction, self.contact)
        self.transfers = self._transfers()
        self._check_bodies_held()
        self.notes = (tuple(f"body {k}: {note}" for k, part in enumerate(self.parts) for note in part.notes)
                      + tuple(_coupling_notes(self.couplings)))

    @property
    def multibody(self) -> bool:
        """Does the problem couple several bodies (through mortar pairs)?"""
        return len(self.bodies) > 1

    @property
    def pair(self) -> ContactPair:
        """The first (for two bodies: the only) contact pair."""
        return self.pairs[0]

    @property
    def coupling(self) -> MortarCoupling:
        """The fine mortar coupling of the first pair."""
        return self.couplings[0]

    def _check_rigid_motion(self, held_by_contact: bool = False) -> list:
        """The Dirichlet dofs (and springs) must pin every rigid-body motion of every connected
        piece of the body, or (held_by_contact) its contacts must: returns the pieces left to the
        contacts as (nodes, free modes), for _check_held_by_contact."""
        mesh = self.mesh
        x, d = mesh.points, mesh.dim
        fixed = self.fixed.astype(bool)
        if self.springs:  # an elastic support holds the directions it acts in
            blocks = spring_blocks(mesh, self.springs)
            fixed |= blocks[:, np.arange(d), np.arange(d)] > 0
        count, label = self._pieces()
        order = np.argsort(label, kind="stable")
        bounds = np.searchsorted(label[order], np.arange(count + 1))
        floating = []
        for k in range(count):
            nodes = np.sort(order[bounds[k]:bounds[k + 1]])
            if _holds_rigid_motion(x[nodes], fixed[nodes]):
                continue
            if held_by_contact:
                floating.append((nodes, free_modes(x[nodes], fixed[nodes]), k, count))
                continue
            where = "" if count == 1 else (
                f" of piece {k + 1} of the {count} disconnected pieces of the mesh ({len(nodes)} nodes, "
                f"node {int(nodes[0])} at {np.round(x[nodes[0]], 6).tolist()})")
            raise ValueError(f"the Dirichlet conditions{' and springs' if self.springs else ''} leave rigid-body motion"
                             f"{where} free: fix enough displacement components to hold " +
                             ("the body" if count == 1 else "every piece") + " (or let an obstacle hold it)")
        return floating

    def _check_bodies_held(self) -> None:
        """Several bodies: the free rigid motions of every body left to its contacts must be held
        by them, the pairs passing forces between bodies (model/rigid_motion.py)."""
        motions, work, index = [], [], {}
        for k, part in enumerate(self.parts):
            for nodes, modes, piece, count in part.floating:
                name = f"body {k}" if count == 1 else f"piece {piece + 1} of the {count} pieces of body {k}"
                index[(k, piece)] = len(motions)
                motion = FreeMotion(part.mesh.points[nodes], modes, name)
                motions.append(motion)
                work.append(np.einsum("mdk,md->k", motion.at(part.mesh.points[nodes]), part.load[nodes]))
        if not motions:
            return
        piece_of = [part._pieces()[1] for part in self.parts]
        c = self.contact
        body = self.body_id[c.nodes]
        local = c.nodes - self.offsets[body]
        pushed = np.array([index.get((int(b), int(piece_of[b][i])), -1) for b, i in zip(body, local)], int)
        pulled = np.full(len(c.nodes), -1)
        for k, q in enumerate(self.pairs):
            sel = self.contact_source == k
            # the piece of the mortar body that holds the mortar side of the pair
            labels = piece_of[q.mortar][np.unique(self.couplings[k].M.tocsr().indices)]
            piece = int(np.bincount(np.asarray(labels)).argmax())
            pulled[sel] = index.get((q.mortar, piece), -1)
        x = self.mesh.points[c.nodes]
        contacts = []
        for a, b in sorted({(int(a), int(b)) for a, b in zip(pushed, pulled) if a >= 0 or b >= 0}):
            sel = (pushed == a) & (pulled == b)
            contacts.append((x[sel], c.normals[sel], c.frames[sel], self.coefficients[sel], a, b))
        check_held(motions, work, contacts, self.law)

    def _check_held_by_contact(self, floating: list) -> None:
        """Every piece whose supports leave rigid motions free must touch an obstacle that can hold
        them under the load (model/rigid_motion.py): else a ValueError naming the free motion."""
        c, x = self.contact, self.mesh.points
        for nodes, modes, k, count in floating:
            where = "the body" if count == 1 else f"piece {k + 1} of the {count} disconnected pieces of the mesh"
            sel = np.isin(c.nodes, nodes)
            if not np.any(sel):
                raise ValueError(f"the Dirichlet conditions{' and springs' if self.springs else ''} leave rigid-body "
                                 f"motion of {where} free and no contact boundary touches it: fix enough displacement "
                                 "components to hold it")
            rows = np.searchsorted(nodes, c.nodes[sel])
            check_held_by_contact(x[nodes], modes, self.load[nodes], rows, c.normals[sel], c.frames[sel],
                                  self.law, self.coefficients[sel], where)

    def _pieces(self):
        """(count, label) of the connected pieces of the finest mesh, found on the coarsest mesh
        (refinement splits cells and joins nothing) and handed down through the transfers: a
        fine node lies in the piece of its first coarse parent."""
        h = self.hierarchy
        if h.from_fine_mesh:  # no coarse mesh: count on the fine one
            return connected_components(self.mesh.cells, self.mesh.num_points)
        coarse = h.meshes[0]
        count, label = connected_components(coarse.cells, coarse.num_points)
        for t in h.transfers:
            if np.any(np.diff(t.ptr) < 1):  # a node without parents: count on the fine mesh itself
                return connected_components(self.mesh.cells, self.mesh.num_points)
            label = label[t.parent[t.ptr[:-1]]]
        return count, label

    def _obstacle_boundary(self, contacts: Sequence[ObstacleContact]):
        """The contact boundary of one body against its obstacles, and per contact node the index
        of its ObstacleContact as -1 - j."""
        if not contacts:
            return self._contact_boundary((), None), np.zeros(0, np.int32)
        parts = [self._contact_boundary(oc.tags, oc.obstacle, oc) for oc in contacts]
        if len(parts) == 1:
            return parts[0], np.full(len(parts[0].nodes), -1, np.int32)
        nodes = np.concatenate([b.nodes for b in parts])
        gaps = np.concatenate([b.gaps for b in parts])
        source = np.concatenate([np.full(len(b.nodes), -1 - j, np.int32) for j, b in enumerate(parts)])
        nodes, keep = _nearest_obstacle(nodes, gaps, source)
        order = np.argsort(nodes, kind="stable")
        keep = keep[order]
        normals = np.ascontiguousarray(np.vstack([b.normals for b in parts])[keep])
        c = ContactBoundary(nodes[order].astype(np.int64), normals, np.ascontiguousarray(gaps[keep]),
                            np.concatenate([b.measure for b in parts])[keep],
                            facets=np.ascontiguousarray(np.vstack([b.facets for b in parts])),
                            frames=contact_frames(normals, self.fixed[nodes[order]]))
        return c, source[keep]

    def _contact_boundary(self, tags, obstacle, contact: Optional[ObstacleContact] = None,
                          allow_empty: bool = False) -> ContactBoundary:
        """The contact nodes of the facets tagged `tags`: gaps, normals, boundary measure, frames.
        allow_empty: a boundary every node of which is fixed is returned empty rather than refused
        (one rank's part of a distributed mesh, where the ranks decide together)."""
        mesh, d = self.mesh, self.mesh.dim
        if not len(tags):
            return ContactBoundary(np.zeros(0, np.int64), np.zeros((0, d)), np.zeros(0), np.zeros(0),
                                   facets=np.zeros((0, mesh.facets.shape[1]), np.int64))
        sel = np.isin(mesh.facet_tags, list(tags))
        if not np.any(sel):
            raise ValueError(f"no boundary facet carries the contact tags {list(tags)}")
        facets = mesh.facets[sel]
        nodes = np.unique(facets)
        # Dirichlet wins where it fixes every component (e.g. the ends of the Hertz arc on the clamped top edge)
        nodes = nodes[~self.fixed[nodes].all(axis=1)]
        at_nodes = getattr(obstacle, "gaps_and_normals_at", None)
        x = mesh.points[nodes]
        facing = getattr(obstacle, "gaps_and_normals_facing", None)
        if callable(facing):  # an obstacle that takes its solid side from the body (MeshObstacle)
            gaps, normals = facing(x, _body_normals(mesh, facets, nodes)[0])
        else:
            gaps, normals = at_nodes(nodes, x) if callable(at_nodes) else obstacle.gaps_and_normals(x)
        gaps, normals = np.asarray(gaps, dtype=float), np.asarray(normals, dtype=float)
        if gaps.shape != (len(nodes),) or normals.shape != (len(nodes), d):
            raise ValueError(f"the obstacle gave gaps of shape {gaps.shape} and normals of shape {normals.shape} "
                             f"for {len(nodes)} contact nodes")
        if not (np.all(np.isfinite(gaps)) and np.all(np.isfinite(normals))):
            raise ValueError("the obstacle gave non-finite gaps or normals")
        # A node with some fixed components keeps its contact condition in the free directions; one
        # whose normal component is prescribed is no contact node (the core checks it is admissible
        # and refuses a fixed component that is neither normal nor tangential)
        classify = _core.classify_contact_dirichlet_2D if d == 2 else _core.classify_contact_dirichlet_3D
        keep = classify(nodes.astype(np.int64), self.fixed[nodes], self.fixed_values[nodes],
                        np.ascontiguousarray(normals), np.ascontiguousarray(gaps)) < 2
        nodes, gaps, normals = nodes[keep], gaps[keep], normals[keep]
        if len(nodes) == 0:
            if allow_empty:
                return ContactBoundary(np.zeros(0, np.int64), np.zeros((0, d)), np.zeros(0), np.zeros(0),
                                       facets=np.zeros((0, mesh.facets.shape[1]), np.int64))
            raise ValueError(f"the contact boundary is empty: every node of the facets tagged {list(tags)} is fixed by "
                             "Dirichlet data (are the contact tags the Dirichlet tags?)")
        _check_obstacle_placement(mesh, facets, nodes, gaps, normals, tags,
                                  contact is not None and contact.allow_penetration)
        ones = np.ones((mesh.num_points, 1))
        measure = _core.assemble_facet_load(mesh.points, facets, ones)[nodes, 0]
        normals = np.ascontiguousarray(normals)
        return ContactBoundary(nodes.astype(np.int64), normals, np.ascontiguousarray(gaps), measure,
                               facets=np.ascontiguousarray(facets),
                               frames=contact_frames(normals, self.fixed[nodes]))

    def _nonmortar_facet_mask(self, pair: ContactPair, m: Mesh) -> np.ndarray:
        sel = np.isin(m.facet_tags, list(tag_tuple(pair.nonmortar_tags, "nonmortar_tags")))
        if pair.region is not None:
            sel &= np.asarray(pair.region(m.points[m.facets].mean(axis=1)), dtype=bool)
        if not np.any(sel):
            raise ValueError(f"no facet of body {pair.nonmortar} carries the nonmortar tags "
                             f"{list(pair.nonmortar_tags)} (in the region)")
        return sel

    def _level_coupling(self, level: int, held: Sequence[np.ndarray]) -> dict:
        """The pairs' dual mortar couplings on the meshes of `level` (None: each body's finest): N_l (union numbering of that
        level, scalar weights per node pair), its block form Nk_l (the prescribed axes of a node left
        alone) and, per nonmortar node that carries a condition, its union id, normal, gap, measure
        D and pair. `held[body]`: the Dirichlet-prescribed axes of the body's mesh nodes (n, d), or
        (n,) for nodes held in every axis. A nonmortar node prescribed along its normal, or whose
        support faces the mortar side over too little, is taken out by the boundary modification
        of the dual basis (mortar.py); the counts are kept for the notes."""
        import scipy.sparse as sp  # only several bodies need it (a one-body process need not load scipy)

        from .mortar import covers_facets, mortar_coupling_2d
        from .mortar_3d import mortar_coupling_3d
        meshes = [b.hierarchy.finest if level is None or level == b.hierarchy.levels - 1 else b.hierarchy.meshes[level]
                  for b in self.bodies]
        d = meshes[0].dim
        offsets = np.r_[0, np.cumsum([m.num_points for m in meshes])].astype(np.int64)
        n = int(offsets[-1])
        rows, cols, vals, free_rows = [], [], [], []
        out = {k: [] for k in ("nodes", "normals", "gaps", "measure", "pair", "facets")}
        couplings = []
        for k, q in enumerate(self.pairs):
            sm, mm = meshes[q.nonmortar], meshes[q.mortar]
            msel = np.isin(mm.facet_tags, list(tag_tuple(q.mortar_tags, "mortar_tags")))
            if not np.any(msel):
                raise ValueError(f"no facet of body {q.mortar} carries the mortar tags {list(q.mortar_tags)}")
            ssel = self._nonmortar_facet_mask(q, sm)
            fixed = np.asarray(held[q.nonmortar], bool)
            if fixed.ndim == 1:
                fixed = np.repeat(fixed[:, None], d, axis=1)
            c = (mortar_coupling_2d if d == 2 else mortar_coupling_3d)(sm.points, sm.facets[ssel], mm.points,
                                                                       mm.facets[msel], q.search, fixed=fixed)
            couplings.append(c)
            if len(c.nonmortar_nodes) == 0:
                raise ValueError(f"no nonmortar node of contact pair {k} sees the mortar boundary within the search "
                                 "distance (or every one is held by Dirichlet data)")
            nodes = c.nonmortar_nodes + offsets[q.nonmortar]
            # u_p = w_p + (Mhat u_m)_p - (Shat u_s)_p on the node's free axes
            for W, off, sign in ((c.Mhat.tocoo(), offsets[q.mortar], 1.0), (c.Shat.tocoo(), offsets[q.nonmortar], -1.0)):
                rows.append(nodes[W.row])
                cols.append(W.col + off)
                vals.append(sign * W.data)
                free_rows.append(c.free[W.row])
            out["nodes"].append(nodes)
            out["normals"].append(c.normals)
            # the gap between the surfaces the facets approximate where the mortar body's hierarchy knows it
            pm = getattr(self.bodies[q.mortar].hierarchy, "projector", None)
            if covers_facets(pm, mm.points, mm.facets[msel], mm.facet_tags[msel]):
                ps = getattr(self.bodies[q.nonmortar].hierarchy, "projector", None)
                ps = ps if covers_facets(ps, sm.points, sm.facets[ssel], sm.facet_tags[ssel]) else None
                own = _node_tags(c.nonmortar_nodes, sm.facets[ssel], sm.facet_tags[ssel], sm.num_points)
                g = c.true_gaps(sm.points, pm, _facing_tags(c, mm.facets[msel], mm.facet_tags[msel]), ps, own)
            else:
                g = c.gaps(sm.points, mm.points)
            # a gap at the round-off of the geometry is a touching contact: exactly zero (a node left a
            # round-off's room from its bound is not active, and its slack would hold back every
            # coarse correction near it until the smoother closes it)
            size = c.D if d == 2 else np.sqrt(c.D)  # D_p: the measure of the node's support
            g[np.abs(g) <= TOUCHING_GAP * size] = 0.0
            out["gaps"].append(g)
            out["measure"].append(c.D)
            out["pair"].append(np.full(len(nodes), k, np.int32))
            out["facets"].append(sm.facets[ssel] + offsets[q.nonmortar])
        res = {key: np.concatenate(v) for key, v in out.items()}
        if len(np.unique(res["nodes"])) != len(res["nodes"]):
            raise ValueError("a node is a nonmortar node of two contact pairs (pairs must not share nonmortar nodes)")
        r, cl, v, fr = (np.concatenate(x) for x in (rows, cols, vals, free_rows))
        N = sp.csr_matrix((v, (r, cl)), shape=(n, n))
        N.sum_duplicates()
        N.eliminate_zeros()
        # T^{-1} = I - N needs N^2 = 0: no mortar node of one pair is a nonmortar node of another
        if (abs(N) @ abs(N)).nnz:
            raise ValueError("a mortar node of one contact pair is a nonmortar node of another: make that body the "
                             "nonmortar (or the mortar) side of both its pairs")
        # the block form: a node's prescribed axes keep u = w (its Dirichlet value holds for w)
        ax = np.nonzero(fr)
        Nk = sp.csr_matrix((v[ax[0]], (r[ax[0]] * d + ax[1], cl[ax[0]] * d + ax[1])), shape=(n * d, n * d))
        Nk.sum_duplicates()
        Nk.eliminate_zeros()
        res["N"], res["Nk"], res["couplings"] = N, Nk, couplings
        return res

    def _transfers(self):
        """Per level the union of the bodies' prolongations, their own levels and those made below
        their coarse meshes (_coarsen_below): a body with fewer levels than another keeps its
        coarsest level on the levels below it (identity prolongations), so bodies of unequal
        hierarchies (each coarsened from its own fine mesh, or refined a different number of times)
        form one multigrid. On the finest, T^{-1} P = (I - N) P."""
        import scipy.sparse as sp  # only several bodies need it (a one-body process need not load scipy)
        own = [[t.matrix() for t in part.transfers] for part in self.parts]
        levels = max(len(t) for t in own) + 1
        out = []
        for l in range(levels - 1):
            blocks = []
            for part, ts in zip(self.parts, own):
                k = l - (levels - 1 - len(ts))
                if k >= 0:
                    blocks.append(ts[k])
                else:
                    n0 = ts[0].shape[1] if ts else part.mesh.num_points
                    blocks.append(sp.identity(n0, format="csr"))
            P = sp.block_diag(blocks, format="csr")
            if l == levels - 2:
                P = (sp.identity(P.shape[0]) - self.N) @ P
            out.append(Transfer.from_matrix(P))
        return out

    def _assemble_matrix(self):
        """The matrix of the problem's unknowns: one body's stiffness, or T^T A T of the bodies'
        block-diagonal stiffness."""
        if self.multibody:
            return _block_matrix((self._Tk.T @ self.A_canonical @ self._Tk).tocsr(), self.mesh.dim)
        m = self.mesh
        A = _core.assemble_elasticity(m.points, m.cells, m.cell_type, *core_moduli(m, self.material))
        if self.springs:
            A.add_diagonal_blocks(spring_blocks(m, self.springs))
        return A

    def to_canonical(self, w: np.ndarray) -> np.ndarray:
        """The displacement u = T w of the problem's unknowns w (one body: w itself)."""
        if not self.multibody:
            return w
        w = np.asarray(w)
        return w + (self.Nk @ w.ravel()).reshape(w.shape)

    def relative_displacement(self, u: np.ndarray) -> np.ndarray:
        """w = T^{-1} u = u - N u: at a nonmortar node its displacement relative to the mortar side's
        (D^{-1} M u_m, in its free axes); elsewhere u itself."""
        if not self.multibody:
            return u
        u = np.asarray(u)
        return u - (self.Nk @ u.ravel()).reshape(u.shape)

    def canonical_forces(self, f: np.ndarray) -> np.ndarray:
        """Nodal forces (n, d) of the unknowns w as forces on the displacement u: T^{-T} f = f - N^T f
        (one body: f itself)."""
        if not self.multibody:
            return f
        f = np.asarray(f)
        return f - (self.Nk.T @ f.ravel()).reshape(f.shape)

    # The load and the Dirichlet values (n, d): held until a solver has its own copies
    # (release_vectors), then made again from the description when asked for (the same bits: the
    # same assembly and the same Dirichlet data).
    _load: Optional[np.ndarray] = None
    _fixed_values: Optional[np.ndarray] = None
    _load_recipe = None
    _values_recipe = None

    @property
    def load(self) -> np.ndarray:
        """The nodal load (n, d) of the problem's unknowns: one body, that of u; several bodies,
        T^T f of w (load_canonical: f of u)."""
        if self._load is None and self._load_recipe is not None:
            self._load = assemble_load(self.mesh, *self._load_recipe)
        return self._load

    @load.setter
    def load(self, value: np.ndarray) -> None:
        self._load, self._load_recipe = value, None

    @property
    def fixed_values(self) -> np.ndarray:
        """The prescribed displacements (n, d) of the fixed components (`fixed`)."""
        if self._fixed_values is None and self._values_recipe is not None:
            self._fixed_values = dirichlet_arrays(self.mesh, self._values_recipe)[1]
        return self._fixed_values

    @fixed_values.setter
    def fixed_values(self, value: np.ndarray) -> None:
        self._fixed_values, self._values_recipe = value, None

    def release_vectors(self) -> None:
        """Drop the load and the Dirichlet values where they can be made again (see load): a solver
        that holds its own copies frees the memory (0011-memory-release)."""
        if self._load_recipe is not None:
            self._load = None
        if self._values_recipe is not None:
            self._fixed_values = None

    @property
    def A(self):
        """The stiffness matrix of the problem's unknowns (no boundary conditions): one body, that
        of the displacement u; several bodies, T^T A T of the unknowns w = T^{-1} u (relative
        displacements at the nonmortar nodes, see relative_displacement), not the bodies' own
        stiffness of u (A_canonical). A solver may take it over (take_matrix); asking for it again
        assembles it anew."""
        if self._A is None:
            self._A = self._assemble_matrix()
        return self._A

    def take_matrix(self):
        """Hand the assembled matrix over to a solver that keeps it (one fine matrix in memory): one
        body's matrix is released here (`A` assembles it again when asked); the transformed matrix
        of several bodies stays (checks and reports multiply with it). Returns (matrix, taken)."""
        if self.multibody:
            return self.A, False
        A, self._A = self.A, None
        return A, True

    @property
    def setup_seconds(self) -> float:
        """Hierarchy and assembly time (a solver adds its build)."""
        return self.assembly_seconds

    @property
    def law(self) -> str:
        """The contact law the core solves: "linear" without contact nodes, else the friction's."""
        return "linear" if len(self.contact.nodes) == 0 else self.friction.law

    def rotated_frames(self) -> bool:
        """Is some contact frame not a signed permutation of the axes?"""
        if self.law == "linear" or len(self.contact.nodes) == 0:
            return False
        a = np.abs(np.asarray(self.contact.frames, float))
        return bool(np.any(np.minimum(a, np.abs(a - 1.0)) > 1e-12))

    def adaptive_2d(self) -> bool:
        """Is the hierarchy adaptive and the mesh two-dimensional?"""
        return self.hierarchy.kind == "adaptive" and self.mesh.dim == 2

    def coarse_levels_match_meshes(self) -> bool:
        """Are the unknowns of every coarse level the nodes of the hierarchy's mesh of that level
        (not so for several bodies, whose levels are unions, nor below a coarse mesh too large for
        a direct solve)?"""
        return not self.multibody and len(self.transfers) == self.hierarchy.levels - 1

    # notes on what the problem did on its own (read by reports and summaries)
    notes: tuple = ()
    # coarse levels made below the hierarchy's coarse mesh from it (_coarsen_below)
    _levels_below: int = 0

    def coarse_levels_from_mesh(self) -> bool:
        """Whether some coarse levels were made from a mesh alone (geometric coarsening or
        aggregation, not refinement): the hierarchy's own, or those made below its coarse mesh."""
        return bool(self.hierarchy.from_fine_mesh or self._levels_below)

    def _coarsen_below(self, h: MeshHierarchy) -> None:
        """Coarse levels made from the coarse mesh alone by geometric coarsening
        (mesh/coarsening.py), down to a size a direct solve takes at once, where the coarse mesh is
        too large for the coarsest level's direct solve (a fine mesh from a mesher taken as the
        coarse level), or where it is the only level (the sweeps alone contract by little more than
        a Gauss-Seidel iteration's rate); the problem says so (notes, a warning where the user
        gave a coarse mesh)."""
        if h.from_fine_mesh:
            return
        coarse = h.meshes[0]
        dofs = coarse.num_points * coarse.dim
        alone = h.levels == 1
        if dofs <= MAX_COARSEST_DOFS and not alone:
            return
        from ..mesh.coarsening import coarsening_prolongations

        below = coarsening_prolongations(coarse)
        if not below:
            return
        self.transfers = [Transfer.from_matrix(P) for P in below] + self.transfers
        self._levels_below = len(below)
        made = (f"{len(below)} coarser levels were made from it by geometric coarsening, down to "
                f"{below[0].shape[1] * coarse.dim:,} dofs")
        if dofs > MAX_COARSEST_DOFS and not alone:
            note = (f"the coarse mesh has {dofs:,} dofs, more than the coarsest level's direct solve should take "
                    f"({MAX_COARSEST_DOFS:,}): {made}")
            warnings.warn(note, UserWarning, stacklevel=4)
        else:
            note = f"the mesh is the only level of its hierarchy: {made}"
        self.notes = (note,)

    def vector_bytes(self) -> int:
        """Bytes of the problem's vectors now held (load, Dirichlet data, contact boundary, coefficients)."""
        c = self.contact
        arrays = (self._load, self.fixed, self._fixed_values, self.coefficients, c.nodes, c.normals, c.gaps, c.measure,
                  c.frames, c.facets)
        return int(sum(a.nbytes for a in arrays if isinstance(a, np.ndarray)))

    def matrix_bytes(self) -> int:
        """Bytes of an assembled matrix held here (0 once a solver took it over)."""
        return self._A.memory_bytes() if self._A is not None else 0

    def write_vtu(self, path, result) -> None:
        """One VTU file of `result` on the problem's mesh, with a body_id field for several bodies."""
        from ..mesh.io import write_mesh

        data = result.point_data()
        if self.multibody:
            data["body_id"] = self.body_id
        write_mesh(path, self.mesh, point_data=data, cell_data=result.cell_data())

    # -- solving ----------------------------------------------------------------------------------
    # The solve layer sits above this one: these import it when they run, so that importing the
    # description loads no solver.
    @property
    def solver(self):
        """The Solver kept by this problem for problem.solve (built on first use with the problem's
        default options)."""
        from ..solve.options import options_from

        return self._solver_for(options_from(self.default_options))

    def solve(self, method: Optional[str] = None, options=None, *, u0=None, progress=None, reference=None,
              error_reference=None, **option_fields):
        """Solve through the problem's kept Solver (problem.solver) with `options` (a SolverOptions or a
        dict; None: the problem's defaults) and the `option_fields` on top (SolverOptions field names),
        `method` first among them: problem.solve("nmg", tol=1e-10) is
        Solver(problem).solve(options=SolverOptions(method="nmg", tol=1e-10)). A solve that asks for
        other build-time options (local_smoothing, release_hierarchy) builds the kept solver again; the
        kept solver stores its levels for the ordering of problem.default_options (None: coloured). Method "linear" with `reference` (a ContactResult) takes that result's contact state."""
        from ..solve.options import for_method, options_from

        base = options_from(self.default_options if options is None else options)
        opts = for_method(base, base.method if method is None else method, **option_fields)
        solver = self.solver
        if _builds_differently(solver, opts):
            solver = self._solver_for(opts, again=True)
        if opts.method == "linear" and reference is not None:
            return solver.solve_known_state(reference, opts, progress=progress, error_reference=error_reference)
        return solver.solve(u0, options=opts, progress=progress, error_reference=error_reference)

    def _solver_for(self, options, again: bool = False):
        """The kept Solver; built with `options` where there is none yet, where it was built with
        other build-time options than `options` asks for, or where `again`."""
        from ..solve.solver import Solver

        kept = self.__dict__.get("_kept_solver")
        if again or kept is None or _builds_differently(kept, options):
            kept = self.__dict__["_kept_solver"] = Solver(self, options, _kept=True)
        return kept


# Above this many dofs the coarse mesh of a hierarchy is not solved directly: coarser levels go
# below it, down to aggregation.COARSEST_NODES nodes (0027-coarse-level-size: a gmsh mesh of 7,032 dofs
# as the coarse level took 2.98 s, with aggregates below it 0.42 s; the paper's coarsest, 2,286 dofs
# at most, stay as they are).
MAX_COARSEST_DOFS = 4000
# A weighted gap of a contact pair below this fraction of its node's facet size is round-off of the
# geometry (coincident surfaces measured between their projections give 1e-12): a touching contact.
TOUCHING_GAP = 1e-9


def _builds_differently(solver, options) -> bool:
    """Do `options` ask for other build-time options than `solver` was built with?"""
    from ..solve.options import BUILD_FIELDS

    return any(getattr(options, k) is not None and getattr(options, k) != getattr(solver.options, k)
               for k in BUILD_FIELDS)


def _holds_rigid_motion(x: np.ndarray, fixed: np.ndarray) -> bool:
    """Do the fixed components `fixed` (m, d) of the nodes at `x` (m, d) pin every rigid motion?"""
    d = x.shape[1]
    if not fixed.any():
        return False
    x = x - x.mean(axis=0)
    modes = [np.eye(d)[a][None, :].repeat(len(x), 0) for a in range(d)]
    pairs = [(0, 1)] if d == 2 else [(0, 1), (1, 2), (0, 2)]
    for i, j in pairs:
        r = np.zeros_like(x)
        r[:, i], r[:, j] = -x[:, j], x[:, i]
        modes.append(r)
    R = np.stack([m[fixed] for m in modes], axis=1)
    return np.linalg.matrix_rank(R, tol=1e-10 * max(1.0, np.abs(R).max())) == len(modes)


def friction_coefficients(friction, contact: ContactBoundary) -> np.ndarray:
    """The friction law's coefficients at the contact nodes."""
    return friction.coefficients(contact.nodes, contact.measure)


def _bsr(A, n: int, d: int):
    import scipy.sparse as sp  # only several bodies need it (a one-body process need not load scipy)
    return sp.bsr_matrix((np.asarray(A.data), np.asarray(A.indices), np.asarray(A.indptr)), shape=(n * d, n * d))


def _block_matrix(A, d: int):
    import scipy.sparse as sp  # only several bodies need it (a one-body process need not load scipy)
    B = sp.bsr_matrix(A, blocksize=(d, d))
    B.sort_indices()
    cls = _core.BlockMatrix2D if d == 2 else _core.BlockMatrix3D
    n = B.shape[0] // d
    return cls(n, n, B.indptr.astype(np.int64), B.indices.astype(np.int64), np.ascontiguousarray(B.data))


def _union_mesh(meshes: Sequence[Mesh], offsets: np.ndarray) -> Mesh:
    cell_types = {m.cell_type for m in meshes}
    if len(cell_types) != 1:
        raise ValueError(f"the bodies need one cell type for one output mesh, got {sorted(cell_types)}")
    return Mesh._trusted(np.vstack([m.points for m in meshes]),
                         np.vstack([m.cells + o for m, o in zip(meshes, offsets)]), meshes[0].cell_type,
                         np.vstack([m.facets + o for m, o in zip(meshes, offsets)]),
                         np.concatenate([m.facet_tags for m in meshes]),
                         np.concatenate([m.cell_tags for m in meshes]))


def _items(value, types: tuple, message: str) -> list:
    """None, one item of `types` or a sequence of them, as a list (TypeError `message` otherwise)."""
    if value is None:
        return []
    if isinstance(value, types):
        return [value]
    try:
        items = list(value)
    except TypeError:
        raise TypeError(message) from None
    for item in items:
        if not isinstance(item, types):
            raise TypeError(f"{message}, got {type(item).__name__}")
    return items


def _node_tags(nodes: np.ndarray, facets: np.ndarray, tags: np.ndarray, n: int) -> np.ndarray:
    """The tag of a facet (of `facets`, tagged `tags`) that holds each of `nodes` (ids < n)."""
    tag_of_node = np.full(n, tags[0] if len(tags) else 0)
    for k in range(facets.shape[1]):
        tag_of_node[facets[:, k]] = tags
    return tag_of_node[nodes]


def _facing_tags(c, facets: np.ndarray, tags: np.ndarray) -> np.ndarray:
    """Per kept nonmortar node of coupling c the tag of a mortar facet it faces: one holding the
    mortar node of its largest weight in M."""
    M = c.M.tocsr()
    top = np.array([M.indices[a + np.argmax(M.data[a:b])] if b > a else -1 for a, b in zip(M.indptr[:-1], M.indptr[1:])])
    return _node_tags(np.maximum(top, 0), facets, tags, M.shape[1])


def _coupling_notes(couplings) -> List[str]:
    """What the mortar couplings did on their own: nonmortar nodes with no condition of their own."""
    notes = []
    for k, c in enumerate(couplings):
        if len(c.excluded):
            notes.append(f"contact pair {k}: {len(c.excluded)} nonmortar node(s) held along their normal by Dirichlet "
                         "data carry no contact condition of their own (the dual basis of their neighbours is "
                         "modified to cover their support)")
        if len(c.uncovered):
            notes.append(f"contact pair {k}: {len(c.uncovered)} nonmortar node(s) face the mortar side over less than "
                         "1 % of their support within the search distance and carry no contact condition")
    return notes


def _split_contacts(bodies, obstacle, pairs, contacts):
    """(obstacle contacts, pairs) of the problem's arguments: `contacts` (ObstacleContact and
    ContactPair) and the short forms (`obstacle` with the bodies' contact_tags, `pairs`)."""
    contacts = _items(contacts, (ObstacleContact, ContactPair), "contacts must hold ObstacleContact and ContactPair")
    pairs = _items(pairs, (ContactPair,), "pairs must be a ContactPair or a non-empty sequence of ContactPair")
    pairs = pairs + [c for c in contacts if isinstance(c, ContactPair)]
    obstacles = [c for c in contacts if isinstance(c, ObstacleContact)]
    tagged = [k for k, b in enumerate(bodies) if len(b.contact_tags)]
    if obstacle is not None:
        if not callable(getattr(obstacle, "gaps_and_normals", None)):
            raise TypeError("obstacle must be a PlaneObstacle, a NodalObstacle or an object with "
                            f"gaps_and_normals(points), got {type(obstacle).__name__}")
        if len(bodies) > 1:
            raise ValueError("obstacle= is the short form for one body: give several bodies their obstacles as "
                             "contacts=[ObstacleContact(body, tags, obstacle), ...]")
        if tagged:
            obstacles.insert(0, ObstacleContact(0, bodies[0].contact_tags, obstacle))
    elif tagged:
        if len(bodies) > 1:
            raise ValueError("contact_tags name a body's facets against the obstacle= of one body: give several "
                             "bodies their obstacles as contacts=[ObstacleContact(body, tags, obstacle), ...]")
        raise ValueError("contact_tags are given but no obstacle")
    for oc in obstacles:
        if not 0 <= oc.body < len(bodies):
            raise ValueError(f"an ObstacleContact names body {oc.body}; the problem has bodies 0..{len(bodies) - 1}")
    return obstacles, pairs


def _nearest_obstacle(nodes: np.ndarray, gaps: np.ndarray, source: np.ndarray):
    """(unique nodes, the row kept for each): a node claimed by several contacts keeps the one with
    the smallest gap (the obstacle it is nearest to; ties: the first given)."""
    order = np.lexsort((np.arange(len(nodes)), gaps, nodes))
    first = np.r_[True, nodes[order][1:] != nodes[order][:-1]]
    keep = order[first]
    return nodes[keep], keep


def _body_normals(mesh, facets: np.ndarray, nodes: np.ndarray):
    """(outward unit normal (m, d), mean facet size (m,), facet measure around (m,)) of the body at
    the `nodes` (ascending) from its contact `facets`."""
    d = mesh.dim
    fn = facet_area_vectors(mesh.points, facets)             # outward normal times measure
    size = np.linalg.norm(fn, axis=1) ** (1.0 / (d - 1))     # a length: the edge, or the root of the area
    pos = np.searchsorted(nodes, facets)
    pos = np.minimum(pos, len(nodes) - 1)
    hit = nodes[pos] == facets
    body_n = np.zeros((len(nodes), d))
    h = np.zeros(len(nodes))
    count = np.zeros(len(nodes))
    for a in range(facets.shape[1]):
        sel = hit[:, a]
        np.add.at(body_n, pos[sel, a], fn[sel])
        np.add.at(h, pos[sel, a], size[sel])
        np.add.at(count, pos[sel, a], 1.0)
    h = h / np.maximum(count, 1.0)
    length = np.linalg.norm(body_n, axis=1)
    body_n = body_n / np.where(length > 0, length, 1.0)[:, None]
    return body_n, h, length


def _check_obstacle_placement(mesh, facets, nodes, gaps, normals, tags, allow_penetration: bool) -> None:
    """Refuse an obstacle whose normal points into the body (it would be solved without a word into
    a body through the obstacle), and report (unless allowed) one that starts inside the body
    beyond the geometry's round-off.

    The body's outward normal at a node is the measure-weighted mean of its contact facets'
    normals. An obstacle normal points from the body into the obstacle, so where the body will
    touch it (the nodes nearest the obstacle) the two normals agree: a negative mean of their dot
    product there is an obstacle given the wrong way round."""
    body_n, h, weight = _body_normals(mesh, facets, nodes)
    # the nodes on the obstacle's surface (|gap| within half a facet), else those nearest to it
    near = np.abs(gaps) <= 0.5 * h
    if not np.any(near):
        near = gaps <= gaps.min() + 0.5 * np.median(h)
    agree = float(np.sum(weight[near] * np.einsum("ij,ij->i", body_n[near], normals[near])))
    if agree < 0:
        raise ValueError(f"the obstacle of the facets tagged {list(tags)} has its normal pointing into the body (the "
                         "body's outward normal and the obstacle normal disagree at the nodes nearest the obstacle): "
                         "contactmg's obstacle normal points from the body into the obstacle, away from the body (the "
                         "opposite of an Abaqus rigid surface); turn the normal round (a sphere: check inside=), or check "
                         "that the contact tags name the facets that face the obstacle")
    deep = gaps < -h
    # any start inside the obstacle beyond the geometry's round-off presses the body before it is
    # loaded (0.02 inside a body tripled its reaction without a word): said unless intended
    inside = gaps < -1e-9 * h
    if np.any(inside) and not allow_penetration:
        k = int(np.argmin(gaps / h))
        how = ("deeper than their contact facets are long" if np.any(deep) else
               f"by up to {-gaps.min():.3g} ({-gaps[k] / h[k]:.2g} of the facet size there)")
        warnings.warn(f"{int(inside.sum())} node(s) of the facets tagged {list(tags)} start inside the obstacle {how} "
                      f"(node {int(nodes[k])} at {np.round(mesh.points[nodes[k]], 6).tolist()}: gap {gaps[k]:.3g}, "
                      f"facet size {h[k]:.3g}); the solve pushes them out onto the obstacle, which loads the body. Is "
                      "the obstacle placed right? (an intended interference fit: ObstacleContact(..., "
                      "allow_penetration=True) says so)", UserWarning, stacklevel=4)
