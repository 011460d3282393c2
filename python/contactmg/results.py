"""Results of a solve: named fields, derived contact quantities, VTU output."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Dict, Optional

import numpy as np

from .mesh import Mesh

if TYPE_CHECKING:  # pragma: no cover
    from .problem import ContactProblem

# node_state values
NOT_CONTACT, FREE, STICK, SLIP = -1, 0, 1, 2


@dataclass
class ContactResult:
    """Displacement and contact quantities of one solve.

    contact_force: (A u - f) at the contact nodes in their frames [n, t(, s)] — the nodal force the
    obstacle exerts on the body; normal component <= 0 in compression. normal_stress and
    tangential_stress divide it by the lumped boundary measure of each node."""

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

    @classmethod
    def from_raw(cls, problem: "ContactProblem", raw: dict, method: str) -> "ContactResult":
        c = problem.contact
        state = np.full(problem.mesh.num_points, NOT_CONTACT, dtype=np.int8)
        state[c.nodes] = raw["state"]
        return cls(mesh=problem.mesh, method=method, law=problem.law, displacement=raw["u"],
                   contact_nodes=c.nodes, contact_normals=c.normals, contact_force=raw["contact_force"],
                   measure=c.measure, friction_bound=raw["friction_bound"], node_state=state,
                   history={k: np.asarray(v) for k, v in raw["history"].items()}, converged=bool(raw["converged"]),
                   status=raw["status"], cycles=int(raw["cycles"]),
                   outer_iterations=int(raw["outer_iterations"]) if method == "fixed-point" else None,
                   rebuilds=int(raw["rebuilds"]), setup_seconds=problem.setup_seconds, solve_seconds=float(raw["seconds"]),
                   sweep_check=float(raw["sweep_check"]), phase_seconds=dict(raw["phase_seconds"]))

    # -- contact quantities ---------------------------------------------------------------------
    @property
    def normal_stress(self) -> np.ndarray:
        return self.contact_force[:, 0] / self.measure

    @property
    def tangential_stress(self) -> np.ndarray:
        return self.contact_force[:, 1:] / self.measure[:, None]

    @property
    def contact_state(self) -> np.ndarray:
        return self.node_state[self.contact_nodes]

    @property
    def reaction(self) -> np.ndarray:
        """Total force of the obstacle on the body (canonical frame)."""
        from .problem import _frames

        if len(self.contact_nodes) == 0:
            return np.zeros(self.mesh.dim)
        return np.einsum("cij,cj->i", _frames(self.contact_normals), self.contact_force)

    def halfwidth(self, states=(STICK, SLIP), axis: int = 0, center: float = 0.0) -> float:
        """Largest |x_axis - center| over contact nodes in the given states (0 if none)."""
        sel = np.isin(self.contact_state, states)
        if not np.any(sel):
            return 0.0
        return float(np.max(np.abs(self.mesh.points[self.contact_nodes[sel], axis] - center)))

    @property
    def contact_halfwidth(self) -> float:
        return self.halfwidth((STICK, SLIP))

    @property
    def stick_halfwidth(self) -> float:
        return self.halfwidth((STICK,))

    def counts(self) -> Dict[str, int]:
        s = self.contact_state
        return {"contact_nodes": int(np.sum(s > 0)), "stick_nodes": int(np.sum(s == STICK)),
                "slip_nodes": int(np.sum(s == SLIP))}

    # -- output ---------------------------------------------------------------------------------
    def point_data(self) -> Dict[str, np.ndarray]:
        n, d = self.mesh.num_points, self.mesh.dim
        sn = np.zeros(n)
        st = np.zeros((n, d - 1))
        sn[self.contact_nodes] = self.normal_stress
        st[self.contact_nodes] = self.tangential_stress
        return {"displacement": self.displacement, "normal_stress": sn,
                "tangential_stress": st[:, 0] if d == 2 else st, "node_state": self.node_state.astype(np.int32)}

    def write_vtu(self, path) -> None:
        """Write the mesh with point data displacement, normal_stress, tangential_stress, node_state."""
        from .io import write_mesh

        write_mesh(path, self.mesh, point_data=self.point_data())
