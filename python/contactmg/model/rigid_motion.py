"""Rigid-body motions that a body's supports leave free, and whether its contacts can hold them.

A body whose Dirichlet conditions and springs leave rigid motions free is a semi-coercive problem: it
has a solution only if its contacts can balance the load on those motions, and a unique one only if
every free motion moves some contact node towards its obstacle or is resisted by friction. Both are
decided here, before a solve, from the free motions alone: the load on them must be a combination
with non-negative weights of the forces the contacts can exert (Farkas: a non-negative least-squares
problem with one column per contact node and force direction). The solve itself needs nothing
special: the monotone multigrid's smoother has positive definite nodal blocks, the coarse levels see
the nodes on the obstacle truncated, and the coarsest level's factorization is shifted where the
truncated matrix is only semi-definite (0024-bodies-held-by-contact).
"""
from __future__ import annotations

from typing import Optional

import numpy as np


def _base_modes(x: np.ndarray) -> np.ndarray:
    """The rigid motions of points `x` (m, d) about their centroid: (m, d, d) translations, then
    rotations (2D: about z; 3D: about x, y, z): (m, d, nmodes)."""
    m, d = x.shape
    y = x - x.mean(axis=0)
    modes = [np.broadcast_to(np.eye(d)[a], (m, d)) for a in range(d)]
    if d == 2:
        modes.append(np.c_[-y[:, 1], y[:, 0]])
    else:
        for a in range(3):
            modes.append(np.cross(np.eye(3)[a], y))
    return np.stack(modes, axis=2)


