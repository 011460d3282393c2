"""Independent check of a computed contact state against the discrete conditions.

The solvers stop when ||u^{k+1} - u^k||_A <= tol. That test cannot tell a solution from an iterate
that the cycle maps back onto itself without solving anything (e.g. a smoother that flips a few
contact nodes back and forth with an even number of sweeps per cycle). This module recomputes the
residual r = A u - f from the displacement alone and measures every force condition relative to the
force scale of the problem and the penetration relative to its displacement scale, so a "converged"
result can be confirmed or rejected.
"""
from __future__ import annotations

from typing import Dict

import numpy as np

from ..model.frames import to_local

# A solve that met its stopping test but violates the conditions by more than this (relative) did
# not find a solution.
VIOLATION_TOL = 1e-6


def contact_conditions(problem, result, raise_on_violation: bool = False, tol: float = VIOLATION_TOL,
                       residual=None, stiffness=None) -> Dict[str, float]:
    """Relative violations of the discrete contact conditions by `result` (a ContactResult of
    `problem`), each >= 0, plus "max", their maximum:

    - interior: max |(A w - f)| over the free dofs off the contact boundary,
    - inactive_force: max |s_n| over contact nodes off the obstacle (w_n < g), and |s_T| there
      unless friction acts there (Tresca),
    - tension: max (A w - f)_{p,n} over nodes in contact (must be <= 0),
    - friction_bound: max (|s_T| - s_p) where friction acts (Coulomb: nodes in contact, s_p =
      F_p |s_n|; Tresca: every contact node, the given bound; frictionless: nodes in contact, 0),
    - slip_direction: max |s_T + s_p v_T/|v_T|| over the nodes where friction acts and v_T != 0,
    all divided by the force scale of the problem, which the iterate cannot inflate (the largest nodal
    load, or the largest contact force or reaction up to max|A| times the largest prescribed
    displacement or initial penetration; max|A| max|w| for a body nothing loads); balance: per body the largest component of
    the residual summed over its free dofs off the contact boundary (what reactions, contact forces
    and load fail to balance) divided by the load's total (the sum of |f|, at least the force scale); and
    penetration: max (w_n - g) divided by the displacement scale of the problem (the largest
    prescribed displacement or gap, or the force scale over max|A|). The
    contact state is recomputed from w (w_n >= g in contact, v_T == 0 sticking, both up to
    round-off), not taken from the result; the frames are the result's (result.contact_frames).

    What the conditions are posed on:

    - the unknowns w = problem.relative_displacement(u) of the canonical displacement u =
      result.displacement, with the matrix problem.A and the load of those unknowns. One body: w = u.
      Several bodies: at a nonmortar node w is its displacement relative to the mortar side, and A,
      f are the transformed T^T A T, T^T f (the conditions are nodal only in w).
    - the slip v_T = w_T - w0_T: the tangential displacement since the slip origin w0 the solve was
      given (result.slip_origin: the previous step of a load path, whose incremental friction law
      acts on the slip of the step); without one, w0 = 0. The normal conditions use w itself.
    - the load and the prescribed displacements of the solve (result.load, result.fixed_values:
      a load path step's own), else the problem's.

    With raise_on_violation, a ValueError names every condition violated by more than `tol`.
    `residual` (A w - f of the result, as a core solver gives it) and `stiffness` (the largest entry
    of A) spare a product with the problem's matrix, which one body's solver has taken over."""
    c = problem.contact
    w = problem.relative_displacement(np.asarray(result.displacement, dtype=float))
    load = problem.load if getattr(result, "load", None) is None else result.load
    fixed_values = problem.fixed_values if getattr(result, "fixed_values", None) is None else result.fixed_values
    r = problem.A.matvec(w) - load if residual is None else np.asarray(residual, dtype=float)
    origin = getattr(result, "slip_origin", None)
    slip = w if origin is None else w - origin
    Q = result.contact_frames
    ul = to_local(Q, w[c.nodes])
    vl = to_local(Q, slip[c.nodes])
    sl = to_local(Q, r[c.nodes])
    tied = np.zeros(ul.shape, bool)
    if len(c.nodes):
        tied = getattr(result, "frame_fixed", None)
        tied = (problem.solver.core.frame_fixed if tied is None else tied).astype(bool)
    if stiffness is None:
        stiffness = float(np.abs(problem.A.data).max(initial=0.0))
    fixed = problem.fixed.astype(bool)
    out = condition_violations(r, w, load, fixed, np.where(fixed, fixed_values, 0.0), c.nodes, c.gaps, ul, vl, sl,
                               tied, problem.coefficients, problem.law, stiffness,
                               getattr(problem, "body_id", np.zeros(len(w), np.int32)))
    if raise_on_violation:
        raise_violations(out, tol)
    return out


