"""Deprecated: load paths moved to contactmg.solve.loadpath (LoadPath and PathResult are also
`contactmg.LoadPath`, `contactmg.PathResult`). This module re-exports the names it held and will be
removed in a later release."""
import warnings

from .solve.loadpath import PATH_METHODS, LoadPath, PathResult, StepData, two_phase_path

# stacklevel 2: the warning names the module that imported this one, not this file
warnings.warn("contactmg.loadpath is deprecated: import from contactmg.solve.loadpath (or contactmg)",
              DeprecationWarning, stacklevel=2)

__all__ = ["PATH_METHODS", "LoadPath", "PathResult", "StepData", "two_phase_path"]
