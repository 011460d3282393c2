"""The solver of a Problem: builds the core once and solves it for what changes from one load step
to the next (load, prescribed displacements, slip origin, start value)."""
from __future__ import annotations

import time
import weakref
from typing import Callable, Optional

import numpy as np

from .. import _core
from ..model.frames import to_canonical, to_local
from ..model.problem import Problem
from ..results.result import ContactResult
from .options import BUILD_FIELDS, SolverOptions, options_from, resolve_options


def memory_report(problem: Problem, core=None) -> dict:
    """Bytes held now by `problem` and a built `core` (None: none yet), by owner: mesh_hierarchy,
    transfers, problem_vectors, python_matrix, core, and their sum, total."""
    h = problem.hierarchy.memory_bytes()
    out = {"mesh_hierarchy": h["meshes"], "transfers": h["transfers"], "problem_vectors": problem.vector_bytes(),
           "python_matrix": problem.matrix_bytes(), "core": int(core.memory_bytes()) if core is not None else 0}
    out["total"] = sum(out.values())
    return out


# The final check of a converged solve: its tolerance is FINAL_CHECK_FACTOR times the stop's
# relative level (at least VIOLATION_TOL), and a solve that fails it goes on from its iterate at most
# this many times while cycles are left.
FINAL_CHECK_FACTOR = 1e4
FINAL_CHECK_RESTARTS = 2


def final_check_tol(opts: SolverOptions, first_correction=None, solution_norm=None) -> float:
    """The final check's tolerance for a solve stopped by `opts`: FINAL_CHECK_FACTOR times the stop's
    relative level (an absolute tol relative to the larger of the first correction and ||u||_A), at
    least VIOLATION_TOL."""
    from ..results.checks import VIOLATION_TOL

    tol_abs, rtol = opts.stop
    if first_correction is not None:
        size = max(float(first_correction), float(solution_norm or 0.0), 1e-300)
        level = max(rtol, tol_abs / size)
    else:
        level = rtol
    return max(VIOLATION_TOL, FINAL_CHECK_FACTOR * level)


def failed_check_status(violations: dict, tol: float) -> str:
    """The status of a solve whose stop was met but whose final check found `violations` above `tol`."""
    worst = max((k for k in violations if k != "max"), key=violations.get)
    return (f"not converged: the cycles' stop was met, but the final check finds {worst} {violations[worst]:.3g} "
            f"(relative to the problem's force and displacement scales; tolerance {tol:.3g})")


def _joined(first: dict, then: dict) -> dict:
    """The raw result of a solve that went on from `first` with `then`: then's iterate and figures,
    the cycles and history of both."""
    out = dict(then)
    out["cycles"] = int(first["cycles"]) + int(then["cycles"])
    hist = {}
    for k, v in then["history"].items():
        a = np.asarray(first["history"].get(k, []))
        b = np.asarray(v)
        if k == "cycle":
            b = b + int(first["cycles"])
        hist[k] = np.concatenate([a, b]) if a.shape[1:] == b.shape[1:] else b
    out["history"] = hist
    return out


