"""Results of a solve: named fields, derived contact quantities, VTU output."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Dict, Optional, Sequence

import numpy as np

from ..model.frames import contact_frames, to_canonical
from ..mesh.mesh import Mesh

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
        """The result of the core's raw output `raw` for `problem` (a ContactProblem)."""
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

    # -- output ---------------------------------------------------------------------------------
    def point_data(self) -> Dict[str, np.ndarray]:
        """The per-node fields written to VTU files (displacement, contact state and stresses)."""
        n, d = self.mesh.num_points, self.mesh.dim
        sn = np.zeros(n)
        st = np.zeros((n, d - 1))
        sn[self.contact_nodes] = self.normal_stress
        st[self.contact_nodes] = self.tangential_stress
        return {"displacement": self.displacement, "normal_stress": sn,
                "tangential_stress": st[:, 0] if d == 2 else st, "node_state": self.node_state.astype(np.int32)}

    def write_vtu(self, path) -> None:
        """Write a VTU file (ParaView) of the mesh with point data displacement, normal_stress,
        tangential_stress, node_state. Other formats: io.write_mesh(path, result.mesh,
        point_data=result.point_data())."""
        from ..mesh.io import write_mesh

        if not os.fspath(path).lower().endswith(".vtu"):
            raise ValueError(f"write_vtu writes VTU files: {os.fspath(path)} does not end in .vtu (for other formats use "
                             "contactmg.write_mesh(path, result.mesh, point_data=result.point_data()))")
        write_mesh(path, self.mesh, point_data=self.point_data())


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
