"""Problem setup: an elastic body on a mesh hierarchy, Dirichlet and Neumann data, a contact
boundary against a rigid obstacle with a friction law, and the solvers on top of it."""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Sequence, Union

import numpy as np

from . import _core
from .friction import Coulomb, Frictionless, Tresca
from .hierarchy import MeshHierarchy
from .material import Material
from .results import ContactResult

VectorField = Union[Sequence[float], np.ndarray, Callable[[np.ndarray], np.ndarray]]

METHODS = ("nmg", "fixed-point", "linear")
CYCLES = ("V", "W", "F")


@dataclass(frozen=True)
class Dirichlet:
    """Prescribed displacement on the nodes of the boundary facets with the given tags: a constant
    vector (a component given as None stays free) or a callable x (m, d) -> (m, d) values, which
    fixes every component."""

    tags: Sequence[int]
    value: Union[Sequence[Optional[float]], Callable[[np.ndarray], np.ndarray]]


@dataclass
class ContactBoundary:
    """Contact nodes of the finest mesh with their outward normals, gaps, lumped boundary measure
    (integral of the hat function over the contact boundary) and friction data."""

    nodes: np.ndarray
    normals: np.ndarray
    gaps: np.ndarray
    measure: np.ndarray


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


class ContactProblem:
    """Linear elasticity on the finest level of `hierarchy` with contact on the facets tagged
    `contact_tags` against `obstacle` under `friction`. Without contact tags it is a linear
    elasticity problem solved by linear multigrid."""

    def __init__(self, hierarchy: MeshHierarchy, material: Material, dirichlet: Sequence[Dirichlet],
                 contact_tags: Sequence[int] = (), obstacle=None, friction=None,
                 body_force: Optional[VectorField] = None, traction: Optional[Dict[int, VectorField]] = None,
                 cycle: str = "F", nu1: int = 3, nu2: int = 3):
        if not isinstance(hierarchy, MeshHierarchy):
            raise TypeError("hierarchy must be a MeshHierarchy")
        if not isinstance(material, Material):
            raise TypeError("material must be a Material")
        if cycle not in CYCLES:
            raise ValueError(f"cycle must be one of {CYCLES}, got {cycle!r}")
        friction = Frictionless() if friction is None else friction
        if not isinstance(friction, (Frictionless, Tresca, Coulomb)):
            raise TypeError("friction must be Frictionless(), Tresca(bound) or Coulomb(F)")
        if len(contact_tags) and obstacle is None:
            raise ValueError("contact_tags are given but no obstacle")
        if obstacle is not None and not callable(getattr(obstacle, "gaps_and_normals", None)):
            raise TypeError("obstacle must be a PlaneObstacle, a NodalObstacle or an object with "
                            f"gaps_and_normals(points), got {type(obstacle).__name__}")
        for bc in dirichlet:
            if not isinstance(bc, Dirichlet):
                raise TypeError(f"dirichlet must be a sequence of Dirichlet(tags, value), got a {type(bc).__name__}")
            if not callable(bc.value) and (np.ndim(bc.value) != 1 or isinstance(bc.value, str)):
                raise TypeError("a Dirichlet value must be a vector (None for a free component) or a callable, "
                                f"got {bc.value!r}")
        for name, nu in (("nu1", nu1), ("nu2", nu2)):
            if isinstance(nu, bool) or not isinstance(nu, (int, np.integer)) or not 0 <= nu <= 100:
                raise ValueError(f"{name} must be an integer in 0..100, got {nu!r}")
        if nu1 + nu2 < 1:
            raise ValueError("nu1 + nu2 must be at least 1: a cycle needs smoothing")
        t0 = time.perf_counter()
        self.hierarchy, self.material, self.friction = hierarchy, material, friction
        self.cycle, self.nu1, self.nu2 = cycle, nu1, nu2
        mesh = self.mesh = hierarchy.finest
        d, n = mesh.dim, mesh.num_points
        self.A = _core.assemble_elasticity(mesh.points, mesh.cells, mesh.cell_type, material.E, material.nu)
        self.load = _core.assemble_mass_load(mesh.points, mesh.cells, mesh.cell_type,
                                             _field(body_force, mesh.points, "body_force"))
        for tag, value in (traction or {}).items():
            sel = mesh.facet_tags == tag
            if not np.any(sel):
                raise ValueError(f"no boundary facet carries the traction tag {tag}")
            self.load += _core.assemble_facet_load(mesh.points, mesh.facets[sel],
                                                   _field(value, mesh.points, f"traction[{tag}]"))
        self.fixed = np.zeros((n, d), dtype=np.uint8)
        self.fixed_values = np.zeros((n, d))
        for bc in dirichlet:
            nodes = mesh.boundary_nodes(bc.tags)
            if len(nodes) == 0:
                raise ValueError(f"no boundary facet carries the Dirichlet tags {list(bc.tags)}")
            if callable(bc.value):
                self.fixed[nodes] = 1
                self.fixed_values[nodes] = _field(bc.value, mesh.points[nodes], "Dirichlet value")
                continue
            if len(bc.value) != d:
                raise ValueError(f"a Dirichlet value needs {d} components (None for free), got {len(bc.value)}")
            for a, v in enumerate(bc.value):
                if v is not None:
                    if not np.isfinite(v):
                        raise ValueError("Dirichlet values must be finite")
                    self.fixed[nodes, a] = 1
                    self.fixed_values[nodes, a] = v
        self._check_rigid_motion()
        self.contact = self._contact_boundary(contact_tags, obstacle)
        self.coefficients = friction.coefficients(len(self.contact.nodes), self.contact.measure)
        self._solver = None
        self._solver_build_seconds = 0.0
        self.setup_seconds = time.perf_counter() - t0 + hierarchy.build_seconds

    # -- setup helpers --------------------------------------------------------------------------
    def _check_rigid_motion(self):
        """The Dirichlet dofs must pin every rigid-body motion of the body (no contact relied on)."""
        x = self.mesh.points
        d = self.mesh.dim
        x = x - x.mean(axis=0)
        modes = [np.eye(d)[a][None, :].repeat(len(x), 0) for a in range(d)]
        pairs = [(0, 1)] if d == 2 else [(0, 1), (1, 2), (0, 2)]
        for i, j in pairs:
            r = np.zeros_like(x)
            r[:, i], r[:, j] = -x[:, j], x[:, i]
            modes.append(r)
        R = np.stack([m[self.fixed.astype(bool)] for m in modes], axis=1)
        if R.size == 0 or np.linalg.matrix_rank(R, tol=1e-10 * max(1.0, np.abs(R).max())) < len(modes):
            raise ValueError("the Dirichlet conditions leave rigid-body motion free: "
                             "fix enough displacement components to hold the body")

    def _contact_boundary(self, tags, obstacle) -> ContactBoundary:
        mesh, d = self.mesh, self.mesh.dim
        if not len(tags):
            return ContactBoundary(np.zeros(0, np.int64), np.zeros((0, d)), np.zeros(0), np.zeros(0))
        sel = np.isin(mesh.facet_tags, list(tags))
        if not np.any(sel):
            raise ValueError(f"no boundary facet carries the contact tags {list(tags)}")
        nodes = np.unique(mesh.facets[sel])
        # Dirichlet wins where it fixes every component (e.g. the ends of the Hertz arc on the clamped top edge)
        nodes = nodes[~self.fixed[nodes].all(axis=1)]
        gaps, normals = obstacle.gaps_and_normals(mesh.points[nodes])
        # A node with some fixed components keeps its contact condition in the free directions; one
        # whose normal component is prescribed is no contact node (the core checks it is admissible
        # and refuses a fixed component that is neither normal nor tangential)
        classify = _core.classify_contact_dirichlet_2D if d == 2 else _core.classify_contact_dirichlet_3D
        keep = classify(nodes.astype(np.int64), self.fixed[nodes], self.fixed_values[nodes],
                        np.asarray(normals, float), np.asarray(gaps, float)) < 2
        nodes, gaps, normals = nodes[keep], np.asarray(gaps)[keep], np.asarray(normals)[keep]
        ones = np.ones((mesh.num_points, 1))
        measure = _core.assemble_facet_load(mesh.points, mesh.facets[sel], ones)[nodes, 0]
        return ContactBoundary(nodes.astype(np.int64), np.ascontiguousarray(normals), np.ascontiguousarray(gaps), measure)

    def _make_solver(self, law: str, frame_fixed=None, frame_values=None, load=None):
        d = self.mesh.dim
        cls = _core.ContactSolver2D if d == 2 else _core.ContactSolver3D
        c = self.contact
        return cls(self.A, self.load if load is None else load, self.fixed, self.fixed_values, c.nodes, c.normals,
                   c.gaps, self.coefficients, law, [t.as_tuple() for t in self.hierarchy.transfers], self.cycle,
                   self.nu1, self.nu2, frame_fixed=frame_fixed, frame_values=frame_values)

    @property
    def law(self) -> str:
        return "linear" if len(self.contact.nodes) == 0 else self.friction.law

    @property
    def solver(self):
        if self._solver is None:
            t0 = time.perf_counter()
            self._solver = self._make_solver(self.law)
            self._solver_build_seconds = time.perf_counter() - t0
            self.setup_seconds += self._solver_build_seconds
        return self._solver

    # -- solving --------------------------------------------------------------------------------
    def solve(self, method: str = "nmg", tol: float = 1e-11, rtol: float = 0.0, max_cycles: int = 200,
              u0: Optional[np.ndarray] = None, reference: Optional[ContactResult] = None,
              fixed_point_tol: float = 1e-9, fixed_point_max: int = 100,
              error_reference: Optional[np.ndarray] = None) -> ContactResult:
        """Solve with `method`: "nmg" (Algorithm 2 for Coulomb; truncated monotone multigrid for
        frictionless and Tresca; linear multigrid without contact), "fixed-point" (Algorithm 1,
        Coulomb only) or "linear" (the cost reference: the linear problem with the contact state of
        `reference` — or of an nmg solve made first — known in advance, started from zero).
        With `error_reference` (a displacement u*), history["error"] records ||u - u*||_A after
        every cycle (one extra matrix product per cycle, kept out of the timings)."""
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        for name, v in (("tol", tol), ("rtol", rtol), ("fixed_point_tol", fixed_point_tol)):
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
        if tol == 0 and rtol == 0:
            raise ValueError("one of tol and rtol must be positive")
        for name, v in (("max_cycles", max_cycles), ("fixed_point_max", fixed_point_max)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        kw = dict(tol=tol, rtol=rtol, max_cycles=int(max_cycles), fixed_point_tol=fixed_point_tol,
                  fixed_point_max=int(fixed_point_max), reference=error_reference)
        if method == "fixed-point":
            if not isinstance(self.friction, Coulomb) or self.law == "linear":
                raise ValueError("the fixed-point method (Algorithm 1) needs Coulomb friction on a contact boundary")
            raw = self.solver.solve(u0, fixed_point=True, **kw)
        elif method == "nmg":
            raw = self.solver.solve(u0, **kw)
        else:
            if reference is None:
                reference = self.solve("nmg", tol=tol, rtol=rtol, max_cycles=max_cycles)
            t0 = time.perf_counter()
            solver = self._known_state_solver(reference)
            build = time.perf_counter() - t0
            raw = solver.solve(None, **kw)
            raw["contact_force"], raw["friction_bound"], raw["state"] = self._contact_outputs_linear(raw, reference)
            res = ContactResult.from_raw(self, raw, method)
            # building its hierarchy for the known state is setup, like the nmg solver's own build
            res.setup_seconds = self.setup_seconds - self._solver_build_seconds + build
            res.extra["reference"] = {"method": reference.method, "cycles": reference.cycles,
                                      "solve_seconds": reference.solve_seconds, "converged": reference.converged}
            return res
        return ContactResult.from_raw(self, raw, method)

    def _known_state_solver(self, ref: ContactResult):
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
        frames = self.solver.frames
        s_local = np.zeros_like(ref.contact_force)
        s_local[slip, 1:] = ref.contact_force[slip, 1:]
        load[c.nodes] += np.einsum("cij,cj->ci", frames, s_local)
        return self._make_solver("linear", fixed, values, load)

    def _contact_outputs_linear(self, raw, ref):
        # the linear reference knows no contact law; report the contact forces it produced
        frames = self.solver.frames
        u = raw["u"]
        f = self.A.matvec(u) - self.load
        cf = np.einsum("cji,cj->ci", frames, f[self.contact.nodes])
        return cf, ref.friction_bound.copy(), ref.node_state[self.contact.nodes].copy()


def _frames(normals: np.ndarray) -> np.ndarray:
    """The frames Q = [n, t(, s)] of the core (columns), for given unit normals."""
    nc, d = normals.shape
    Q = np.zeros((nc, d, d))
    n = normals / np.linalg.norm(normals, axis=1)[:, None] if nc else normals
    Q[:, :, 0] = n
    if d == 2:
        Q[:, 0, 1], Q[:, 1, 1] = -n[:, 1], n[:, 0]
    else:
        for c in range(nc):
            k = int(np.argmin(np.abs(n[c])))
            e = np.zeros(3)
            e[k] = 1
            t = np.cross(n[c], e)
            t /= np.linalg.norm(t)
            Q[c, :, 1], Q[c, :, 2] = t, np.cross(n[c], t)
    return Q
