"""Results of a solve: named fields, derived contact quantities, VTU output."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Dict, Optional, Sequence

import numpy as np

from ..model.frames import contact_frames, to_canonical, to_local
from ..mesh.mesh import Mesh
from .checks import VIOLATION_TOL, contact_conditions
from .fields import cell_strain, hooke, nodal_average, problem_cell_moduli, von_mises

# node_state values
NOT_CONTACT, FREE, STICK, SLIP = -1, 0, 1, 2


@dataclass
class ContactResult:
    """Displacement and contact quantities of one solve.

    contact_force: (A u - f) at the contact nodes in their frames [n, t(, s)] — the nodal force the
    obstacle exerts on the body; normal component <= 0 in compression. normal_stress and
    tangential_stress divide it by the lumped boundary measure of each node.

    contact_nodes: the mesh node ids of the contact nodes, in the order of every per-contact-node
    array here (contact_force, contact_normals, contact_frames, measure, friction_bound,
    contact_state): ascending node id. contact_frames (nc, d, d): the frame of each node, columns
    n, t(, s), in which contact_force is given."""

    mesh: Mesh
    method: str
    law: str
    displacement: np.ndarray
    contact_nodes: np.ndarray
    contact_normals: np.ndarray
    contact_force: np.ndarray
    measure: np.ndarray
    friction_bound: np.ndarray
    node_state: np.ndarray
    history: Dict[str, np.ndarray]
    converged: bool
    status: str
    cycles: int
    outer_iterations: Optional[int]
    rebuilds: int
    setup_seconds: float
    solve_seconds: float
    # ||S(u) - u||_A for one more nonlinear smoothing sweep S at the stop (NaN for linear solves): a
    # solution is a fixed point of the smoother; a stop is confirmed only when this is tiny.
    sweep_check: float = float("nan")
    # seconds per phase of the cycles: presmooth, linearize, coarse_update, coarse_correction,
    # postsmooth, norm, check (their sum is the solve time less the per-cycle bookkeeping)
    phase_seconds: Dict[str, float] = field(default_factory=dict)
    extra: Dict = field(default_factory=dict)
    contact_frames: Optional[np.ndarray] = None
    # the facets (mesh node ids) of the contact boundary: the arc along which zones are measured
    contact_facets: Optional[np.ndarray] = None
    # "hertz" for the Hertz benchmark, whose zones are centred on x = 0 (contact_halfwidth)
    benchmark: Optional[str] = None
    # the solver options the solve used, every problem-dependent default resolved (field -> value)
    options: Optional[Dict] = None
    # The problem solved (the Solver sets it; None for a result made otherwise): checks, reactions,
    # stresses and the summary read its matrix, load, Dirichlet data and materials.
    problem: Optional[object] = field(default=None, repr=False, compare=False)
    # What the solve was given in place of the problem's own, in the problem's unknowns (w for
    # several bodies), None where it used the problem's: the nodal load (n, d), the prescribed
    # displacements (n, d) and the slip origin (n, d), the displacement the incremental friction
    # law measures slip from (a load path's previous step).
    load: Optional[np.ndarray] = field(default=None, repr=False, compare=False)
    fixed_values: Optional[np.ndarray] = field(default=None, repr=False, compare=False)
    slip_origin: Optional[np.ndarray] = field(default=None, repr=False, compare=False)
    # (nc, d) of the contact frames' components fixed by Dirichlet data (the core's frame_fixed)
    frame_fixed: Optional[np.ndarray] = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        if self.contact_frames is None:
            self.contact_frames = contact_frames(self.contact_normals)

    @classmethod
    def from_raw(cls, problem, raw: dict, method: str) -> "ContactResult":
        """The result of the core's raw output `raw` for `problem` (a Problem)."""
        c = problem.contact
        state = np.full(problem.mesh.num_points, NOT_CONTACT, dtype=np.int8)
        state[c.nodes] = raw["state"]
        return cls(mesh=problem.mesh, method=method, law=problem.law, displacement=raw["u"],
                   contact_nodes=c.nodes, contact_normals=c.normals,
                   contact_frames=raw.get("frames", c.frames),  # the core's own, once it returns them
                   contact_facets=c.facets, benchmark=getattr(problem, "benchmark", None),
                   contact_force=raw["contact_force"],
                   measure=c.measure, friction_bound=raw["friction_bound"], node_state=state,
                   history={k: np.asarray(v) for k, v in raw["history"].items()}, converged=bool(raw["converged"]),
                   status=raw["status"], cycles=int(raw["cycles"]),
                   outer_iterations=int(raw["outer_iterations"]) if method == "fixed-point" else None,
                   rebuilds=int(raw["rebuilds"]), setup_seconds=problem.setup_seconds, solve_seconds=float(raw["seconds"]),
                   sweep_check=float(raw["sweep_check"]), phase_seconds=dict(raw["phase_seconds"]))

    # -- contact quantities ---------------------------------------------------------------------
    @property
    def normal_stress(self) -> np.ndarray:
        """The normal contact stress per contact node: normal force over the node's boundary measure."""
        return self.contact_force[:, 0] / self.measure

    @property
    def tangential_stress(self) -> np.ndarray:
        """The tangential contact stress per contact node: tangential force over the node's boundary measure."""
        return self.contact_force[:, 1:] / self.measure[:, None]

    @property
    def contact_state(self) -> np.ndarray:
        """The state per contact node: 0 not in contact, 1 stick, 2 slip."""
        return self.node_state[self.contact_nodes]

    @property
    def reaction(self) -> np.ndarray:
        """Total force of the obstacle on the body (canonical frame)."""
        if len(self.contact_nodes) == 0:
            return np.zeros(self.mesh.dim)
        return to_canonical(self.contact_frames, self.contact_force).sum(axis=0)

    def halfwidth(self, states=(STICK, SLIP), axis: int = 0, center: float = 0.0) -> float:
        """Largest |x_axis - center| over contact nodes in the given states (0 if none): the
        half-width of a zone centred on x_axis = center."""
        sel = np.isin(self.contact_state, states)
        if not np.any(sel):
            return 0.0
        return float(np.max(np.abs(self.mesh.points[self.contact_nodes[sel], axis] - center)))

    def _hertz_halfwidth(self, states, name) -> float:
        if self.benchmark != "hertz":
            raise ValueError(f"{name} measures |x| from x = 0, the symmetry line of the Hertz benchmark; for "
                             f"other problems use {name.replace('halfwidth', 'extent')} (the zone's measure along "
                             "the contact boundary) or halfwidth(states, axis, center)")
        return self.halfwidth(states)

    @property
    def contact_halfwidth(self) -> float:
        """Hertz benchmark only: the largest |x| of a node in contact."""
        return self._hertz_halfwidth((STICK, SLIP), "contact_halfwidth")

    @property
    def stick_halfwidth(self) -> float:
        """Hertz benchmark only: the largest |x| of a sticking node."""
        return self._hertz_halfwidth((STICK,), "stick_halfwidth")

    def extent(self, states: Sequence[int] = (STICK, SLIP)) -> float:
        """The measure (length in 2D, area in 3D) of the part of the contact boundary whose nodes
        are in the given states, each node counting its lumped share of the boundary measure (a
        zone of nodes i..j on a 2D arc measures the arc from half-way before i to half-way after j).
        Meaningful for every problem, whatever its symmetry."""
        sel = np.isin(self.contact_state, states)
        return float(self.measure[sel].sum())

    @property
    def contact_extent(self) -> float:
        """The extent of the contact zone (stick and slip nodes)."""
        return self.extent((STICK, SLIP))

    @property
    def stick_extent(self) -> float:
        """The extent of the stick zone."""
        return self.extent((STICK,))

    @property
    def slip_extent(self) -> float:
        """The extent of the slip zone."""
        return self.extent((SLIP,))

    def arc_length(self) -> np.ndarray:
        """Arc length along the 2D contact boundary at each contact node (order of contact_nodes):
        the contact facets are walked chain by chain from the end with the smallest (x, y); a
        further chain continues where the previous one ended (no distance added between chains)."""
        if self.mesh.dim != 2:
            raise ValueError("arc length along the contact boundary is defined in 2D only; plot against a coordinate")
        if self.contact_facets is None:
            raise ValueError("this result does not know its contact facets")
        return _arc_length(self.mesh.points, self.contact_facets, self.contact_nodes)

    def counts(self) -> Dict[str, int]:
        """The numbers of contact, stick and slip nodes."""
        s = self.contact_state
        return {"contact_nodes": int(np.sum(s > 0)), "stick_nodes": int(np.sum(s == STICK)),
                "slip_nodes": int(np.sum(s == SLIP))}

    # -- engineering output ---------------------------------------------------------------------
    def _known_problem(self, what: str):
        if self.problem is None:
            raise ValueError(f"{what} needs the problem of this result (result.problem, set by the Solver): "
                             "set result.problem = problem")
        return self.problem

    def check(self, raise_on_violation: bool = False, tol: float = VIOLATION_TOL) -> Dict[str, float]:
        """The relative violations of the discrete contact conditions (checks.contact_conditions)
        by this result; with raise_on_violation a ValueError names every one above `tol`."""
        return contact_conditions(self._known_problem("check()"), self, raise_on_violation, tol)

    def canonical_load(self) -> np.ndarray:
        """The nodal load (n, d) of the solve on the canonical displacement (body force and
        tractions of every body, the units as given): for several bodies T^{-T} of the load of
        the unknowns."""
        p = self._known_problem("canonical_load()")
        if self.load is None:
            return p.load_canonical if p.multibody else p.load
        return p.canonical_forces(self.load)

    def residual(self) -> np.ndarray:
        """A u - f (n, d) of the canonical displacement u with the bodies' own stiffness: at a fixed
        component the support reaction, at a contact node the contact force, elsewhere ~0."""
        p = self._known_problem("residual()")
        u = np.asarray(self.displacement, dtype=float)
        Au = (p.A_canonical @ u.ravel()).reshape(u.shape) if p.multibody else p.A.matvec(u)
        return Au - self.canonical_load()

    def spring_forces(self) -> Dict:
        """The force (d,) of each elastic support on its body, in global components: -k u summed
        over the nodes of its facets (k lumped per node, as in the stiffness). Keys: the spring's
        tag, for several bodies (body index, tag). With the reactions, the contact forces and the
        load they balance."""
        from ..model.loads import spring_blocks

        p = self._known_problem("spring_forces()")
        out = {}
        parts = p.parts if p.multibody else [p]
        for k, (part, b) in enumerate(zip(parts, p.bodies)):
            u = self.displacement[p.offsets[k]:p.offsets[k + 1]] if p.multibody else self.displacement
            for tag, stiffness in (b.springs or {}).items():
                blocks = spring_blocks(part.mesh, {tag: stiffness})
                out[(k, tag) if p.multibody else tag] = -np.einsum("nab,nb->a", blocks, u)
        return out

    def reactions(self) -> Dict:
        """The support reaction of every Dirichlet condition (force vector (d,) in global x, y(, z),
        the units of the load): the sum of A u - f over the components it fixes at the nodes of its
        facets. Keys: its tag (a tuple for several tags; conditions on the same tags add up), for
        several bodies (body index, tag). A component fixed by two conditions counts for the
        first. With the contact forces and the load they balance: sum = -(total load)."""
        p = self._known_problem("reactions()")
        r = self.residual()
        fixed = p.fixed.astype(bool)
        claimed = np.zeros_like(fixed)
        offsets = p.offsets if p.multibody else [0]
        out: Dict = {}
        for k, body in enumerate(p.bodies):
            mesh = body.hierarchy.finest
            for bc in body.dirichlet:
                comps = np.ones(mesh.dim, bool) if callable(bc.value) else np.array([v is not None for v in bc.value])
                mask = np.zeros_like(fixed)
                mask[mesh.boundary_nodes(bc.tags) + offsets[k]] = comps
                mask &= fixed & ~claimed
                claimed |= mask
                key = bc.tags[0] if len(bc.tags) == 1 else tuple(bc.tags)
                key = (k, key) if p.multibody else key
                out[key] = out.get(key, 0.0) + np.where(mask, r, 0.0).sum(axis=0)
        return out

    def contact_forces(self) -> Dict[str, np.ndarray]:
        """The total contact force (d,) in global x, y(, z), the units of the load: one body, key
        "obstacle", the force of the obstacle on the body; with several contacts, keys "pair k" (the
        force of the mortar body on the nonmortar body of pair k, whose mortar body feels its
        opposite) and "obstacle j" (the force of the j-th ObstacleContact's obstacle on its body).
        The sum of A u - f over the contact nodes, less their Dirichlet-fixed components (those
        count as reactions). Without a contact boundary: {}."""
        p = self._known_problem("contact_forces()")
        c = p.contact
        if len(c.nodes) == 0:
            return {}
        f = np.where(p.fixed[c.nodes].astype(bool), 0.0, self.residual()[c.nodes])
        source = p.contact_source
        if not p.multibody and len(p.obstacle_contacts) == 1:
            return {"obstacle": f.sum(axis=0)}
        out = {f"pair {k}": f[source == k].sum(axis=0) for k in range(len(p.pairs))}
        out.update({f"obstacle {j}": f[source == -1 - j].sum(axis=0) for j in range(len(p.obstacle_contacts))})
        return out

    def strain(self, at: str = "cells") -> np.ndarray:
        """The small strain (m, 3, 3), dimensionless: at="cells" at every cell centroid, at="nodes"
        recovered at the nodes (the measure-weighted average of their cells'). 2D: plane strain."""
        return self._at(cell_strain(self.mesh, self.displacement), at)

    def stress(self, at: str = "cells") -> np.ndarray:
        """The Cauchy stress (m, 3, 3) in the units of E (Hooke's law with each cell's E and nu, 2D
        plane strain: sigma_zz = nu (sigma_xx + sigma_yy)): at="cells" at every cell centroid,
        at="nodes" recovered at the nodes (the measure-weighted average of their cells')."""
        E, nu = problem_cell_moduli(self._known_problem("stress()"))
        return self._at(hooke(cell_strain(self.mesh, self.displacement), E, nu), at)

    def von_mises(self, at: str = "cells") -> np.ndarray:
        """The von Mises stress (m,) in the units of E of stress(at): per cell, or of the recovered
        nodal stress."""
        return von_mises(self.stress(at))

    def _at(self, cell_values: np.ndarray, at: str) -> np.ndarray:
        if at == "cells":
            return cell_values
        if at == "nodes":
            return nodal_average(self.mesh, cell_values)
        raise ValueError(f"at must be 'cells' or 'nodes', got {at!r}")

    def slip(self) -> np.ndarray:
        """The slip (n, d) in global x, y(, z), the units of the displacement: at the contact nodes
        in contact (stick or slip) the tangential part of w - w0, w the unknowns (relative to the
        mortar side for several bodies) and w0 the slip origin of the solve (a load path's
        previous step; none: 0), zero elsewhere."""
        w = np.asarray(self.displacement, dtype=float)
        if self.problem is not None:
            w = self.problem.relative_displacement(w)
        if self.slip_origin is not None:
            w = w - self.slip_origin
        local = to_local(self.contact_frames, w[self.contact_nodes])
        local[:, 0] = 0.0
        local[self.contact_state <= FREE] = 0.0
        out = np.zeros_like(w)
        out[self.contact_nodes] = to_canonical(self.contact_frames, local)
        return out

    # -- output ---------------------------------------------------------------------------------
    def point_data(self) -> Dict[str, np.ndarray]:
        """The per-node fields written to VTU files:
        displacement (global x, y(, z)); node_state (-1 no contact node, 0 free, 1 stick, 2 slip);
        contact_pressure (-normal force / boundary measure: positive in compression, 0 off the
        contact nodes); tangential_traction (tangential force / measure, global x, y(, z));
        slip (see slip(), global); normal_stress and tangential_stress (the contact tractions in
        the nodal contact frame [n] and [t(, s)], normal negative in compression); with the
        problem known, von_mises (of the recovered nodal stress); for several bodies body_id (the
        body of each node, to tell the bodies apart in a viewer)."""
        n, d = self.mesh.num_points, self.mesh.dim
        sn = np.zeros(n)
        st = np.zeros((n, d - 1))
        sn[self.contact_nodes] = self.normal_stress
        st[self.contact_nodes] = self.tangential_stress
        tt = np.zeros((n, d))
        local = np.c_[np.zeros(len(self.contact_nodes)), self.tangential_stress]
        tt[self.contact_nodes] = to_canonical(self.contact_frames, local)
        out = {"displacement": self.displacement, "normal_stress": sn,
               "tangential_stress": st[:, 0] if d == 2 else st, "node_state": self.node_state.astype(np.int32),
               "contact_pressure": -sn, "tangential_traction": tt, "slip": self.slip()}
        if self.problem is not None:
            out["von_mises"] = self.von_mises("nodes")
        # here rather than in Problem.write_vtu alone, so that every writer of a result (write_vtu,
        # the load path's series, the command line's outputs) has it
        body_id = self.problem.body_id if self.problem is not None and self.problem.multibody \
            else self.extra.get("body_id")
        if body_id is not None:
            out["body_id"] = np.asarray(body_id, dtype=np.int32)
        return out

    def cell_data(self) -> Dict[str, np.ndarray]:
        """The per-cell fields written to VTU files (the problem known, else none): stress and
        strain at the cell centroids as 9 components xx, xy, xz, yx, ..., zz (ParaView's tensor),
        von_mises."""
        if self.problem is None:
            return {}
        sigma = self.stress()
        m = self.mesh.num_cells
        return {"stress": sigma.reshape(m, 9), "strain": self.strain().reshape(m, 9), "von_mises": von_mises(sigma)}

    def write_vtu(self, path) -> None:
        """Write a VTU file (ParaView) of the mesh with the point data of point_data() and the cell
        data of cell_data(). Other formats: io.write_mesh(path, result.mesh,
        point_data=result.point_data(), cell_data=result.cell_data())."""
        from ..mesh.io import write_mesh

        if not os.fspath(path).lower().endswith(".vtu"):
            raise ValueError(f"write_vtu writes VTU files: {os.fspath(path)} does not end in .vtu (for other formats use "
                             "contactmg.write_mesh(path, result.mesh, point_data=result.point_data()))")
        write_mesh(path, self.mesh, point_data=self.point_data(), cell_data=self.cell_data())

    def _nested_rows(self) -> list:
        """The summary's row of a nested start: each coarse level's cycles and their work in cycles
        of the finest level."""
        rec = self.extra.get("nested_start")
        if not rec or not rec.get("levels"):
            return []
        kept = "" if rec.get("kept") else " (not taken: no lower energy than u = 0)"
        return [("nested start", f"levels {rec['levels'][0]}-{rec['levels'][-1]}: "
                                 f"{' + '.join(str(c) for c in rec['cycles'])} cycles, the work of "
                                 f"{rec['work']:.3g} finest cycles{kept}")]

    def summary(self) -> str:
        """A plain-text table of the solve: method, law, status, cycles, dofs, solve seconds, the
        contact/stick/slip node counts, the contact extent, and with the problem known the total
        contact force, the reactions per Dirichlet tag, the elastic supports' forces per tag (with
        the reactions and contact forces they balance the load), the largest von Mises stress and the
        largest violation of the contact conditions (check())."""
        after = self.extra.get("switched_to_tnnmg_after")
        method = self.method if after is None else f"{self.method}, then tnnmg after cycle {after}"
        rows = [("method", method), ("law", self.law),
                ("converged", f"{self.converged} ({self.status})"), ("cycles", str(self.cycles)),
                *self._nested_rows(),
                ("dofs", str(self.displacement.size)), ("solve seconds", f"{self.solve_seconds:.4g}")]
        rows += [(k.replace("_", " "), str(v)) for k, v in self.counts().items()]
        rows.append(("contact extent", f"{self.contact_extent:.6g}"))
        if self.problem is not None:
            vec = lambda v: "(" + ", ".join(f"{x:.6g}" for x in np.asarray(v)) + ")"
            rows += [(f"contact force {k}", vec(v)) for k, v in self.contact_forces().items()]
            rows += [(f"reaction {k}", vec(v)) for k, v in self.reactions().items()]
            rows += [(f"spring force {k}", vec(v)) for k, v in self.spring_forces().items()]
            rows.append(("max von Mises", f"{float(self.von_mises().max(initial=0.0)):.6g}"))
            check = self.check()
            worst = max((k for k in check if k != "max"), key=lambda k: check[k])
            rows.append(("max violation", f"{check['max']:.3g} ({worst}); penetration {check['penetration']:.3g}"))
        width = max(len(k) for k, _ in rows)
        return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _arc_length(points: np.ndarray, facets: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Arc length of `nodes` along the chains formed by the 2D boundary `facets` (edges)."""
    neighbours: Dict[int, list] = {}
    for a, b in facets.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    s: Dict[int, float] = {}
    offset = 0.0
    while len(s) < len(neighbours):
        todo = [v for v in neighbours if v not in s]
        ends = [v for v in todo if len(neighbours[v]) == 1] or todo  # a closed loop has no end
        v = min(ends, key=lambda k: (points[k, 0], points[k, 1]))
        s[v] = offset
        while True:
            nxt = [w for w in neighbours[v] if w not in s]
            if not nxt:
                break
            w = nxt[0]
            s[w] = s[v] + float(np.linalg.norm(points[w] - points[v]))
            v = w
        offset = s[v]
    return np.array([s.get(int(k), np.nan) for k in nodes])
