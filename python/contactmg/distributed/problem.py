"""A contact problem solved on MPI ranks: the description of one body against a rigid obstacle on a
DistributedHierarchy, and its solve by the nonlinear monotone multigrid of Algorithm 2
(frictionless, Tresca and Coulomb contact), the same cycle as the serial solver's on each rank's
part.

    comm = contactmg.distributed.get_comm()
    h = DistributedHierarchy.build(coarse_mesh, levels, comm, projector=...)
    problem = DistributedProblem(h, Material(E, nu), [Dirichlet(...)], contact_tags=[...],
                                 obstacle=PlaneObstacle(...), friction=Coulomb(0.4))
    result = problem.solve(SolverOptions(cycle="V"))
    result.write_pvtu("out/result.pvtu")

Run it with `mpirun -n N python script.py`; on one process it runs without MPI. Every rank returns
the same cycle counts, norms and status; the displacement of each node is the same on every number
of ranks, bit for bit."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from ..model.friction import Frictionless
from ..model.problem import Dirichlet
from ..solve.options import DEFAULT_OMEGA, SolverOptions, options_from
from .comm import get_comm, is_serial, op, raise_together
from .cycle import DistributedMonotoneStep
from .fine_level import LocalFine, check_description

PHASES = ("pre_smooth", "linearize", "coarse_update", "coarse_correction", "post_smooth", "norm")
# the fields of a cycle's record in DistributedResult.history
RECORD_KEYS = ("cycle", "correction_norm", "energy", "solution_norm", "active", "stick", "slip", "seconds", "rebuilt")


def resolve(options, cell_type: str) -> SolverOptions:
    """The SolverOptions of a distributed solve (None: the defaults) with what the ranks need
    decided: the smoothing weights (omega_post as omega where not given) and the threads per rank
    (one unless asked: ranks usually take a core each, and 0, the serial "every core", would put every
    rank's threads on every core); a ValueError for what is not distributed yet."""
    o = options_from(options)
    if o.method not in (None, "nmg"):
        raise ValueError(f"method {o.method!r} is not distributed yet: the distributed solve is truncated monotone "
                         "multigrid (method 'nmg'); solve on one rank for the others")
    for name in ("petrov_galerkin", "upwind_contact_sweep", "projected_coarse_correction", "local_smoothing"):
        if getattr(o, name, None):
            raise ValueError(f"{name} is not distributed yet: solve on one rank")
    if o.lines:
        raise ValueError("line smoothers are not distributed yet: solve on one rank")
    if o.start == "nested":
        raise ValueError("the nested start is not distributed yet: solve on one rank, or start from zero")
    omega = float(o.omega) if o.omega is not None else float(DEFAULT_OMEGA.get(cell_type, 1.0))
    post = float(o.omega_post) if o.omega_post is not None else omega
    return o.replace(method="nmg", omega=omega, omega_post=post, threads=int(o.threads) if o.threads > 0 else 1)


def __getattr__(name):
    if name == "DistributedOptions":
        import warnings

        warnings.warn("DistributedOptions is deprecated: a distributed solve takes SolverOptions (resolve() gives "
                      "them with the ranks' choices made)", DeprecationWarning, stacklevel=2)
        return SolverOptions
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass
class DistributedResult:
    """The solve on this rank: `u` (local nodes, (n, d), global x/y(/z) components), the global
    facts (converged, status, cycles, history: one dict per cycle), the seconds of the solve and of
    each phase on this rank, `ranks`, and the hierarchy the local nodes belong to."""

    u: np.ndarray
    converged: bool
    status: str
    cycles: int
    history: List[dict]
    seconds: float
    build_seconds: float
    phase_seconds: Dict[str, float]
    ranks: int
    memory_bytes: int
    hierarchy: object = field(repr=False)
    notes: List[str] = field(default_factory=list)
    # the contact zone: the total force of the obstacle on the body (global components), the nodes
    # touching (stick, slip), the largest distance of a touching (sticking) node from the line x = 0
    # (2D) or the z axis (3D), the largest normal stress (contact force over the lumped boundary
    # measure); the coarse hierarchies built
    reaction: np.ndarray = None
    contact_nodes: int = 0
    stick_nodes: int = 0
    slip_nodes: int = 0
    contact_halfwidth: float = 0.0
    stick_halfwidth: float = 0.0
    max_normal_stress: float = 0.0
    central_pressure: float = 0.0
    rebuilds: int = 0
    exchanges: int = 0     # halo exchanges of the solve on this rank (one per colour of a sweep, ...)
    whole_levels: int = 0  # coarse levels held whole by every rank
    # the final check of a stop the cycles met (results.checks.contact_conditions' figures, the same
    # on every rank) and its tolerance; None where the cycles did not stop
    final_check: Optional[Dict[str, float]] = None
    final_check_tol: Optional[float] = None

    @property
    def level(self):
        """The finest level of the hierarchy: the local nodes of `u`."""
        return self.hierarchy.levels[-1]

    def gathered_u(self, root: int = 0) -> Optional[np.ndarray]:
        """The displacement of every node (global node order, the serial hierarchy's) on `root`;
        None on the other ranks. Collective."""
        lev, comm = self.level, self.hierarchy.comm
        owned = np.flatnonzero(lev.owner == lev.rank)
        mine = (lev.gid[owned], self.u[owned])
        parts = [mine] if is_serial(comm) else comm.gather(mine, root=root)
        if comm.rank != root:
            return None
        out = np.zeros((lev.num_global_nodes, self.u.shape[1]))
        for g, v in parts:
            out[g] = v
        return out

    def write_pvtu(self, path) -> None:
        """The displacement as a parallel .pvtu: one piece per rank (collective)."""
        from .output import write_pvtu
        write_pvtu(path, self.level, {"displacement": self.u}, comm=self.hierarchy.comm)

    def write_vtu(self, path, root: int = 0) -> None:
        """The displacement gathered into one .vtu on `root`, in global node order (collective)."""
        from .output import write_gathered_vtu
        write_gathered_vtu(path, self.level, {"displacement": self.u}, comm=self.hierarchy.comm, root=root)


class DistributedProblem:
    """Linear elasticity of one body on a DistributedHierarchy with contact on its `contact_tags`
    facets against the rigid `obstacle`: Frictionless() (the default), Tresca(bound) or
    Coulomb(coefficient); loads: body force, gravity, tractions and pressures as in Body.
    Collective: every rank builds its part."""

    def __init__(self, hierarchy, material, dirichlet: Sequence[Dirichlet] = (), contact_tags: Sequence[int] = (),
                 obstacle=None, friction=None, body_force=None, traction=None, pressure=None, gravity=None,
                 point_loads=(), springs=None):
        t0 = time.perf_counter()
        self.hierarchy = hierarchy
        comm = self.comm = hierarchy.comm
        friction = Frictionless() if friction is None else friction
        self.friction = friction
        dirichlet = [dirichlet] if isinstance(dirichlet, Dirichlet) else list(dirichlet)
        with raise_together(comm):
            check_description(material, friction, point_loads, springs)
            if len(hierarchy.levels) < 2:
                raise ValueError("a distributed solve needs at least two levels")
            if len(contact_tags) and obstacle is None:
                raise ValueError("contact tags need an obstacle")
            self.fine = LocalFine(hierarchy.levels[-1], hierarchy.cell_type, material, dirichlet, contact_tags, obstacle,
                                  friction, body_force, traction, pressure, gravity)
        found = self.fine.found_dirichlet.astype(int)
        contacts = len(self.fine.owned_contacts)
        contact_facets = int(self.fine.found_contact)
        if not is_serial(comm):
            found = np.max(comm.allgather(np.atleast_1d(found)), axis=0)
            contacts = comm.allreduce(contacts, op=op(comm, "SUM"))
            contact_facets = comm.allreduce(contact_facets, op=op(comm, "MAX"))
        with raise_together(comm):
            for bc, f in zip(dirichlet, np.atleast_1d(found)):
                if not f:
                    raise ValueError(f"no boundary facet carries the Dirichlet tags {list(bc.tags)}")
            if len(contact_tags) and contacts == 0 and not contact_facets:
                raise ValueError(f"no boundary facet carries the contact tags {list(contact_tags)}")
            if len(contact_tags) and contacts == 0:
                raise ValueError(f"the contact boundary is empty: every node of the facets tagged {list(contact_tags)} is "
                                 "fixed by Dirichlet data (are the contact tags the Dirichlet tags?)")
        self.num_contact = int(contacts)
        self.assembly_seconds = time.perf_counter() - t0

    def distributed_solver(self, options=None) -> "DistributedSolver":
        """The solver contactmg.Solver(problem, options) makes for this problem. Collective."""
        return DistributedSolver(self, options)

    @property
    def law(self) -> str:
        """The contact law solved: \"linear\" without contact tags, else the friction's."""
        return self.fine.law

    def solve(self, options=None, progress: Optional[Callable[[dict], None]] = None,
              whole_below: Optional[int] = None) -> DistributedResult:
        """Truncated monotone multigrid from u = 0 until ||u^{k+1} - u^k||_A meets the stop of
        `options` (SolverOptions: tol / rtol, cycle, nu1, nu2, omega, max_cycles), confirmed by one
        more sweep and by the final check of the contact conditions and the balance (as a serial
        solve's: `final_check` of the result). `progress(record)` is called on rank 0 after each cycle. The coarse levels of at
        most `whole_below` global nodes (and all below them) are held whole by every rank and swept
        without exchanges (0: none; None: the small levels whose whole size is a small share of a
        rank's fine level, replicated.py); the answer does not depend on it. Collective."""
        comm = self.comm
        with raise_together(comm):
            opt = resolve(options, self.hierarchy.cell_type)
            if whole_below is not None and (isinstance(whole_below, bool) or not isinstance(whole_below, (int, np.integer))
                                            or whole_below < 0):
                raise ValueError(f"whole_below must be an integer >= 0 or None, got {whole_below!r}")
        t0 = time.perf_counter()
        step = DistributedMonotoneStep(comm, self.fine, self.hierarchy, opt, whole_below)
        build = time.perf_counter() - t0
        d, n = self.fine.d, len(self.fine.level.gid)
        u = np.zeros((n, d))
        exchanges_before = step.exchanges()  # the solve's, not the set-up's
        history: List[dict] = []
        t1 = time.perf_counter()
        converged, status, check, check_tol = self._loop(step, u, opt, progress, history)
        seconds = time.perf_counter() - t1
        u_canonical = self.fine.core.to_canonical(u)
        out = DistributedResult(u_canonical, converged, status, len(history), history, seconds, build,
                                dict(step.phase_seconds), comm.size, step.memory_bytes(), self.hierarchy, step.notes)
        out.rebuilds = step.rebuilds
        out.exchanges = step.exchanges() - exchanges_before
        out.whole_levels = step.whole_levels
        out.final_check, out.final_check_tol = check, check_tol
        self._contact_zone(u, out)
        return out

    def _loop(self, step, u: np.ndarray, opt, progress, history: List[dict]):
        """The solver's loop (the core's run_loop: the stop, its sweep check, divergence) around the
        ranks' cycle on u (in place), and the final check of a stop it meets, as the serial Solver
        does: a check that fails goes on from the iterate while cycles are left, then gives the
        verdict. Appends the cycles' records to `history`; returns (converged, status, check, tol)."""
        from .. import _core
        from ..solve.solver import FINAL_CHECK_RESTARTS, failed_check_status, final_check_tol
        from .final_check import final_check

        tol, rtol = opt.stop
        report = progress if progress is not None and self.comm.rank == 0 else None
        check, check_tol = None, None
        for attempt in range(FINAL_CHECK_RESTARTS + 1):
            left = opt.max_cycles - len(history)
            if left <= 0:
                break
            raw = _core.run_loop(lambda: step.iterate(u), lambda: step.record(u), lambda: step.sweep_change(u),
                                 {"tol": tol, "rtol": rtol, "max_cycles": left}, report)
            first = len(history)
            h = raw["history"]
            for k in range(raw["cycles"]):
                rec = {key: h[key][k].item() for key in RECORD_KEYS}
                rec["cycle"] = first + k + 1
                history.append(rec)
            converged, status = bool(raw["converged"]), str(raw["status"])
            if not converged:
                return False, status, check, check_tol
            check = final_check(self.fine, u, self.comm)
            check_tol = final_check_tol(opt, h["correction_norm"][0], h["solution_norm"][-1])
            if check["max"] <= check_tol:
                return True, status, check, check_tol
        return False, failed_check_status(check, check_tol), check, check_tol

    def _contact_zone(self, u: np.ndarray, out: DistributedResult) -> None:
        """The contact facts of `out` from this rank's owned contact nodes, summed or maximized
        over the ranks (sums exact)."""
        from .exchange import exact_sum
        fine, comm, d = self.fine, self.comm, self.fine.d
        mine = fine.owned_contacts
        nodes = fine.contact_nodes[mine]
        r = fine.core.residual(u, nodes.astype(np.int64))[nodes]          # f - A u in the frames
        force_frame = -r                                                   # A u - f: the obstacle's force
        force = np.einsum("cab,cb->ca", fine.frames[mine], force_frame)   # global components
        out.reaction = np.array([exact_sum(force[:, a], comm) for a in range(d)])
        state, _ = fine.core.contact_state(u, mine.astype(np.int64))
        # distance from the x = 0 line (2D) or the z axis (3D): the examples' symmetry axes
        pts = fine.level.points[nodes]
        x = pts[:, 0] if d == 2 else np.hypot(pts[:, 0], pts[:, 1])
        touching, stick = state > 0, state == 1
        stress = np.abs(force_frame[:, 0]) / np.where(fine.measure[mine] > 0, fine.measure[mine], np.inf)
        local = np.array([np.abs(x[touching]).max(initial=0.0), np.abs(x[stick]).max(initial=0.0),
                          stress[touching].max(initial=0.0)])
        counts = np.array([np.count_nonzero(touching), np.count_nonzero(stick), np.count_nonzero(state == 2)])
        if not is_serial(comm):
            local = np.max(comm.allgather(local), axis=0)
            counts = np.sum(comm.allgather(counts), axis=0)
        out.contact_halfwidth, out.stick_halfwidth, out.max_normal_stress = (float(v) for v in local)
        # the normal stress at the contact node nearest the axis (lowest global id among equals)
        k = int(np.argmin(x)) if len(x) else -1
        mine_c = (float(x[k]), int(fine.level.gid[nodes[k]]), float(stress[k])) if k >= 0 else (np.inf, -1, 0.0)
        every = [mine_c] if is_serial(comm) else comm.allgather(mine_c)
        out.central_pressure = min(every)[2]
        out.contact_nodes, out.stick_nodes, out.slip_nodes = (int(v) for v in counts)


class DistributedSolver:
    """contactmg.Solver(problem, options) of a DistributedProblem: the options resolved for the
    ranks once (a ValueError on every rank for what is not distributed yet); solve() is the
    problem's solve with them. Collective."""

    def __init__(self, problem: DistributedProblem, options=None):
        self.problem = problem
        with raise_together(problem.comm):
            self.options = resolve(options, problem.hierarchy.cell_type)

    def solve(self, options=None, progress: Optional[Callable[[dict], None]] = None,
              whole_below: Optional[int] = None) -> DistributedResult:
        """DistributedProblem.solve with this solver's options (or `options`: a SolverOptions, or a
        dict of changes to this solver's)."""
        if isinstance(options, dict):
            options = self.options.replace(**options)
        return self.problem.solve(self.options if options is None else options, progress=progress,
                                  whole_below=whole_below)
