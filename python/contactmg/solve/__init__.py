"""Solving a Problem: SolverOptions and resolve_options (options.py), Solver (solver.py), load paths
(loadpath.py), adaptive hierarchies (adaptivity.py).

The model layer describes problems and cannot import this layer, so the convenience
`problem.solve(...)` and the kept `problem.solver` of every Problem are installed on the class here,
when the package is imported: `Problem.solve(method=None, options=None, *, u0=None, progress=None,
reference=None, error_reference=None, **option_fields)` solves through the kept Solver (built on
first use; built again when a solve asks for other build-time options: local_smoothing,
release_hierarchy)."""
from __future__ import annotations

from typing import Optional

from ..model.problem import Problem
from .options import BUILD_FIELDS, SolverOptions, for_method, options_from
from .solver import Solver


def _problem_solver(self) -> Solver:
    """The Solver kept by this problem for problem.solve (built on first use with the problem's
    default options)."""
    kept = self.__dict__.get("_kept_solver")
    wanted = options_from(self.default_options)
    if kept is None or _rebuild(kept, wanted):
        kept = self.__dict__["_kept_solver"] = Solver(self, wanted, _kept=True)
    return kept


def _rebuild(solver: Solver, options: SolverOptions) -> bool:
    """Do `options` ask for other build-time options than `solver` was built with?"""
    return any(getattr(options, k) is not None and getattr(options, k) != getattr(solver.options, k) for k in BUILD_FIELDS)


def _problem_solve(self, method: Optional[str] = None, options=None, *, u0=None, progress=None, reference=None,
                   error_reference=None, **option_fields):
    """Solve through the problem's kept Solver (problem.solver) with `options` (a SolverOptions or a
    dict; None: the problem's defaults) and the `option_fields` on top (SolverOptions field names),
    `method` first among them: problem.solve("nmg", tol=1e-10) is
    Solver(problem).solve(options=SolverOptions(method="nmg", tol=1e-10)). A solve that asks for
    other build-time options (local_smoothing, release_hierarchy) builds the kept solver again; the
    kept solver stores its levels for the ordering of problem.default_options (None: coloured). Method "linear" with `reference` (a ContactResult) takes that result's contact state."""
    base = options_from(self.default_options if options is None else options)
    opts = for_method(base, base.method if method is None else method, **option_fields)
    solver = _problem_solver(self)
    if _rebuild(solver, opts):
        solver = self.__dict__["_kept_solver"] = Solver(self, opts, _kept=True)
    if opts.method == "linear" and reference is not None:
        return solver.solve_known_state(reference, opts, progress=progress, error_reference=error_reference)
    return solver.solve(u0, options=opts, progress=progress, error_reference=error_reference)


Problem.solver = property(_problem_solver)
Problem.solve = _problem_solve
