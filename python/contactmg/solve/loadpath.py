"""Quasi-static load paths.

A load path is a sequence of load steps k = 1..K, each with its Dirichlet values and its load (body
force and Neumann tractions), on one Problem (body, mesh hierarchy, contact boundary, law:
the description; the path only changes the data). Step k is solved with the incremental friction
law -- friction acts on the slip increment u_T - u^{k-1}_T, "stick" means no slip in this step --
starting from u^{k-1} (warm start). The one-step path from u^0 = 0 is the problem's own solve.

Step data, per step: either a callable of the load parameter t_k or one entry per step:
  dirichlet: Sequence[Dirichlet] (the same components fixed as in the problem; values may change),
  body_force: a VectorField, traction: {tag: VectorField}.
Anything not given keeps the problem's own data. LoadPath.proportional scales the problem's
Dirichlet values and load by t_k (normal loading in equal increments)."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence

import numpy as np

from ..model.loads import assemble_load
from ..model.problem import Dirichlet, Problem, dirichlet_arrays
from .options import INT32_MAX, METHODS, for_method, options_from, resolve_options
from .solver import Solver
from ..results.result import SLIP, STICK, ContactResult

PATH_METHODS = ("nmg", "fixed-point")


@dataclass
class StepData:
    """The data of one step in the arrays the core takes: Dirichlet values (n, d) on the problem's
    fixed components and the nodal load (n, d)."""

    parameter: float
    fixed_values: np.ndarray
    load: np.ndarray


def _per_step(spec, t: float, k: int, name: str):
    """The entry of step k of `spec` (None: not given; a callable of t; or a sequence per step)."""
    if spec is None:
        return None
    if callable(spec):
        return spec(t)
    return spec[k]


class LoadPath:
    """Steps with the load parameters `parameters` (t_1..t_K, any increasing or decreasing real
    numbers: they label the steps) on `problem`; dirichlet, body_force, traction as described in the
    module docstring. `initial`: the displacement the path starts from (None: u = 0, the reference
    configuration), also the slip origin of its first step."""

    def __init__(self, problem: Problem, parameters: Sequence[float], dirichlet=None, body_force=None,
                 traction=None, initial: Optional[np.ndarray] = None):
        if not isinstance(problem, Problem):
            raise TypeError("a load path needs a Problem")
        try:
            params = [float(t) for t in parameters]
        except (TypeError, ValueError):
            raise ValueError(f"the load parameters must be a sequence of numbers, got {parameters!r}") from None
        if not params:
            raise ValueError("a load path needs at least one step")
        if not all(np.isfinite(params)):
            raise ValueError(f"the load parameters must be finite, got {params}")
        for name, spec in (("dirichlet", dirichlet), ("body_force", body_force), ("traction", traction)):
            if spec is not None and not callable(spec):
                if isinstance(spec, (str, bytes)) or not hasattr(spec, "__len__") or len(spec) != len(params):
                    raise ValueError(f"{name} must be a callable of the load parameter or a sequence of one entry per "
                                     f"step ({len(params)} steps)")
        self.problem, self.parameters = problem, params
        self.dirichlet, self.body_force, self.traction = dirichlet, body_force, traction
        mesh = problem.mesh
        if initial is not None:
            initial = np.ascontiguousarray(initial, dtype=float)
            if initial.shape != (mesh.num_points, mesh.dim) or not np.all(np.isfinite(initial)):
                raise ValueError(f"the initial displacement must be a finite array of shape {(mesh.num_points, mesh.dim)}")
        self.initial = initial
        self._scale = None  # set by proportional()

    @classmethod
    def proportional(cls, problem: Problem, steps: int, start: float = 0.0, end: float = 1.0) -> "LoadPath":
        """The problem's Dirichlet values and load scaled by t_k = start + (end - start) k / steps,
        k = 1..steps: loading in equal increments to the problem's own data at t = 1."""
        if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) or not 1 <= steps <= INT32_MAX:
            raise ValueError(f"steps must be a positive integer, got {steps!r}")
        params = [start + (end - start) * k / steps for k in range(1, steps + 1)]
        path = cls(problem, params)
        path._scale = True
        return path

    def __len__(self) -> int:
        return len(self.parameters)

    def step_data(self, k: int) -> StepData:
        """The data of step k (0-based)."""
        p, t = self.problem, self.parameters[k]
        if self._scale:
            # t == 1 keeps the problem's arrays bit for bit (the one-step path is today's solve)
            return StepData(t, p.fixed_values if t == 1.0 else t * p.fixed_values, p.load if t == 1.0 else t * p.load)
        values = p.fixed_values
        bcs = _per_step(self.dirichlet, t, k, "dirichlet")
        if bcs is not None:
            if isinstance(bcs, Dirichlet):
                bcs = [bcs]
            for bc in bcs:
                if not isinstance(bc, Dirichlet):
                    raise TypeError(f"the Dirichlet data of step {k + 1} must be Dirichlet(tags, value), got {bc!r}")
            fixed, values = dirichlet_arrays(p.mesh, bcs)
            if not np.array_equal(fixed, p.fixed):
                raise ValueError(f"the Dirichlet data of step {k + 1} fix other components than the problem's: a load "
                                 "path changes the values, not which components are prescribed")
        load = p.load
        bf, tr = _per_step(self.body_force, t, k, "body_force"), _per_step(self.traction, t, k, "traction")
        if bf is not None or tr is not None:
            load = assemble_load(p.mesh, bf, tr)
        return StepData(t, values, load)

    def solve(self, method: Optional[str] = None, options=None, *, warm_start: bool = True,
              stop_on_failure: bool = True, progress: Optional[Callable[[int, ContactResult], None]] = None,
              **option_fields) -> "PathResult":
        """Solve every step by `method` ("nmg": Algorithm 2, "fixed-point": Algorithm 1; None: the
        problem's default, as in problem.solve -- the method of `options` or, given none, of
        problem.default_options, else the one resolve_options chooses for the problem, "nmg" where
        that is "tnnmg", which takes no slip origin) with the incremental law from the previous
        step's solution, all on one Solver (one core, one hierarchy: each step sets its load,
        Dirichlet values and slip origin). `options` (a SolverOptions or a dict) and `option_fields`
        (tol, max_cycles, cycle, nu1, nu2, ...) as in problem.solve. warm_start=False starts every
        step from u = 0 instead (same problem, same slip origin: the reference for the cycle
        savings). A step that does not converge ends the path (stop_on_failure) -- later steps would
        start from a state that is not a solution; the result says so (converged False).
        `progress(step, result)` is called after every step."""
        p = self.problem
        base = options_from(getattr(p, "default_options", None) if options is None else options)
        if method is None:
            method = base.method if base.method is not None else default_path_method(p, base.replace(**option_fields))
        if method not in PATH_METHODS:
            raise ValueError(f"a load path is solved by one of {PATH_METHODS}, got {method!r}"
                             + (" (the linear cost reference has no load path)" if method in METHODS else ""))
        if p.law == "linear":
            raise ValueError("a load path needs a contact boundary (without contact the problem is linear: scale the solution)")
        if method == "fixed-point" and p.friction.law != "coulomb":
            raise ValueError("the fixed-point method (Algorithm 1) needs Coulomb friction")
        opts = for_method(base, method, **option_fields)
        if progress is not None and not callable(progress):
            raise ValueError(f"progress must be a callable of (step, result), got {progress!r}")
        t_path = time.perf_counter()
        solver = Solver(p, opts)
        steps: List[ContactResult] = []
        previous = self.initial
        zero = np.zeros((p.mesh.num_points, p.mesh.dim))
        for k in range(len(self)):
            data = self.step_data(k)
            # the core's unknowns: w = T^{-1} u for several bodies (slip is relative), u for one
            start = zero if previous is None else p.relative_displacement(previous)
            res = solver.solve(start if warm_start and previous is not None else None, load=data.load,
                               fixed_values=data.fixed_values, slip_origin=start)
            build = solver.build_seconds if k == 0 else 0.0
            res.setup_seconds = p.assembly_seconds + build  # hierarchy, assembly and the core's build (step 1)
            res.extra.update(step=k + 1, parameter=data.parameter, build_seconds=build,
                             slip_increment=self._slip_increment(res, previous))
            steps.append(res)
            if progress is not None:
                progress(k + 1, res)
            previous = res.displacement
            if not res.converged and stop_on_failure:
                break
        return PathResult(self, steps, time.perf_counter() - t_path, warm_start)

    def _slip_increment(self, res: ContactResult, previous) -> np.ndarray:
        """u_T - u^{k-1}_T at the contact nodes in their frames (nc, d - 1)."""
        from ..model.frames import to_local

        du = res.displacement if previous is None else res.displacement - previous
        return to_local(res.contact_frames, du[res.contact_nodes])[:, 1:]


