"""Shared checks of the "nmg" cycle switches (petrov_galerkin, upwind_contact_sweep,
projected_coarse_correction): a bad value of solve(name=...) is refused with a message naming the
switch, and switching one on is refused for the methods that have no such cycle."""
import pytest


def check_switch_refuses_bad_values(p, name, methods=("tnnmg", "fixed-point")):
    for bad in ("yes", 1, 0.0, [True]):
        with pytest.raises(ValueError, match=f"{name} must be True or False"):
            p.solve(**{name: bad})
    for method in methods:
        with pytest.raises(ValueError, match=f"{name} is a choice of method 'nmg'"):
            p.solve(method, **{name: True})
