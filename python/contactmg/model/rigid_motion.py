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


def _base_modes(x: np.ndarray, centre: Optional[np.ndarray] = None) -> np.ndarray:
    """The rigid motions of points `x` (m, d) about `centre` (None: their centroid): translations,
    then rotations (2D: about z; 3D: about x, y, z): (m, d, nmodes)."""
    m, d = x.shape
    y = x - (x.mean(axis=0) if centre is None else centre)
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


def _generators(normals: np.ndarray, frames: np.ndarray, law: str, coefficients: np.ndarray) -> np.ndarray:
    """The directions (nc, g, d) of the forces each contact node's obstacle can exert on the body,
    whose non-negative combinations are those forces: -n (pressure), with Coulomb friction the
    edges of a pyramid around the cone |s_T| <= F |s_n| that contains it (so a load refused is one
    no friction force can balance), with Tresca friction +-t (its bound is not proportional to the
    pressure). A node without friction repeats -n in the friction columns."""
    n = -normals[:, None, :]                                  # (nc, 1, d)
    tang = np.swapaxes(frames[:, :, 1:], 1, 2)                # (nc, d - 1, d)
    d = normals.shape[1]
    if law == "coulomb":
        if d == 2:
            dirs = np.stack([tang[:, 0], -tang[:, 0]], axis=1)            # (nc, 2, d)
            F = coefficients
        else:
            angles = 2 * np.pi * np.arange(8) / 8
            dirs = np.cos(angles)[None, :, None] * tang[:, :1] + np.sin(angles)[None, :, None] * tang[:, 1:2]
            F = coefficients / np.cos(np.pi / 8)
        return np.concatenate([n, n + F[:, None, None] * dirs], axis=1)
    if law == "tresca":
        return np.concatenate([n, tang, -tang], axis=1)
    return n


class FreeMotion:
    """The free rigid motions of one piece (of one body): its points, their centroid, the basis
    `modes` (nmodes, k) and the piece's name in messages."""

    def __init__(self, x: np.ndarray, modes: np.ndarray, name: str):
        self.x, self.centre, self.modes, self.name = x, x.mean(axis=0), modes, name

    def at(self, points: np.ndarray) -> np.ndarray:
        """The free motions at `points` (m, d): (m, d, k)."""
        return _base_modes(points, self.centre) @ self.modes

    def describe(self, c: np.ndarray) -> str:
        """The piece and the motion of coefficients `c` (k,) in its free modes, in words."""
        return f"{self.name} in {describe(self.x, self.modes @ c)}"


def check_held(motions: list, load_work: list, contacts: list, law: str) -> None:
    """Raise a ValueError naming a free rigid motion that the contacts cannot hold, or leave
    undetermined. `motions`: FreeMotion per piece; `load_work`: per piece the load's work on each of
    its free motions (k,); `contacts`: (points (nc, d), normals (nc, d), frames (nc, d, d),
    coefficients (nc,), pushed, pulled) with `pushed` the index into `motions` of the piece the
    force -lambda n acts on (or -1: a held body) and `pulled` the piece that feels the opposite force
    (the other body of a pair; -1: an obstacle or a held body)."""
    from scipy.optimize import nnls

    sizes = [m.modes.shape[1] for m in motions]
    offsets = np.r_[0, np.cumsum(sizes)].astype(int)
    K = int(offsets[-1])
    f = np.concatenate(load_work) if load_work else np.zeros(0)
    cols, normal_rows = [], []
    for points, normals, frames, coefficients, pushed, pulled in contacts:
        if len(points) == 0:
            continue
        U = np.zeros((len(points), points.shape[1], K))    # the relative motion (pushed - pulled) at the nodes
        if pushed >= 0:
            U[:, :, offsets[pushed]:offsets[pushed + 1]] += motions[pushed].at(points)
        if pulled >= 0:
            U[:, :, offsets[pulled]:offsets[pulled + 1]] -= motions[pulled].at(points)
        normal_rows.append(np.einsum("cdk,cd->ck", U, normals))
        cols.append(np.einsum("cdk,cgd->kcg", U, _generators(normals, frames, law, coefficients)).reshape(K, -1))

    def name(c):
        j = int(np.argmax([np.linalg.norm(c[offsets[a]:offsets[a + 1]]) for a in range(len(motions))]))
        return motions[j].describe(c[offsets[j]:offsets[j + 1]])

    G = np.hstack(cols) if cols else np.zeros((K, 0))
    normal_motion = np.vstack(normal_rows) if normal_rows else np.zeros((0, K))
    # a free motion that moves no contact node along its normal: only friction can fix it
    if law == "frictionless":
        scale = max(float(np.abs(normal_motion).max(initial=0.0)), 1e-300)
        _, sv, vt = np.linalg.svd(normal_motion / scale if len(normal_motion) else np.zeros((1, K)), full_matrices=True)
        rank = int(np.sum(sv > 1e-8))
        if rank < K:
            raise ValueError(f"nothing holds {name(vt[rank])}: its supports leave that motion free and frictionless "
                             "contact exerts no force along it (hold it by a Dirichlet condition or a spring, or give "
                             "friction)")
    fnorm = float(np.linalg.norm(f))
    gscale = np.linalg.norm(G, axis=0)
    Gs = G / np.where(gscale > 0, gscale, 1.0)
    target = -f / fnorm if fnorm > 0 else np.zeros(K)
    weights, residual = nnls(Gs, target) if G.shape[1] else (np.zeros(0), float(np.linalg.norm(target)))
    if residual > 1e-6:
        raise ValueError(f"nothing holds {name(Gs @ weights - target)}: the load pushes it that way and its contacts "
                         "cannot push back (the load moves it away from every obstacle, or beyond what friction "
                         "holds); hold it by a Dirichlet condition or a spring, or check the load's direction")
    # Unique only if the contacts' forces balance the load with room to spare in every direction of
    # the free motions (the load inside the cone of the contact forces, not on its edge): else some
    # motion -- lifting off, rolling -- changes nothing, and the body may take it by any amount.
    delta = 1e-4
    for a in range(K):
        for sign in (1.0, -1.0):
            shifted = target + sign * delta * np.eye(K)[a]
            r = nnls(Gs, shifted)[1] if G.shape[1] else float(np.linalg.norm(shifted))
            if r > 1e-3 * delta:
                raise ValueError(f"nothing holds {name(-sign * np.eye(K)[a])}: its supports leave that motion free "
                                 "and the load does not press it onto its obstacles that way, so it may take that "
                                 "motion (lift off, tip or slide) by any amount; hold it by a Dirichlet condition or "
                                 "a spring, or press it onto the obstacle")


def check_held_by_contact(x: np.ndarray, modes: np.ndarray, load: np.ndarray, contact_rows: np.ndarray,
                          normals: np.ndarray, frames: np.ndarray, law: str, coefficients: np.ndarray,
                          where: str) -> None:
    """check_held for one piece (points `x`, free modes `modes`) against rigid obstacles at its
    points `contact_rows` under `load` (m, d)."""
    motion = FreeMotion(x, modes, where)
    work = np.einsum("mdk,md->k", motion.at(x), load)
    check_held([motion], [work], [(x[contact_rows], normals, frames, coefficients, 0, -1)], law)
