"""Deprecated: the bodies in contact through mortar pairs are contactmg.Problem(bodies, pairs=...);
Body and ContactPair live in contactmg.model.problem, the deprecated MultiBodyProblem and
TwoBodyProblem in contactmg.solve.contact_problem (all four are names of `contactmg`). This module
re-exports the names it held and will be removed in a later release. Body is the general one now:
its fourth field is contact_tags, so give traction and body_force by keyword."""
import warnings

from .model.problem import Body, ContactPair
from .solve.contact_problem import MultiBodyProblem, TwoBodyProblem

# stacklevel 2: the warning names the module that imported this one, not this file
warnings.warn("contactmg.two_body is deprecated: use contactmg.Problem(bodies, pairs=...) with contactmg.Body and "
              "contactmg.ContactPair (from contactmg.model.problem)", DeprecationWarning, stacklevel=2)

__all__ = ["Body", "ContactPair", "MultiBodyProblem", "TwoBodyProblem"]
