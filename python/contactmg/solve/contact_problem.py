"""Problem setup: an elastic body on a mesh hierarchy, Dirichlet and Neumann data, a contact
boundary against a rigid obstacle with a friction law, and the solvers on top of it."""
from __future__ import annotations

import numbers
import time
import warnings
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Sequence, Union

import numpy as np

from .. import _core
from ..model.frames import contact_frames, to_canonical, to_local
from ..model.friction import Coulomb, Frictionless, Tresca
from ..mesh.hierarchy import MeshHierarchy
from ..model.material import Material
from ..mesh.mesh import connected_components
from ..results.result import ContactResult

VectorField = Union[Sequence[float], np.ndarray, Callable[[np.ndarray], np.ndarray]]

METHODS = ("nmg", "fixed-point", "linear", "tnnmg")
CYCLES = ("V", "W", "F")
INT32_MAX = 2 ** 31 - 1  # the core counts cycles in a C int
ORDERINGS = ("coloured", "lexicographic")
LINEAR_CORRECTIONS = ("pcg", "cycle", "coarse")
# The default omega by cell type. Simplices: 1.3 (symmetric SOR). Nodal block Gauss-Seidel on P1
# elasticity levels off near 0.34 per F(3,3) cycle on the adaptive Hertz levels (Q1: 0.14 on the
# unit square); over-relaxed it contracts by 0.26 / 0.235 / 0.216 / 0.216 at level 11 with omega
# 1.2 / 1.3 / 1.4 / 1.5 at the same cost per sweep, and Algorithm 2 at F = 0.4 needs 9-15 cycles over
# levels 3-11 instead of 10-17 (docs/history/adaptive.md, issue 11, third part). 1.3 rather than 1.4: within 0.02 in
# rate, and 1.4 costs one cycle on the small uniform level 3 at F = 0.4 (16 against 15). The
# tetrahedral half ball gains too (level 3: 0.40 -> 0.32, 19 -> 16 cycles). Quadrilaterals gain nothing
# (0.171 -> 0.157, 0.226 -> 0.225 at 1.4) and hexahedra lose (0.19 -> 0.25): plain Gauss-Seidel there.
DEFAULT_OMEGA = {"triangle": 1.3, "tetra": 1.3}
# The post-smoothing's own omega on 2D adaptive hierarchies, where the Petrov-Galerkin coupling is
# on by default: with it, 1.5 took adaptive Hertz level 11 at F = 0.4 / 1 from 13 / 14 cycles to 12 / 13
# (level 3: 8 / 9), 1.7 costs level 3 a cycle (issue 11, tenth part).
DEFAULT_OMEGA_POST_ADAPTIVE = {"triangle": 1.5}
# Issue 15: a core solver built for the coloured order stores its levels by colours (each colour a
# contiguous range: the coloured sweep streams memory). The default ordering of a problem's solves,
# chosen by measurement (docs/scaling.md, benchmarks/parallel_bandwidth.py).
DEFAULT_ORDERING = "coloured"


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


def _field(value: Optional[VectorField], x: np.ndarray, name: str) -> np.ndarray:
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


def assemble_load(mesh, body_force: Optional[VectorField] = None,
                  traction: Optional[Dict[int, VectorField]] = None) -> np.ndarray:
    """The nodal load (n, d): body force and Neumann tractions on tagged facets (a load path
    assembles one per step)."""
    load = _core.assemble_mass_load(mesh.points, mesh.cells, mesh.cell_type, _field(body_force, mesh.points, "body_force"))
    for tag, value in (traction or {}).items():
        (tag,) = tag_tuple(tag, "a traction tag")
        sel = mesh.facet_tags == tag
        if not np.any(sel):
            raise ValueError(f"no boundary facet carries the traction tag {tag}")
        load += _core.assemble_facet_load(mesh.points, mesh.facets[sel], _field(value, mesh.points, f"traction[{tag}]"))
    return load


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
            values[nodes] = _field(bc.value, mesh.points[nodes], "Dirichlet value")
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


def _count(v, name: str, lo: int, hi: int) -> int:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
        raise ValueError(f"{name} must be an integer in {lo}..{hi}, got {v!r}")
    return int(v)


@dataclass(frozen=True)
class CycleOptions:
    """The multigrid cycle of a solve: type V/W/F and nu1 pre-, nu2 post-smoothing sweeps."""

    cycle: str = "F"
    nu1: int = 3
    nu2: int = 3

    def __post_init__(self):
        if self.cycle not in CYCLES:
            raise ValueError(f"cycle must be one of {CYCLES}, got {self.cycle!r}")
        object.__setattr__(self, "nu1", _count(self.nu1, "nu1", 0, 100))
        object.__setattr__(self, "nu2", _count(self.nu2, "nu2", 0, 100))
        if self.nu1 + self.nu2 < 1:
            raise ValueError("nu1 + nu2 must be at least 1: a cycle needs smoothing")


