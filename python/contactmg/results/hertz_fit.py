"""The Hertz half-width and peak pressure of a computed contact zone, fitted to all its nodes.

The discrete contact pressure of a node (its multiplier: the nodal force over the measure of the
node, for two bodies the dual mortar multiplier D^{-1} f) converges slowly in the maximum norm at a
contact peak: at levels 5-7 of the Hertz half-disk the largest nodal value lies 10.6 / 6.6 / 3.8 %
above p0 for one body and 6.0 / 4.0 / 2.6 % for two (measured), and the largest |x| of a
contact node misses the half-width by up to a mesh size. The Hertz profile p(x) = p0 sqrt(1 -
((x - c)/a)^2) is an ellipse: p^2 = k0 + k1 x - k2 x^2 is linear in (k0, k1, k2), and the least-squares
fit over every node in contact gives a and p0 from the whole zone (0.4 % off the one-body Hertz
values at level 7).
"""
from __future__ import annotations

import numpy as np


def elliptic_fit(x: np.ndarray, pressure: np.ndarray):
    """(half-width a, peak p0, centre c) of the ellipse p^2 = p0^2 (1 - ((x - c)/a)^2) fitted by least
    squares to the pressures (>= 0) of the nodes in contact at positions x; (nan, nan, nan) with
    fewer than three nodes or a fit that is not an ellipse."""
    x, pressure = np.asarray(x, float).ravel(), np.asarray(pressure, float).ravel()
    if x.shape != pressure.shape:
        raise ValueError("x and pressure need the same length")
    if len(x) < 3:
        return (np.nan, np.nan, np.nan)
    k0, k1, k2 = np.linalg.lstsq(np.c_[np.ones_like(x), x, -x ** 2], pressure ** 2, rcond=None)[0]
    if not k2 > 0:
        return (np.nan, np.nan, np.nan)
    c = k1 / (2 * k2)
    top = k0 + k2 * c ** 2  # p0^2
    if not top > 0:
        return (np.nan, np.nan, np.nan)
    return (float(np.sqrt(top / k2)), float(np.sqrt(top)), float(c))


def radial_elliptic_fit(r: np.ndarray, pressure: np.ndarray):
    """(radius a, peak p0) of the axisymmetric Hertz profile p = p0 sqrt(1 - (r/a)^2) fitted to the
    pressures of the nodes in contact at distances r from the axis (3D: a ball on a plane or two
    balls): the profile is even in r, so the fit is elliptic_fit on the nodes and their mirror
    images, whose centre is then 0 exactly."""
    r, pressure = np.abs(np.asarray(r, float).ravel()), np.asarray(pressure, float).ravel()
    if r.shape != pressure.shape:
        raise ValueError("r and pressure need the same length")
    a, p0, _ = elliptic_fit(np.r_[r, -r], np.r_[pressure, pressure])
    return (a, p0)