class SerialReduce:
    """The reductions of condition_violations on one process: the maxima are the values, the sums
    those of the arrays."""

    @staticmethod
    def max(values) -> np.ndarray:
        """The values themselves."""
        return np.asarray(values, float)

    @staticmethod
    def sum(arrays) -> np.ndarray:
        """The sum of each array."""
        return np.array([float(np.sum(a)) for a in arrays])


def condition_violations(r, w, load, fixed, prescribed, contact_nodes, gaps, ul, vl, sl, tied, coefficients, law: str,
                         stiffness: float, body, reduce=SerialReduce) -> Dict[str, float]:
    """The relative violations of contact_conditions from arrays: the residual r = A w - f (n, d),
    w, the load, the fixed dofs and their prescribed values (0 where free), the contact nodes with
    their gaps, and w, the slip and r at them in their frames (ul, vl, sl (c, d)), the frame
    components a Dirichlet condition ties (tied (c, d)), the friction coefficients (or Tresca
    bounds), the law, max|A| and each node's body. `reduce` (max: of a list of values, entry by entry;
    sum: of each array of a list, every entry) over every part of the problem lets a part of the
    problem (an MPI rank's owned rows) give the figures of the whole: every array here is that
    part's."""
    ul, vl, sl = ul.copy(), vl.copy(), sl.copy()
    # a tangential component fixed by a Dirichlet condition takes no part in friction: its force is a reaction
    ul[tied], vl[tied], sl[tied] = 0.0, 0.0, 0.0
    # Forces are measured against the force scale of the problem, which the iterate cannot inflate:
    # the largest nodal load, and the iterate's largest contact force or reaction only up to the
    # stiffness times the largest prescribed displacement or initial penetration (the most a
    # displacement-driven body's supports or an interference fit call for). A scale
    # from the iterate's own reactions or contact forces grows with a runaway iterate and made its
    # violations look like round-off (|u| = 2e8, every violation below 1e-13).
    gaps = np.asarray(gaps, float)
    big = reduce.max([np.maximum(-gaps, 0.0).max(initial=0.0), np.abs(prescribed).max(initial=0.0),
                      np.abs(sl[:, 0]).max(initial=0.0), np.abs(r[fixed]).max(initial=0.0),
                      np.abs(load).max(initial=0.0), np.abs(w).max(initial=0.0), np.abs(gaps).max(initial=0.0)])
    overlap, most_prescribed, contact_force, reaction, most_load, most_w, most_gap = (float(v) for v in big)
    moved = stiffness * max(most_prescribed, overlap)
    # the iterate's own reactions and contact forces count up to that bound, no further
    own = max(contact_force, reaction)
    scale = max(most_load, min(own, moved))
    if scale <= 1e-9 * moved:
        # its supports move it without loading it (lifted off its obstacle): forces of round-off,
        # measured against the stiffness times the prescribed displacement
        scale = moved
    # equilibrium of each body: the residual left at its free dofs off the contact boundary, summed
    # (what the reactions, contact forces and load fail to balance), against the load's total
    free = ~fixed
    free[contact_nodes] = False
    held = np.where(free, r, 0.0)
    columns = [held[body == b, a] for b in range(int(body.max(initial=0)) + 1) for a in range(w.shape[1])]
    totals = reduce.sum(columns + [np.abs(load).ravel()])
    sums, load_total = totals[:-1], float(totals[-1])
    force_sum = max(load_total, scale)
    if scale == 0.0:
        # nothing loads the body: its solution is zero, and the stiffness times the iterate is what
        # round-off means
        scale = force_sum = stiffness * most_w
    scale, force_sum = max(scale, 1e-300), max(force_sum, 1e-300)
    # The core's tests w_n == g and v_T == 0 are exact in its frames; rebuilt here from the canonical
    # u through a rotated frame (and T^{-1}) they carry round-off, hence the relative tolerance.
    eps = 1e-12 * max(most_w, most_gap, 1e-300)
    active = ul[:, 0] >= gaps - eps
    vt = np.linalg.norm(vl[:, 1:], axis=1)
    vt[vt <= eps] = 0.0
    st = np.linalg.norm(sl[:, 1:], axis=1)
    # Where friction acts: Coulomb at nodes in contact (bound F |s_n|); Tresca at every contact node,
    # touching or not (its bound is given); frictionless nowhere.
    if law == "coulomb":
        s, rubs = coefficients * np.abs(sl[:, 0]), active
    elif law == "tresca":
        s, rubs = np.asarray(coefficients, float), np.ones(len(gaps), bool)
    else:
        s, rubs = np.zeros(len(gaps)), active
    off = ~active
    slide = rubs & (vt > 0)
    dev = sl[slide, 1:] + s[slide, None] * vl[slide, 1:] / vt[slide, None] if np.any(slide) else np.zeros((0, 1))
    worst = reduce.max([np.abs(r[free]).max(initial=0.0),
                        max(np.abs(sl[off, 0]).max(initial=0.0), st[off & ~rubs].max(initial=0.0)),
                        max(0.0, sl[active, 0].max(initial=0.0)),
                        max(0.0, (st - s)[rubs].max(initial=0.0)),
                        np.linalg.norm(dev, axis=1).max(initial=0.0),
                        max(0.0, (ul[:, 0] - gaps).max(initial=0.0))])
    out = {"interior": float(worst[0]) / scale, "balance": float(np.abs(sums).max(initial=0.0)) / force_sum,
           "inactive_force": float(worst[1]) / scale, "tension": float(worst[2]) / scale,
           "friction_bound": float(worst[3]) / scale, "slip_direction": float(worst[4]) / scale}
    # Not max |w_n|: on a tilted plane with zero gaps every w_n is round-off; nor max |w|, which a
    # runaway iterate sets. The displacement scale of the problem: its prescribed displacements, its
    # gaps, and the displacement its force scale makes at the stiffest entry of A.
    disp = max(most_prescribed, most_gap, scale / max(stiffness, 1e-300), 1e-300)
    out["penetration"] = float(worst[5]) / disp
    out["max"] = max(out.values())
    return out


def raise_violations(violations: Dict[str, float], tol: float = VIOLATION_TOL) -> None:
    """Raise a ValueError naming every condition of `violations` (a dict of contact_conditions)
    above `tol`, with its value; return quietly when none is."""
    if not (isinstance(tol, (int, float)) and not isinstance(tol, bool) and tol >= 0):
        raise ValueError(f"tol must be a number >= 0, got {tol!r}")
    bad = {k: v for k, v in violations.items() if k != "max" and not v <= tol}
    if bad:
        named = ", ".join(f"{k} {v:.3g}" for k, v in sorted(bad.items(), key=lambda kv: -kv[1]))
        raise ValueError(f"the result violates the contact conditions (relative, tolerance {tol:.3g}): {named}")


def check_contact(problem, result, tol: float = VIOLATION_TOL) -> Dict[str, float]:
    """contact_conditions(problem, result) as a verdict: the dict of relative violations when
    every one is <= `tol`, else a ValueError naming the violated conditions and their values."""
    return contact_conditions(problem, result, raise_on_violation=True, tol=tol)