def default_path_method(problem: Problem, options=None) -> str:
    """The method of a load path on `problem` whose `options` (None: the defaults) name none: the
    one resolve_options chooses, but "nmg" where that is "tnnmg" -- TNNMG takes no slip origin (its
    line search measures the friction term on u_T, not on the slip of the step)."""
    chosen = resolve_options(problem, options).method
    return "nmg" if chosen == "tnnmg" else chosen


@dataclass
class PathResult:
    """The results of the steps of a load path (ContactResult each, extra holds step, parameter,
    build_seconds, slip_increment), the wall time of the whole path and whether it was warm-started."""

    path: LoadPath
    steps: List[ContactResult]
    seconds: float
    warm_start: bool
    extra: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        """Did every step of the path run and converge?"""
        return len(self.steps) == len(self.path) and all(r.converged for r in self.steps)

    @property
    def last(self) -> ContactResult:
        """The result of the last step solved."""
        return self.steps[-1]

    @property
    def parameters(self) -> List[float]:
        """The load parameter of every step solved."""
        return [r.extra["parameter"] for r in self.steps]

    @property
    def cycles(self) -> List[int]:
        """The cycles of every step solved."""
        return [r.cycles for r in self.steps]

    def summary(self, zone: Optional[Callable[[ContactResult, tuple], float]] = None,
                names=("contact_halfwidth", "stick_halfwidth")) -> List[dict]:
        """One dict per step: step, parameter, cycles, converged, status, reaction, contact/stick
        zone sizes under `names` (by `zone(result, states)`; default: largest |x| of a zone node,
        the Hertz half-width), contact_nodes, stick_nodes, slip_nodes, solve_seconds, build_seconds."""
        zone = zone or (lambda r, states: r.halfwidth(states))
        out = []
        for r in self.steps:
            row = {"step": r.extra["step"], "parameter": r.extra["parameter"], "cycles": r.cycles,
                   "converged": r.converged, "status": r.status, "reaction": [float(v) for v in r.reaction],
                   names[0]: zone(r, (STICK, SLIP)), names[1]: zone(r, (STICK,))}
            row.update(r.counts())
            row.update(solve_seconds=r.solve_seconds, build_seconds=r.extra["build_seconds"])
            out.append(row)
        return out

    def write_pvd(self, path) -> List[str]:
        """A ParaView time series: `path` (.pvd, a collection) and one VTU file per step next to it
        (<stem>_<step>.vtu), the load parameter as the time value. Point data as write_vtu, plus
        slip_increment (u_T - u^{k-1}_T at the contact nodes). Returns the VTU paths."""
        from ..mesh.io import write_mesh
        from ..results.series import write_pvd_collection

        return write_pvd_collection(path, [(r.extra["parameter"], r.mesh, self._point_data(r)) for r in self.steps],
                                    write_mesh)

    @staticmethod
    def _point_data(r: ContactResult) -> dict:
        pd = r.point_data()
        n, d = r.mesh.num_points, r.mesh.dim
        inc = np.zeros((n, d - 1))
        inc[r.contact_nodes] = r.extra["slip_increment"]
        pd["slip_increment"] = inc[:, 0] if d == 2 else inc
        return pd