class Solver:
    """The core solver of `problem` (a Problem) with `options` (a SolverOptions, a dict of its
    fields, or None: the defaults), built once here. For a DistributedProblem, its
    DistributedSolver (the same call on every rank). Options fixed at the build (ordering,
    local_smoothing, release_hierarchy; ordering as the storage of the levels) hold for every solve; the
    others may change per solve."""

    def __new__(cls, problem=None, options=None, **kwargs):
        # a problem on MPI ranks (contactmg.distributed.DistributedProblem) names its own solver:
        # one way to solve every problem kind, without this layer importing the distributed one
        make = getattr(problem, "distributed_solver", None)
        if cls is Solver and callable(make):
            return make(options)
        return super().__new__(cls)

    def __init__(self, problem: Problem, options=None, *, _kept: bool = False):
        if not isinstance(problem, Problem):
            raise TypeError(f"problem must be a Problem, got {type(problem).__name__}")
        # The solver a problem keeps for problem.solve refers back to it weakly: no reference cycle,
        # so a dropped problem frees its core at once (not at a later garbage collection, whose
        # timing would move large frees into other solves).
        self._problem = weakref.ref(problem) if _kept else problem
        # the options as given (None where resolve_options decides): with_options and per-solve dicts change these
        self.requested = options_from(options)
        self.options = resolve_options(problem, self.requested)
        t0 = time.perf_counter()
        self.core = self._build(problem.law, self.options, take_matrix=True)
        if self.options.local_smoothing:
            self._smooth_locally(self.core)
        self.build_seconds = time.perf_counter() - t0
        # The data the kept core holds from the last solve that set it (None: the problem's own; no
        # slip origin): every result records what it was solved with, for its checks. One dict,
        # shared with the with_options copies that solve on the same core.
        self._given = {"load": None, "fixed_values": None, "slip_origin": None}
        if self.options.release_hierarchy:
            problem.hierarchy.release_coarse()
            problem.release_vectors()
            # made for one solve: the cycles' workspace need not outlive it (the lower peak)
            self.core.keep_workspace(False)

    @property
    def problem(self) -> Problem:
        """The problem this solver solves."""
        p = self._problem
        return p() if isinstance(p, weakref.ref) else p

    # -- building -------------------------------------------------------------------------------
    def _build(self, law: str, options: SolverOptions, frame_fixed=None, frame_values=None, load=None,
               take_matrix: bool = False, fixed_values=None):
        p, c = self.problem, self.problem.contact
        cls = _core.ContactSolver2D if p.mesh.dim == 2 else _core.ContactSolver3D
        build = dict(cycle=options.cycle, nu1=options.nu1, nu2=options.nu2, ordering=options.ordering)
        A, taken = p.take_matrix() if take_matrix else (p.A, False)
        core = cls(A, p.load if load is None else load, p.fixed, p.fixed_values if fixed_values is None else fixed_values, c.nodes, c.normals, c.gaps,
                   p.coefficients, law, [t.as_tuple() for t in p.transfers], build,
                   frame_fixed=frame_fixed, frame_values=frame_values, take_matrix=taken)
        if p.tied_correction and law != "linear":
            core.enable_tied_correction()
        return core

    def _smooth_locally(self, core) -> None:
        """Coarse level l (1 <= l < finest; the coarsest is solved exactly) smooths only the nodes
        whose hat functions differ from level l-1 (MeshHierarchy.changed_nodes): elsewhere its
        space is the one below, whose correction the cycle computes anyway (0004-local-smoothing)."""
        p = self.problem
        if not p.coarse_levels_match_meshes():
            return  # unknowns other than the mesh nodes (several bodies): keep every row
        h = p.hierarchy
        for level in range(1, h.levels - 1):
            if core.level_sizes[level] != h.meshes[level].num_points:
                return
        for level in range(1, h.levels - 1):
            core.set_rows_to_smooth(level, h.changed_nodes(level))

    def with_options(self, **changes) -> "Solver":
        """A solver on the same built core whose solves take these option changes (not the fields
        fixed at the build)."""
        fixed = [k for k in changes if k in BUILD_FIELDS and changes[k] != getattr(self.options, k)]
        if fixed:
            raise ValueError(f"{', '.join(fixed)} cannot change per solve: the core is built with it (make a new Solver)")
        other = object.__new__(Solver)
        other.__dict__.update(self.__dict__)
        other._problem = self.problem  # held: the copy may outlive a problem that keeps this solver
        other.requested = self.requested.replace(**changes)
        other.options = resolve_options(self.problem, other.requested)
        return other

    def new_core(self, load: Optional[np.ndarray] = None, fixed_values: Optional[np.ndarray] = None):
        """A further core solver of the problem with this solver's build options (the problem's
        matrix copied, not taken over), with its own `load` and `fixed_values` where given: for
        comparisons against the kept core."""
        return self._build(self.problem.law, self.options, load=load, fixed_values=fixed_values)

    def memory_bytes(self) -> dict:
        """Bytes held now, by owner: the hierarchy's meshes and transfers (Python), the problem's
        vectors (load, Dirichlet data, contact boundary, coefficients), an assembled matrix held in
        Python, and the built core (matrices, prolongations, vectors); "total" is their sum. Nothing
        is made again to count it (a released hierarchy stays so)."""
        return memory_report(self.problem, self.core)

    # -- solving --------------------------------------------------------------------------------
    def solve(self, u0: Optional[np.ndarray] = None, *, load: Optional[np.ndarray] = None,
              fixed_values: Optional[np.ndarray] = None, slip_origin: Optional[np.ndarray] = None,
              options=None, progress: Optional[Callable[[dict], None]] = None,
              error_reference: Optional[np.ndarray] = None) -> ContactResult:
        """Solve from `u0` (None: zero). `load` (n, d) and `fixed_values` (n, d) replace the core's
        (they stay for later solves: a load path's step), `slip_origin` (n, d) is the displacement
        the incremental friction law measures slip from. `options`: a SolverOptions or a dict of
        changes to this solver's options for this solve (not the build's fields). `progress(record)`
        is called after every cycle with a dict (cycle, outer, correction_norm, energy, seconds,
        error, active, stick, slip, rebuilt); an exception it raises stops the solve. With
        `error_reference` (u*), history["error"] records ||u - u*||_A after every cycle. Method
        "linear" solves with "nmg" first for the contact state (see solve_known_state)."""
        opts = self._options_for(options)
        if progress is not None and not callable(progress):
            raise ValueError(f"progress must be a callable (called with a dict after every cycle), got {progress!r}")
        p = self.problem
        if opts.method == "fixed-point" and (p.friction.law != "coulomb" or p.law == "linear"):
            raise ValueError("the fixed-point method (Algorithm 1) needs Coulomb friction on a contact boundary")
        if load is not None:
            self._given["load"] = np.array(load, dtype=float)  # a copy: the caller may reuse its array
            self.core.set_load(self._given["load"])
        if fixed_values is not None:
            self._given["fixed_values"] = np.array(fixed_values, dtype=float)
            self.core.set_fixed_values(self._given["fixed_values"])
        if slip_origin is not None:
            self._given["slip_origin"] = np.array(slip_origin, dtype=float)
            self.core.set_slip_origin(self._given["slip_origin"])
        if opts.method == "linear":
            reference = self.solve(None, options=opts.replace(method="nmg"))
            return self.solve_known_state(reference, opts, progress=progress, error_reference=error_reference)
        nested = None
        if u0 is None and opts.start == "nested" and slip_origin is None and self._given["slip_origin"] is None:
            u0, nested = self._nested_start(opts)
        raw = self.core.solve(u0, opts.to_core(), progress=progress, reference=error_reference)
        res = self._result(raw, opts, self.build_seconds)
        # "converged" only after the final check: a cycle's stop measures the step, which a nearly
        # free motion (a body held by contact) or a stalled iterate can make small while the
        # equations are not solved. Cycles left go on from the iterate; then the verdict.
        passed = not res.converged or self._passes_final_check(res, opts)
        for _ in range(FINAL_CHECK_RESTARTS):
            left = opts.max_cycles - res.cycles
            if passed or left <= 0:
                break
            more = self.core.solve(raw["u"], opts.replace(max_cycles=left).to_core(), progress=progress,
                                   reference=error_reference)
            raw = _joined(raw, more)
            res = self._result(raw, opts, self.build_seconds)
            passed = not res.converged or self._passes_final_check(res, opts)
        if nested is not None:
            res.extra["nested_start"] = nested
            res.solve_seconds += nested["seconds"]
        if not passed:
            res.converged = False
            res.status = failed_check_status(res.extra["final_check"], res.extra["final_check_tol"])
        return res

    def _nested_start(self, opts: SolverOptions):
        """(start, record) of the nested start (solve/nested.py) with this solve's options, load and
        Dirichlet values; start None where the hierarchy gives none or it would not help."""
        from .nested import nested_start

        p = self.problem
        load = self._given["load"] if self._given["load"] is not None else p.load
        values = self._given["fixed_values"] if self._given["fixed_values"] is not None else p.fixed_values
        build = dict(cycle=opts.cycle, nu1=opts.nu1, nu2=opts.nu2, ordering=opts.ordering)
        start, record = nested_start(p, opts.to_core(), build, load, values)
        if self.options.release_hierarchy:
            p.release_vectors()
        return start, record

    def _passes_final_check(self, res: ContactResult, opts: SolverOptions) -> bool:
        """contact_conditions of `res` from the core's residual (no product with a matrix the core has
        taken over), against a tolerance that follows the stop asked for: VIOLATION_TOL at the
        default stop, looser for a looser one. The figures go to res.extra["final_check"]."""
        from ..results.checks import contact_conditions

        v = contact_conditions(self.problem, res, residual=np.asarray(self.core.residual()),
                               stiffness=float(self.core.stiffness_scale()))
        if self.options.release_hierarchy:
            self.problem.release_vectors()  # the check made the load and the Dirichlet values again
        h = res.history
        tol = final_check_tol(opts, h["correction_norm"][0] if len(h.get("correction_norm", ())) else None,
                              h["solution_norm"][-1] if len(h.get("solution_norm", ())) else None)
        res.extra["final_check"], res.extra["final_check_tol"] = v, tol
        return v["max"] <= tol

    def _options_for(self, options) -> SolverOptions:
        if options is None:
            return self.options
        if isinstance(options, SolverOptions):
            given = options
        elif isinstance(options, dict):
            given = self.requested.replace(**options)
        else:
            raise TypeError(f"options must be a SolverOptions or a dict, got {type(options).__name__}")
        opts = resolve_options(self.problem, given)
        fixed = [k for k in BUILD_FIELDS if getattr(opts, k) != getattr(self.options, k)]
        if fixed:
            raise ValueError(f"{', '.join(fixed)} cannot change per solve: the core is built with it (make a new Solver)")
        return opts

    def solve_known_state(self, reference: ContactResult, options=None, progress=None,
                          error_reference: Optional[np.ndarray] = None) -> ContactResult:
        """The cost reference (method "linear"): the linear problem with the final contact state of
        `reference` known (active normals fixed on the gap, sticking tangentials fixed at zero, sliding
        nodes loaded with their friction force), started from zero on a core built for it."""
        opts = self._options_for(options).replace(method="linear")
        p, c = self.problem, self.problem.contact
        d = p.mesh.dim
        fixed, values, load = np.zeros((len(c.nodes), d), np.uint8), np.zeros((len(c.nodes), d)), p.load.copy()
        state = reference.node_state[c.nodes]
        active = state > 0
        fixed[active, 0] = 1
        values[active, 0] = c.gaps[active]
        stick = state == 1
        fixed[stick, 1:] = 1
        values[stick, 1:] = 0.0
        slip = state == 2
        s_local = np.zeros_like(reference.contact_force)
        s_local[slip, 1:] = reference.contact_force[slip, 1:]
        load[c.nodes] += to_canonical(c.frames, s_local)
        t0 = time.perf_counter()
        core = self._build("linear", opts, fixed, values, load)
        build = time.perf_counter() - t0
        raw = core.solve(None, opts.to_core(), progress=progress, reference=error_reference)
        # The core reports A u - f of its own problem, whose load carries the sliding nodes'
        # friction forces and whose fixed dofs are eliminated; the contact force is A u - f of
        # this problem.
        f = p.A.matvec(raw["u"]) - p.load
        raw["contact_force"] = to_local(c.frames, f[c.nodes])
        raw["friction_bound"] = reference.friction_bound.copy()
        raw["state"] = reference.node_state[c.nodes].copy()
        res = self._result(raw, opts, build)
        res.extra["reference"] = {"method": reference.method, "cycles": reference.cycles,
                                  "solve_seconds": reference.solve_seconds, "converged": reference.converged}
        return res

    def _result(self, raw: dict, opts: SolverOptions, build_seconds: float) -> ContactResult:
        p = self.problem
        raw = dict(raw)
        raw["u"] = p.to_canonical(np.asarray(raw["u"]))
        res = ContactResult.from_raw(p, raw, opts.method)
        res.setup_seconds = p.assembly_seconds + build_seconds
        res.problem = p
        res.load, res.fixed_values, res.slip_origin = (self._given[k] for k in ("load", "fixed_values", "slip_origin"))
        if len(p.contact.nodes):
            res.frame_fixed = np.asarray(self.core.frame_fixed)
        res.options = opts.to_dict()
        res.extra["cycle_options"] = {"cycle": opts.cycle, "nu1": opts.nu1, "nu2": opts.nu2}
        res.extra["omega"] = float(raw.get("omega", 1.0))
        if "omega_post" in raw:  # only when it differs from omega
            res.extra["omega_post"] = float(raw["omega_post"])
        if raw.get("petrov_galerkin"):
            pg = np.asarray(raw["history"]["petrov_galerkin"])
            off = np.nonzero(pg == 2)[0]
            res.extra["petrov_galerkin"] = {"cycles": int(np.count_nonzero(pg)),
                                            "fallback_cycle": int(off[0]) + 1 if len(off) else None}
        if raw.get("upwind_contact_sweep"):
            res.extra["upwind_contact_sweep"] = True
        if raw.get("projected_coarse_correction"):
            res.extra["projected_coarse_correction"] = True
        if raw.get("switched_at"):  # Algorithm 2 went on with TNNMG after this cycle (switch_rate)
            res.extra["switched_to_tnnmg_after"] = int(raw["switched_at"])
        if opts.method == "fixed-point" and "outer_changes" in raw:
            res.extra["outer_changes"] = [float(c) for c in raw["outer_changes"]]
        if "threads" in raw:
            res.extra["threads"], res.extra["ordering"] = int(raw["threads"]), str(raw["ordering"])
        if p.multibody:
            res.extra["body_id"] = p.body_id
        return res
