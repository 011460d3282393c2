"""contactmg: nonlinear monotone multigrid for elastic contact with Coulomb friction."""
from . import _core  # noqa: F401

__version__ = "0.1.0"