def two_phase_path(problem: Problem, tags, first, steps: int, second=None, second_steps: int = 0,
                   others: Sequence[Dirichlet] = ()) -> LoadPath:
    """Dirichlet values on the facets `tags` moved from 0 to the vector `first` in `steps` equal
    increments (t_k = k / steps), then by a further `second` in `second_steps` increments
    (t = 1 + j / second_steps): normal loading then shear (Cattaneo-Mindlin, second tangential),
    or push then pull back (second = -first). `others`: the rest of the problem's Dirichlet data,
    held fixed. The problem's load is kept. The last step of the first phase prescribes `first`
    exactly (1.0 * v)."""
    for name, v, lo in (("steps", steps, 1), ("second_steps", second_steps, 0)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or not lo <= v <= INT32_MAX:
            raise ValueError(f"{name} must be an integer >= {lo}, got {v!r}")
    d = problem.mesh.dim
    first = np.asarray(first, dtype=float)
    second = np.zeros(d) if second is None else np.asarray(second, dtype=float)
    if first.shape != (d,) or second.shape != (d,) or not (np.all(np.isfinite(first)) and np.all(np.isfinite(second))):
        raise ValueError(f"the phase displacements must be finite vectors of {d} components")
    if second_steps == 0 and np.any(second != 0):
        raise ValueError("a second phase needs at least one step")
    params = [k / steps for k in range(1, steps + 1)] + [1.0 + j / second_steps for j in range(1, second_steps + 1)]
    others = list(others)

    def dirichlet(t: float):
        a, b = min(t, 1.0), max(t - 1.0, 0.0)
        value = a * first if b == 0 else first + b * second
        return [Dirichlet(tags, tuple(float(v) for v in value))] + others

    return LoadPath(problem, params, dirichlet=dirichlet)
