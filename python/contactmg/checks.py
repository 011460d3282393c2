"""Deprecated: the checks of the discrete contact conditions moved to contactmg.results.checks (use
result.check(), or `from contactmg.results.checks import contact_conditions`). This module
re-exports the names it held and will be removed in a later release."""
import warnings

from .results.checks import VIOLATION_TOL, contact_conditions

# stacklevel 2: the warning names the module that imported this one, not this file
warnings.warn("contactmg.checks is deprecated: import from contactmg.results.checks (or use result.check())",
              DeprecationWarning, stacklevel=2)

__all__ = ["VIOLATION_TOL", "contact_conditions"]