class ContactProblem:
    # the ordering of solves that name none; the kept core solver is stored for it (set before the
    # first solve to change it: another ordering per solve runs on that solver, slower, same result)
    default_ordering: str = DEFAULT_ORDERING
    """Linear elasticity on the finest level of `hierarchy` with contact on the facets tagged
    `contact_tags` against `obstacle` under `friction`. Without contact tags it is a linear
    elasticity problem solved by linear multigrid.

    The problem is the description (body, boundary conditions, contact boundary, obstacle, law),
    assembled once. The solver options go to solve(); cycle, nu1 and nu2 given here are only the
    defaults of solve()."""

    def __init__(self, hierarchy: MeshHierarchy, material: Material, dirichlet: Sequence[Dirichlet],
                 contact_tags: Sequence[int] = (), obstacle=None, friction=None,
                 body_force: Optional[VectorField] = None, traction: Optional[Dict[int, VectorField]] = None,
                 cycle: str = "F", nu1: int = 3, nu2: int = 3):
        if not isinstance(hierarchy, MeshHierarchy):
            raise TypeError("hierarchy must be a MeshHierarchy")
        if not isinstance(material, Material):
            raise TypeError("material must be a Material")
        self.default_cycle = CycleOptions(cycle, nu1, nu2)
        friction = Frictionless() if friction is None else friction
        if not isinstance(friction, (Frictionless, Tresca, Coulomb)):
            raise TypeError("friction must be Frictionless(), Tresca(bound) or Coulomb(F)")
        contact_tags = tag_tuple(contact_tags, "contact_tags")
        if len(contact_tags) and obstacle is None:
            raise ValueError("contact_tags are given but no obstacle")
        if obstacle is not None and not callable(getattr(obstacle, "gaps_and_normals", None)):
            raise TypeError("obstacle must be a PlaneObstacle, a NodalObstacle or an object with "
                            f"gaps_and_normals(points), got {type(obstacle).__name__}")
        if isinstance(dirichlet, Dirichlet):
            dirichlet = [dirichlet]
        for bc in dirichlet:
            if not isinstance(bc, Dirichlet):
                raise TypeError(f"dirichlet must be a sequence of Dirichlet(tags, value), got a {type(bc).__name__}")
            if not callable(bc.value) and (np.ndim(bc.value) != 1 or isinstance(bc.value, (str, bytes))):
                raise TypeError("a Dirichlet value must be a vector (None for a free component) or a callable, "
                                f"got {bc.value!r}")
        t0 = time.perf_counter()
        self.hierarchy, self.material, self.friction = hierarchy, material, friction
        self.benchmark: Optional[str] = None  # "hertz" for the Hertz benchmark (its zones are centred on x = 0)
        mesh = self.mesh = hierarchy.finest
        self._A = _core.assemble_elasticity(mesh.points, mesh.cells, mesh.cell_type, material.E, material.nu)
        self.load = assemble_load(mesh, body_force, traction)
        self.fixed, self.fixed_values = dirichlet_arrays(mesh, dirichlet)
        # how to make load and fixed_values again once released (release_hierarchy; a value set
        # from outside is kept: the setters clear these)
        self._load_recipe, self._values_recipe = (body_force, traction), list(dirichlet)
        self._check_rigid_motion()
        self.contact = self._contact_boundary(contact_tags, obstacle)
        self.coefficients = friction.coefficients(self.contact.nodes, self.contact.measure)
        self._solvers: Dict[CycleOptions, object] = {}
        self._build_seconds: Dict[CycleOptions, float] = {}
        self.assembly_seconds = time.perf_counter() - t0 + hierarchy.build_seconds

    # The load and the Dirichlet values (n, d): held in Python until a kept core solver has its own
    # copies (release_hierarchy), then made again from the description when asked for (16 bytes a
    # dof in 2D; the same bits: the same assembly and the same Dirichlet data).
    _load: Optional[np.ndarray] = None
    _fixed_values: Optional[np.ndarray] = None
    _load_recipe = None
    _values_recipe = None

    @property
    def load(self) -> np.ndarray:
        if self._load is None and self._load_recipe is not None:
            self._load = assemble_load(self.mesh, *self._load_recipe)
        return self._load

    @load.setter
    def load(self, value: np.ndarray) -> None:
        self._load, self._load_recipe = value, None

    @property
    def fixed_values(self) -> np.ndarray:
        if self._fixed_values is None and self._values_recipe is not None:
            self._fixed_values = dirichlet_arrays(self.mesh, self._values_recipe)[1]
        return self._fixed_values

    @fixed_values.setter
    def fixed_values(self, value: np.ndarray) -> None:
        self._fixed_values, self._values_recipe = value, None

    def _release_vectors(self) -> None:
        """Drop the load and the Dirichlet values where they can be made again (see load)."""
        if self._load_recipe is not None:
            self._load = None
        if self._values_recipe is not None:
            self._fixed_values = None

    @property
    def A(self):
        """The stiffness matrix (canonical axes, no boundary conditions). A core solver takes it
        over when it is built (the fine matrix is then held once, issue 15); asking for it again
        assembles it anew."""
        if self._A is None:
            self._A = self._assemble_matrix()
        return self._A

    def _assemble_matrix(self):
        """The matrix of this problem's unknowns (a subclass with another basis assembles its own)."""
        m = self.mesh
        return _core.assemble_elasticity(m.points, m.cells, m.cell_type, self.material.E, self.material.nu)

    # -- compatibility: the defaults of solve() ---------------------------------------------------
    @property
    def cycle(self) -> str:
        return self.default_cycle.cycle

    @property
    def nu1(self) -> int:
        return self.default_cycle.nu1

    @property
    def nu2(self) -> int:
        return self.default_cycle.nu2

    @property
    def setup_seconds(self) -> float:
        """Hierarchy, assembly and the build of the core solver of the default cycle (once built)."""
        return self.assembly_seconds + self._build_seconds.get(self._solver_key(self.default_cycle), 0.0)

    # -- setup helpers --------------------------------------------------------------------------
    def _check_rigid_motion(self):
        """The Dirichlet dofs must pin every rigid-body motion of every connected piece of the body
        (no contact relied on): a piece that floats free makes the problem singular."""
        mesh = self.mesh
        x, d = mesh.points, mesh.dim
        fixed = self.fixed.astype(bool)
        count, label = self._pieces()
        order = np.argsort(label, kind="stable")
        bounds = np.searchsorted(label[order], np.arange(count + 1))
        for k in range(count):
            nodes = np.sort(order[bounds[k]:bounds[k + 1]])
            if _holds_rigid_motion(x[nodes], fixed[nodes]):
                continue
            where = "" if count == 1 else (
                f" of piece {k + 1} of the {count} disconnected pieces of the mesh ({len(nodes)} nodes, "
                f"node {int(nodes[0])} at {np.round(x[nodes[0]], 6).tolist()})")
            raise ValueError(f"the Dirichlet conditions leave rigid-body motion{where} free: "
                             "fix enough displacement components to hold " + ("the body" if count == 1 else "every piece"))

    def _pieces(self):
        """(count, label) of the connected pieces of the finest mesh, found on the coarsest mesh
        (refinement splits cells and joins nothing) and handed down through the transfers: a
        fine node lies in the piece of its first coarse parent."""
        h = self.hierarchy
        coarse = h.meshes[0]
        count, label = connected_components(coarse.cells, coarse.num_points)
        for t in h.transfers:
            if np.any(np.diff(t.ptr) < 1):  # a node without parents: count on the fine mesh itself
                return connected_components(self.mesh.cells, self.mesh.num_points)
            label = label[t.parent[t.ptr[:-1]]]
        return count, label

    def _contact_boundary(self, tags, obstacle) -> ContactBoundary:
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
            raise ValueError(f"the contact boundary is empty: every node of the facets tagged {list(tags)} is fixed by "
                             "Dirichlet data (are the contact tags the Dirichlet tags?)")
        if np.all(gaps < 0):
            warnings.warn(f"every contact node starts inside the obstacle (gaps from {gaps.min():.3g} to {gaps.max():.3g}): "
                          "is the obstacle normal flipped? It must point from the body into the obstacle", UserWarning,
                          stacklevel=3)
        ones = np.ones((mesh.num_points, 1))
        measure = _core.assemble_facet_load(mesh.points, facets, ones)[nodes, 0]
        normals = np.ascontiguousarray(normals)
        return ContactBoundary(nodes.astype(np.int64), normals, np.ascontiguousarray(gaps), measure,
                               facets=np.ascontiguousarray(facets),
                               frames=contact_frames(normals, self.fixed[nodes]))

    @property
    def law(self) -> str:
        return "linear" if len(self.contact.nodes) == 0 else self.friction.law

    def _new_core_solver(self, law: str, options: CycleOptions, frame_fixed=None, frame_values=None, load=None,
                         fixed_values=None, take_matrix: bool = False):
        """A core solver of this problem's matrix and data (building one does not re-assemble).
        frame_fixed/frame_values (num_contact, d): components of the contact nodes fixed in their
        frames on top of the Dirichlet data (the known-state linear reference). take_matrix: the
        core takes the assembled matrix over (one fine matrix in memory; `A` is assembled again
        when asked for) -- for the solver kept for the problem's life, not for passing ones."""
        d = self.mesh.dim
        cls = _core.ContactSolver2D if d == 2 else _core.ContactSolver3D
        c = self.contact
        values = self.fixed_values if fixed_values is None else fixed_values  # a load path's step: its own values
        args = (self.load if load is None else load, self.fixed, values, c.nodes, c.normals,
                c.gaps, self.coefficients, law, [t.as_tuple() for t in self.hierarchy.transfers],
                dict(cycle=options.cycle, nu1=options.nu1, nu2=options.nu2, ordering=self.default_ordering))
        kw = dict(frame_fixed=frame_fixed, frame_values=frame_values)
        if not take_matrix:
            return cls(self.A, *args, **kw)
        # The core takes the assembled matrix over (left empty here): one fine matrix in memory.
        A, self._A = self.A, None
        return cls(A, *args, take_matrix=True, **kw)

    # Issue 15: once the kept core solver is built (it holds its own prolongations, fine matrix, load
    # and Dirichlet values), release the hierarchy's coarse meshes and its transfers
    # (MeshHierarchy.release_coarse: the finest mesh stays for results and output; the others are
    # made again, bit for bit, if anything asks for them) and the load and Dirichlet values (made
    # again the same way: see load). Off by default: a hierarchy shared by several problems, or a load path that
    # builds a core solver per step, would make them again and again. The single solves of the
    # command line turn it on.
    release_hierarchy: bool = False

    # Local smoothing (issue 11): None = on for adaptive hierarchies, off for uniform ones (there every
    # node of a level changes); True/False force it. Set before the first solve.
    local_smoothing: Optional[bool] = None
    # Over-relaxation of the smoothers' unbounded block solves (CycleOptions::omega in the core):
    # None = DEFAULT_OMEGA of the mesh's cell type (1 where it has none); a number in (0, 2) forces it.
    smoother_omega: Optional[float] = None
    # The post-smoothing sweeps' own over-relaxation (CycleOptions::omega_post): None = the
    # pre-smoothing's, except on 2D adaptive hierarchies, where it is DEFAULT_OMEGA_POST_ADAPTIVE of
    # the cell type (with the coupling below; issue 11, tenth part); a number in (0, 2) forces it.
    smoother_omega_post: Optional[float] = None
    # Algorithm 2's cycles (all but the first) with the sliding nodes' Petrov-Galerkin coupling on
    # the top coarse level and a fallback to the symmetric one (CycleOptions::petrov_galerkin;
    # the "nmg" solves of a Coulomb problem): None = on for 2D adaptive hierarchies (issue 11, tenth
    # part: the adaptive Table 1 flat for F <= 2), off otherwise (uniform level 7 at F = 5 takes 19
    # cycles with it, 14 without; in 3D it saves at most a cycle); True/False force it.
    petrov_galerkin: Optional[bool] = None
    # Algorithm 2's fine sweeps each followed by one more visit of the contact nodes, the sliding
    # ones in the upwind order of the Coulomb Jacobian (CycleOptions::upwind_contact_sweep; the "nmg"
    # solves of a Coulomb problem): None = on for 2D adaptive hierarchies (issue 11, eleventh part:
    # one cycle fewer in 16 of the 50 cells of the adaptive Table 1, none more, at 3-6 % a cycle),
    # off otherwise (uniform triangles: one cycle fewer only on level 7 at F = 0.4 / 2, at 3-12 % a
    # cycle; in 3D at most one fewer at 10-40 % a cycle); True/False force it.
    upwind_contact_sweep: Optional[bool] = None
    # The coarse correction of "nmg" without the inactive contact nodes' gap bounds, projected onto
    # the gap and taken with the exact line search of the frozen-bound energy (a descent step, so
    # the cycle stays monotone; CycleOptions::projected_coarse_correction): None = on where a contact
    # frame is not a signed permutation of the axes (curved obstacles, tilted planes, curved
    # interfaces), whose monotone bound restriction bounds every coarse component a gap touches (the
    # cork without friction: 16 / 22 / 29 cycles on levels 2-4 of 8 axial layers become 11 / 12 / 12);
    # off for axis-aligned frames, where the restriction bounds only the normal components and the
    # projected step costs cycles (adaptive Hertz level 11 at F = 0.4: 12 -> 15); True/False force it.
    projected_coarse_correction: Optional[bool] = None

    def _adaptive_2d(self) -> bool:
        return self.hierarchy.kind == "adaptive" and self.mesh.dim == 2

    def post_smoothing_omega(self) -> Optional[float]:
        """The post-smoothing sweeps' own over-relaxation (None: the pre-smoothing's)."""
        w = self.smoother_omega_post
        if w is None and self.smoother_omega is None and self._adaptive_2d():
            w = DEFAULT_OMEGA_POST_ADAPTIVE.get(self.mesh.cell_type)
        return None if w is None else _checked_omega(w, "omega_post")

    def _switch(self, name: str, on, default: bool) -> bool:
        """A switch of the "nmg" cycles (checked here: load paths read it too); None: `default`."""
        if on is None:
            return bool(default)
        if not isinstance(on, (bool, np.bool_)):
            raise ValueError(f"{name} must be True or False, got {on!r}")
        return bool(on)

    def _cycle_choice(self, name: str, on, default: bool) -> bool:
        """A switch of Algorithm 2's cycles; None: `default` for Coulomb friction, off for the other laws."""
        return self._switch(name, on, default and isinstance(self.friction, Coulomb))

    def rotated_frames(self) -> bool:
        """Is some contact frame not a signed permutation of the axes?"""
        if self.law == "linear" or len(self.contact.nodes) == 0:
            return False
        a = np.abs(np.asarray(self.contact.frames, float))
        return bool(np.any(np.minimum(a, np.abs(a - 1.0)) > 1e-12))

    def coarse_correction_projected(self) -> bool:
        """Whether the "nmg" cycles of this problem take the projected coarse correction."""
        return self._switch("projected_coarse_correction", self.projected_coarse_correction, self.rotated_frames())

    def petrov_galerkin_coupling(self) -> bool:
        """Whether Algorithm 2's solves of this problem couple the sliding nodes on the top coarse level."""
        return self._cycle_choice("petrov_galerkin", self.petrov_galerkin, self._adaptive_2d())

    def contact_sweep_upwind(self) -> bool:
        """Whether Algorithm 2's fine sweeps of this problem are each followed by an upwind visit of
        the contact nodes."""
        return self._cycle_choice("upwind_contact_sweep", self.upwind_contact_sweep, self._adaptive_2d())

    def cycle_switches(self, method: str) -> dict:
        """The core solve's keywords for this problem's own choices of Algorithm 2's cycles (method
        "nmg"): petrov_galerkin and upwind_contact_sweep where on."""
        kw = {}
        if method != "nmg":
            return kw
        if self.petrov_galerkin_coupling():
            kw["petrov_galerkin"] = True
        if self.contact_sweep_upwind():
            kw["upwind_contact_sweep"] = True
        if self.coarse_correction_projected():
            kw["projected_coarse_correction"] = True
        return kw

    def smoothing_omega(self) -> float:
        """The over-relaxation the solves of this problem use (smoother_omega or the default)."""
        w = self.smoother_omega
        if w is None:
            return float(DEFAULT_OMEGA.get(self.mesh.cell_type, 1.0))
        return _checked_omega(w)

    def smooths_locally(self) -> bool:
        """Do the coarse levels smooth only where they differ from the level below?"""
        on = self.local_smoothing
        return bool(self.hierarchy.kind == "adaptive" if on is None else on)

    def _apply_local_smoothing(self, core) -> None:
        """Coarse level l (1 <= l < finest; the coarsest is solved exactly) smooths only the nodes
        whose hat functions differ from level l-1 (MeshHierarchy.changed_nodes): elsewhere its
        space is the one below, whose correction the cycle computes anyway. The finest level's
        sweeps stay on every node; truncation and the monotone bound restriction are unchanged."""
        if not self.smooths_locally() or not hasattr(core, "set_rows_to_smooth"):
            return
        h = self.hierarchy
        for level in range(1, h.levels - 1):
            if core.level_sizes[level] != h.meshes[level].num_points:
                return  # unknowns other than the mesh nodes (a subclass's basis): keep every row
        for level in range(1, h.levels - 1):
            core.set_rows_to_smooth(level, h.changed_nodes(level))

    def core_solver(self, cycle: Optional[str] = None, nu1: Optional[int] = None, nu2: Optional[int] = None):
        """The core solver for the cycle options (defaults: the problem's), built on first use and
        kept: one per (cycle, nu1, nu2)."""
        options = self._options(cycle, nu1, nu2)
        key = self._solver_key(options)
        if key not in self._solvers:
            t0 = time.perf_counter()
            self._solvers[key] = self._new_core_solver(self.law, key, take_matrix=True)
            self._apply_local_smoothing(self._solvers[key])
            self._build_seconds[key] = time.perf_counter() - t0
            if self.release_hierarchy:
                self.hierarchy.release_coarse()
                self._release_vectors()
                # made for one solve: the cycles' workspace need not outlive it (the lower peak)
                self._solvers[key].keep_workspace(False)
        return self._solvers[key]

    def memory_bytes(self) -> Dict[str, int]:
        """Bytes held now, by owner: the hierarchy's meshes and transfers (Python), the problem's
        vectors (load, Dirichlet data, contact boundary, coefficients), an assembled matrix held in
        Python, and the kept core solvers (each one's own count: matrices, prolongations, vectors);
        "total" is their sum. Nothing is made again to count it (a released hierarchy stays so)."""
        h = self.hierarchy.memory_bytes()
        c = self.contact
        arrays = (self._load, self.fixed, self._fixed_values, self.coefficients, c.nodes, c.normals, c.gaps, c.measure,
                  c.frames, c.facets)
        out = {"mesh_hierarchy": h["meshes"], "transfers": h["transfers"],
               "problem_vectors": int(sum(a.nbytes for a in arrays if isinstance(a, np.ndarray))),
               "python_matrix": self._A.memory_bytes() if self._A is not None else 0,
               "core": int(sum(S.memory_bytes() for S in self._solvers.values()))}
        out["total"] = sum(out.values())
        return out

    def _solver_key(self, options: CycleOptions) -> CycleOptions:
        # the core takes the cycle per solve: the solver of the defaults serves every choice
        return self.default_cycle

    @property
    def solver(self):
        """The core solver of the default cycle options."""
        return self.core_solver()

    def _options(self, cycle, nu1, nu2) -> CycleOptions:
        base = self.default_cycle
        return CycleOptions(base.cycle if cycle is None else cycle, base.nu1 if nu1 is None else nu1,
                            base.nu2 if nu2 is None else nu2)

    # -- solving --------------------------------------------------------------------------------
    def solve(self, method: str = "nmg", tol: float = 1e-11, rtol: float = 0.0, max_cycles: int = 200,
              u0: Optional[np.ndarray] = None, reference: Optional[ContactResult] = None,
              fixed_point_tol: float = 1e-9, fixed_point_max: int = 100,
              error_reference: Optional[np.ndarray] = None, cycle: Optional[str] = None,
              nu1: Optional[int] = None, nu2: Optional[int] = None,
              progress: Optional[Callable[[dict], None]] = None, threads: int = 0,
              ordering: Optional[str] = None, fixed_point_stall_window: int = 0,
              linear: Optional[str] = None, lines: Optional[bool] = None,
              omega: Optional[float] = None, omega_post: Optional[float] = None,
              petrov_galerkin: Optional[bool] = None,
              upwind_contact_sweep: Optional[bool] = None,
              projected_coarse_correction: Optional[bool] = None) -> ContactResult:
        """Solve with `method`: "nmg" (Algorithm 2 for Coulomb; truncated monotone multigrid for
        frictionless and Tresca; linear multigrid without contact), "tnnmg" (truncated nonsmooth
        Newton multigrid: the fine nonlinear sweeps, one linear cycle for the truncated Newton
        system, projection and an exact line search of the frozen-bound energy),
        "fixed-point" (Algorithm 1, Coulomb only) or "linear" (the cost reference: the linear problem with the contact state of
        `reference` — or of an nmg solve made first — known in advance, started from zero).
        cycle ("V", "W", "F"), nu1 and nu2 (pre- and post-smoothing sweeps) default to the
        problem's; changing them re-uses the assembled problem (a core solver is built once per
        choice). With `error_reference` (a displacement u*), history["error"] records ||u - u*||_A
        after every cycle (one extra matrix product per cycle, kept out of the timings).
        `progress(record)` is called after every cycle with a dict (cycle, outer,
        correction_norm, energy, seconds, error, active, stick, slip, rebuilt); an exception it
        raises stops the solve. `threads`: the
        threads of the sweeps, products and norms (0: all cores); the result is the same bit for
        bit on any count, and in every solve of the problem with the same arguments (each starts
        from the coarse levels as the core solver built them: a later solve pays one full coarse
        rebuild, counted in its rebuilds). `ordering` of every Gauss-Seidel sweep: "coloured" (colours of the block
        graph, the rows of one colour at once; the levels stored by colours) or "lexicographic" (one
        thread for the sweeps); None: `default_ordering` (DEFAULT_ORDERING). `fixed_point_stall_window` (Algorithm 1): stop as not converging once the relative
        change of s_n has not fallen below the one that many outer iterations before (0: run to
        fixed_point_max); result.extra["outer_changes"] holds the change of every outer iteration.
        `omega`: over-relaxation of the unbounded block solves of every sweep (fine nodes without
        contact, coarse rows without bounds), in (0, 2); None: smoothing_omega(). `omega_post`: the
        same for the post-smoothing sweeps only; None: post_smoothing_omega() (omega where that is None),
        or, when `omega` is given, smoother_omega_post or omega.
        `petrov_galerkin` ("nmg", and "linear"'s reference solve): in Algorithm 2's cycles after the first,
        the top coarse level also carries the sliding nodes' Petrov-Galerkin coupling, switched off for
        the rest of the solve by a cycle whose correction is no smaller than every one before; None: petrov_galerkin_coupling(). result.history["petrov_galerkin"]: 1 in the cycles
        with it, 2 in the one that switched it off; result.extra["petrov_galerkin"] when on.
        `upwind_contact_sweep` ("nmg", and "linear"'s reference solve): every fine sweep of Algorithm 2
        followed by one more visit of the contact nodes, the sliding ones in the upwind order of the
        Coulomb Jacobian; None: contact_sweep_upwind(). result.extra["upwind_contact_sweep"] is True when on.
        `projected_coarse_correction` ("nmg", and "linear"'s reference solve; any contact law): the coarse
        correction without the inactive contact nodes' gap bounds, projected onto the gap and taken with
        the exact frozen-energy line search; None: coarse_correction_projected() (on for rotated contact
        frames). result.history["step_size"] holds its step; result.extra["projected_coarse_correction"] is
        True when on."""
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        options = self._options(cycle, nu1, nu2)
        for name, v in (("tol", tol), ("rtol", rtol), ("fixed_point_tol", fixed_point_tol)):
            if isinstance(v, (bool, np.bool_)) or not (isinstance(v, numbers.Real) and np.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
        if tol == 0 and rtol == 0:
            raise ValueError("one of tol and rtol must be positive")
        for name, v in (("max_cycles", max_cycles), ("fixed_point_max", fixed_point_max)):
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or not 1 <= v <= INT32_MAX:
                raise ValueError(f"{name} must be an integer in 1..{INT32_MAX}, got {v!r}")
        if progress is not None and not callable(progress):
            raise ValueError(f"progress must be a callable (called with a dict after every cycle), got {progress!r}")
        if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)) or not 0 <= threads <= 4096:
            raise ValueError(f"threads must be an integer in 0..4096 (0: all cores), got {threads!r}")
        if ordering is not None and ordering not in ORDERINGS:
            raise ValueError(f"ordering must be one of {ORDERINGS}, got {ordering!r}")
        if (linear is not None or lines is not None) and method != "tnnmg":
            raise ValueError("linear and lines choose the linear correction of method 'tnnmg'")
        if linear is not None and linear not in LINEAR_CORRECTIONS:
            raise ValueError(f"linear must be one of {LINEAR_CORRECTIONS}, got {linear!r}")
        if lines is not None and not isinstance(lines, (bool, np.bool_)):
            raise ValueError(f"lines must be True or False, got {lines!r}")
        if ordering is None:
            ordering = self.default_ordering
        kw = dict(tol=float(tol), rtol=float(rtol), max_cycles=int(max_cycles), fixed_point_tol=float(fixed_point_tol),
                  fixed_point_max=int(fixed_point_max), threads=int(threads), ordering=ordering)
        if (isinstance(fixed_point_stall_window, (bool, np.bool_)) or not isinstance(fixed_point_stall_window, (int, np.integer))
                or not 0 <= fixed_point_stall_window <= INT32_MAX):
            raise ValueError(f"fixed_point_stall_window must be an integer >= 0, got {fixed_point_stall_window!r}")
        if fixed_point_stall_window:
            kw["fixed_point_stall_window"] = int(fixed_point_stall_window)
        if omega_post is None:  # a pre-smoothing omega given here is the post-smoothing's too
            omega_post = self.post_smoothing_omega() if omega is None else self.smoother_omega_post
        omega = self.smoothing_omega() if omega is None else _checked_omega(omega)
        kw["omega"] = omega
        if omega_post is not None:
            kw["omega_post"] = _checked_omega(omega_post, "omega_post")
        choices = {}
        for name, value, default, choose, where in (
                ("petrov_galerkin", petrov_galerkin, self.petrov_galerkin, self._cycle_choice, self._adaptive_2d()),
                ("upwind_contact_sweep", upwind_contact_sweep, self.upwind_contact_sweep, self._cycle_choice,
                 self._adaptive_2d()),
                ("projected_coarse_correction", projected_coarse_correction, self.projected_coarse_correction,
                 self._switch, self.rotated_frames())):
            on = choose(name, default if value is None else value, where)
            if on and method not in ("nmg", "linear") and value is not None:
                raise ValueError(f"{name} is a choice of method 'nmg' (Algorithm 2), not {method!r}")
            if on and method == "nmg":
                kw[name] = True
            choices[name] = on
        kw.update(cycle=options.cycle, nu1=options.nu1, nu2=options.nu2)
        if method == "fixed-point":
            if not isinstance(self.friction, Coulomb) or self.law == "linear":
                raise ValueError("the fixed-point method (Algorithm 1) needs Coulomb friction on a contact boundary")
            solver = self.core_solver(options.cycle, options.nu1, options.nu2)
            return self._result(solver.solve(u0, dict(kw, method="fixed-point"), progress=progress, reference=error_reference),
                                method, options)
        if method in ("nmg", "tnnmg"):
            solver = self.core_solver(options.cycle, options.nu1, options.nu2)
            if method == "tnnmg":
                kw["method"] = "tnnmg"
                if linear is not None or lines is not None:
                    kw.update(linear=linear, lines=None if lines is None else bool(lines))
            return self._result(solver.solve(u0, kw, progress=progress, reference=error_reference), method, options)
        if reference is None:
            reference = self.solve("nmg", tol=tol, rtol=rtol, max_cycles=max_cycles, cycle=options.cycle,
                                   nu1=options.nu1, nu2=options.nu2, threads=threads, ordering=ordering, omega=omega,
                                   omega_post=omega_post, **choices)
        t0 = time.perf_counter()
        solver = self._known_state_solver(reference, options)
        build = time.perf_counter() - t0
        raw = solver.solve(None, kw, progress=progress, reference=error_reference)
        raw["contact_force"], raw["friction_bound"], raw["state"] = self._contact_outputs_linear(raw, reference)
        res = self._result(raw, method, options)
        # building its hierarchy for the known state is setup, like the nmg solver's own build
        res.setup_seconds = self.assembly_seconds + build
        res.extra["reference"] = {"method": reference.method, "cycles": reference.cycles,
                                  "solve_seconds": reference.solve_seconds, "converged": reference.converged}
        return res

    def _result(self, raw: dict, method: str, options: CycleOptions) -> ContactResult:
        res = ContactResult.from_raw(self, raw, method)
        res.setup_seconds = self.assembly_seconds + self._build_seconds.get(self._solver_key(options), 0.0)
        res.extra["cycle_options"] = {"cycle": options.cycle, "nu1": options.nu1, "nu2": options.nu2}
        res.extra["omega"] = float(raw.get("omega", 1.0))
        if "omega_post" in raw:  # only when set (issue 11, fifth part)
            res.extra["omega_post"] = float(raw["omega_post"])
        if raw.get("petrov_galerkin"):  # only when set (issue 11, seventh part)
            pg = np.asarray(raw["history"]["petrov_galerkin"])
            off = np.nonzero(pg == 2)[0]
            res.extra["petrov_galerkin"] = {"cycles": int(np.count_nonzero(pg)),
                                            "fallback_cycle": int(off[0]) + 1 if len(off) else None}
        if raw.get("upwind_contact_sweep"):  # only when set (issue 11, eleventh part)
            res.extra["upwind_contact_sweep"] = True
        if raw.get("projected_coarse_correction"):  # only when set (stop 27)
            res.extra["projected_coarse_correction"] = True
        if method == "fixed-point" and "outer_changes" in raw:
            res.extra["outer_changes"] = [float(c) for c in raw["outer_changes"]]
        if "threads" in raw:
            res.extra["threads"], res.extra["ordering"] = int(raw["threads"]), str(raw["ordering"])
        return res

    def _known_state_solver(self, ref: ContactResult, options: CycleOptions):
        """Linear problem with the final contact state of `ref`: active normals fixed on the gap,
        sticking tangentials fixed at zero, sliding nodes loaded with their friction force."""
        c = self.contact
        # components fixed in the contact frames (a Dirichlet component keeps its own value)
        fixed, values, load = np.zeros((len(c.nodes), self.mesh.dim), np.uint8), np.zeros((len(c.nodes), self.mesh.dim)), self.load.copy()
        state = ref.node_state[c.nodes]
        active = state > 0
        fixed[active, 0] = 1
        values[active, 0] = c.gaps[active]
        stick = state == 1
        fixed[stick, 1:] = 1
        values[stick, 1:] = 0.0
        slip = state == 2
        s_local = np.zeros_like(ref.contact_force)
        s_local[slip, 1:] = ref.contact_force[slip, 1:]
        load[c.nodes] += to_canonical(c.frames, s_local)
        return self._new_core_solver("linear", options, fixed, values, load)

    def _contact_outputs_linear(self, raw, ref):
        # The core reports A u - f of its own problem, whose load carries the sliding nodes'
        # friction forces and whose fixed dofs are eliminated; the contact force is A u - f of
        # this problem.
        f = self.A.matvec(raw["u"]) - self.load
        cf = to_local(self.contact.frames, f[self.contact.nodes])
        return cf, ref.friction_bound.copy(), ref.node_state[self.contact.nodes].copy()


def _checked_omega(w, name: str = "omega") -> float:
    if isinstance(w, (bool, np.bool_)) or not (isinstance(w, numbers.Real) and 0 < w < 2):
        raise ValueError(f"{name} must be a number in (0, 2), got {w!r}")
    return float(w)


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