def free_modes(x: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Coefficients (nmodes, k) of the rigid motions of the points `x` (m, d) that vanish on the
    held components `held` (m, d) of bool: a basis of the free rigid motions (k = 0: none)."""
    base = _base_modes(x)
    C = base[held]                                   # (held components, nmodes)
    nmodes = base.shape[2]
    if C.size == 0:
        return np.eye(nmodes)
    scale = max(float(np.abs(C).max()), 1e-300)
    _, s, vt = np.linalg.svd(C / scale)
    rank = int(np.sum(s > 1e-10))
    return vt[rank:].T


def describe(x: np.ndarray, coeff: np.ndarray) -> str:
    """The rigid motion of coefficients `coeff` (nmodes,) about the centroid of `x`, in words: a
    translation, or a rotation about the point (2D) or axis (3D) it leaves in place."""
    d = x.shape[1]
    x0 = x.mean(axis=0)
    t, w = coeff[:d], coeff[d:]
    size = float(np.ptp(x, axis=0).max()) or 1.0
    r = lambda v: (np.round(v, 6) + 0.0).tolist()  # + 0.0: no "-0.0"
    if np.linalg.norm(w) * size <= 1e-6 * np.linalg.norm(t):
        return f"a translation along {np.round(t / np.linalg.norm(t), 3).tolist()}"
    if d == 2:
        (om,) = w
        return f"a rotation in the plane about {r(x0 + np.array([-t[1], t[0]]) / om)}"
    axis = w / np.linalg.norm(w)
    point = x0 + np.cross(w, t) / (w @ w)
    along = float(t @ axis)
    text = f"a rotation about the axis {np.round(axis, 3).tolist()} through {r(point)}"
    if abs(along) > 1e-6 * np.linalg.norm(w) * size:
        text += " with a translation along it"
    return text


def _generators(normals: np.ndarray, frames: np.ndarray, law: str, coefficients: np.ndarray) -> list:
    """Per contact node the directions (d,) of the forces its obstacle can exert on the body, whose
    non-negative combinations are those forces: -n (pressure), with Coulomb friction the edges of a
    pyramid around the cone |s_T| <= F |s_n| that contains it (so a load refused is one no friction
    force can balance), with Tresca friction +-t (its bound is not proportional to the pressure)."""
    d = normals.shape[1]
    out = []
    for i in range(len(normals)):
        n, tang = -normals[i], frames[i][:, 1:].T
        gens = [n]
        if law == "coulomb" and coefficients[i] > 0:
            if d == 2:
                gens += [n + coefficients[i] * tang[0], n - coefficients[i] * tang[0]]
            else:
                m = 8
                f = coefficients[i] / np.cos(np.pi / m)
                gens += [n + f * (np.cos(a) * tang[0] + np.sin(a) * tang[1]) for a in 2 * np.pi * np.arange(m) / m]
        elif law == "tresca":
            gens += [s * t for t in tang for s in (1.0, -1.0)]
        out.append(gens)
    return out


def check_held_by_contact(x: np.ndarray, modes: np.ndarray, load: np.ndarray, contact_rows: np.ndarray,
                          normals: np.ndarray, frames: np.ndarray, law: str, coefficients: np.ndarray,
                          where: str) -> None:
    """Raise a ValueError naming the free rigid motion (of the piece with points `x`, free modes
    `modes` (nmodes, k)) that the contacts (rows `contact_rows` of `x`, with their normals, frames,
    law and coefficients) cannot hold under `load` (m, d) -- or could hold but leave undetermined
    (frictionless contact along a motion that moves no contact node along its normal)."""
    from scipy.optimize import nnls

    base = _base_modes(x)                                  # (m, d, nmodes)
    M = base @ modes                                        # (m, d, k): the free motions
    k = M.shape[2]
    f = np.einsum("mdk,md->k", M, load)                     # the load's work on each free motion
    gens = _generators(normals, frames, law, coefficients)
    cols = [np.einsum("dk,d->k", M[row], g) for row, gs in zip(contact_rows, gens) for g in gs]
    G = np.array(cols).T if cols else np.zeros((k, 0))
    Mc = M[contact_rows]                                    # (nc, d, k)
    normal_motion = np.einsum("cdk,cd->ck", Mc, normals)
    scale = max(float(np.abs(normal_motion).max(initial=0.0)), 1e-300)
    # a free motion that moves no contact node along its normal: only friction can fix it
    _, s, vt = np.linalg.svd(normal_motion / scale, full_matrices=True)
    rank = int(np.sum(s > 1e-8))
    if rank < k and law == "frictionless":
        c = modes @ vt[rank]
        raise ValueError(f"nothing holds {where} in {describe(x, c)}: its supports leave that motion free and "
                         "frictionless contact exerts no force along it (hold it by a Dirichlet condition or a "
                         "spring, or give friction)")
    fnorm = float(np.linalg.norm(f))
    gscale = np.linalg.norm(G, axis=0)
    Gs = G / np.where(gscale > 0, gscale, 1.0)
    target = -f / fnorm if fnorm > 0 else np.zeros(k)
    weights, residual = nnls(Gs, target) if G.shape[1] else (np.zeros(0), float(np.linalg.norm(target)))
    if residual > 1e-6:
        unbalanced = Gs @ weights - target
        c = modes @ unbalanced
        raise ValueError(f"nothing holds {where} in {describe(x, c)}: the load pushes it that way and its contacts "
                         "cannot push back (the load moves it away from every obstacle, or beyond what friction "
                         "holds); hold it by a Dirichlet condition or a spring, or check the load's direction")
    # Unique only if the contacts' forces balance the load with room to spare in every direction of
    # the free motions (the load inside the cone of the contact forces, not on its edge): else some
    # motion -- lifting off, rolling -- changes nothing, and the body may take it by any amount.
    delta = 1e-4
    for a in range(k):
        for sign in (1.0, -1.0):
            shifted = target + sign * delta * np.eye(k)[a]
            _, r = nnls(Gs, shifted) if G.shape[1] else (None, float(np.linalg.norm(shifted)))
            if r > 1e-3 * delta:
                c = modes @ (-sign * np.eye(k)[a])
                raise ValueError(f"nothing holds {where} in {describe(x, c)}: its supports leave that motion free and "
                                 "the load does not press it onto its obstacles that way, so it may take that motion "
                                 "(lift off, tip or slide) by any amount; hold it by a Dirichlet condition or a "
                                 "spring, or press it onto the obstacle")
