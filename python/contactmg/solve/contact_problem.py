"""Deprecated aliases of Problem, kept for one release: ContactProblem (one body against an
obstacle), MultiBodyProblem and TwoBodyProblem (bodies through mortar pairs). Each warns
(DeprecationWarning) when made and builds a Problem; the cycle options given here are the defaults of
problem.solve(), and so is the absolute stop 1e-11 that was the default when they were the API
(contactmg.solve.options.with_cycle sets the same defaults on a Problem)."""
from __future__ import annotations

import warnings
from typing import Dict, Optional, Sequence

from ..mesh.hierarchy import MeshHierarchy
from ..model.material import Material
from ..model.problem import Body, ContactPair, Dirichlet, Problem, VectorField
from .options import PAPER_TOL, SolverOptions

# The solve defaults of the aliases, which the replacement takes from with_cycle
_CYCLE_DEFAULTS = ("; the solve defaults of the alias (method 'nmg', its cycle, tol 1e-11) are "
                   "contactmg.solve.options.with_cycle(problem, cycle, nu1, nu2)")
_CONTACT_PROBLEM_DEPRECATED = (
    "contactmg.ContactProblem is deprecated and will be removed in the next release: use "
    "contactmg.Problem(contactmg.Body(hierarchy, material, dirichlet, contact_tags, body_force, traction), "
    "obstacle=obstacle, friction=friction)" + _CYCLE_DEFAULTS)
_MULTI_BODY_PROBLEM_DEPRECATED = (
    "contactmg.MultiBodyProblem is deprecated and will be removed in the next release: use "
    "contactmg.Problem(bodies, pairs=pairs, friction=friction, tied_correction=tied_correction)" + _CYCLE_DEFAULTS)
_TWO_BODY_PROBLEM_DEPRECATED = (
    "contactmg.TwoBodyProblem is deprecated and will be removed in the next release: use "
    "contactmg.Problem(bodies, pairs=pair, friction=friction, tied_correction=tied_correction)" + _CYCLE_DEFAULTS)


class ContactProblem(Problem):
    """Deprecated: Problem(Body(hierarchy, material, dirichlet, contact_tags, body_force, traction),
    obstacle, friction). Linear elasticity on the finest level of `hierarchy` with contact on the
    facets tagged `contact_tags` against `obstacle` under `friction`; cycle, nu1 and nu2 are the
    defaults of problem.solve()."""

    def __init__(self, hierarchy: MeshHierarchy, material: Material, dirichlet: Sequence[Dirichlet],
                 contact_tags: Sequence[int] = (), obstacle=None, friction=None,
                 body_force: Optional[VectorField] = None, traction: Optional[Dict[int, VectorField]] = None,
                 cycle: str = "F", nu1: int = 3, nu2: int = 3):
        # stacklevel 2: the warning names the line that made the alias
        warnings.warn(_CONTACT_PROBLEM_DEPRECATED, DeprecationWarning, stacklevel=2)
        self.default_options = SolverOptions(method="nmg", cycle=cycle, nu1=nu1, nu2=nu2, tol=PAPER_TOL)
        super().__init__(Body(hierarchy, material, dirichlet, contact_tags, body_force, traction), obstacle, friction)


class MultiBodyProblem(Problem):
    """Deprecated: Problem(bodies, pairs=pairs, friction=friction, tied_correction=...); cycle, nu1
    and nu2 are the defaults of problem.solve()."""

    def __init__(self, bodies: Sequence[Body], pairs: Sequence[ContactPair], friction=None, cycle: str = "F",
                 nu1: int = 3, nu2: int = 3, tied_correction: bool = True):
        warnings.warn(_MULTI_BODY_PROBLEM_DEPRECATED, DeprecationWarning, stacklevel=2)
        self._build(bodies, pairs, friction, cycle, nu1, nu2, tied_correction)

    def _build(self, bodies, pairs, friction, cycle, nu1, nu2, tied_correction) -> None:
        bodies = list(bodies) if not isinstance(bodies, Body) else [bodies]
        if len(bodies) < 2 or not all(isinstance(b, Body) for b in bodies):
            raise TypeError("bodies must be a sequence of at least two Body")
        self.default_options = SolverOptions(method="nmg", cycle=cycle, nu1=nu1, nu2=nu2, tol=PAPER_TOL)
        Problem.__init__(self, bodies, friction=friction, pairs=pairs, tied_correction=tied_correction)


class TwoBodyProblem(MultiBodyProblem):
    """Deprecated: two (or more) bodies through one mortar pair (or a sequence of pairs): MultiBodyProblem."""

    def __init__(self, bodies: Sequence[Body], pair: ContactPair, friction=None, cycle: str = "F", nu1: int = 3,
                 nu2: int = 3, tied_correction: bool = True):
        # its own warning (not MultiBodyProblem's): one warning, naming this alias and the caller's line
        warnings.warn(_TWO_BODY_PROBLEM_DEPRECATED, DeprecationWarning, stacklevel=2)
        if not isinstance(pair, ContactPair) and not (isinstance(pair, (list, tuple))
                                                      and all(isinstance(q, ContactPair) for q in pair)):
            raise TypeError("pair must be a ContactPair")
        self._build(bodies, pair, friction, cycle, nu1, nu2, tied_correction)
