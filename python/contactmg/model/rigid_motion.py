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


def _generators(normals: np.ndarray, frames: np.ndarray, law: str, coefficients: np.ndarray,
                friction_scale: float = 1.0) -> np.ndarray:
    """The directions (nc, g, d) of the forces each contact node's obstacle can exert on the body,
    whose non-negative combinations are those forces: -n (pressure), with Coulomb friction edges of
    the cone |s_T| <= F |s_n| (2D: its two edges, the cone itself; 3D: eight edges of a pyramid
    inscribed in it, which check_held completes by the edges a load needs), with Tresca friction
    +-t (its bound is not proportional to the pressure). A node without friction repeats -n in the
    friction columns. friction_scale multiplies every F (the friction a load needs)."""
    n = -normals[:, None, :]                                  # (nc, 1, d)
    tang = np.swapaxes(frames[:, :, 1:], 1, 2)                # (nc, d - 1, d)
    d = normals.shape[1]
    if law == "coulomb":
        if d == 2:
            dirs = np.stack([tang[:, 0], -tang[:, 0]], axis=1)            # (nc, 2, d)
        else:
            angles = 2 * np.pi * np.arange(8) / 8
            dirs = np.cos(angles)[None, :, None] * tang[:, :1] + np.sin(angles)[None, :, None] * tang[:, 1:2]
        F = friction_scale * coefficients
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


class _Balance:
    """Can the contacts' forces balance the load on the free motions? A non-negative least-squares
    problem (Farkas) over the forces each contact node can exert. In 3D the friction cone is a cone:
    the inscribed pyramid of _generators is completed by the edges the load needs (at each node the
    friction direction opposite the motion the unbalanced load would make there, added until the
    residual stops falling), so a load is refused only if no friction inside the cone balances it;
    the outer pyramid of before accepted loads that need up to 8 % more friction than given."""

    def __init__(self, contacts, motions, offsets, K, law, target):
        self.contacts, self.motions, self.offsets, self.K, self.law = contacts, motions, offsets, K, law
        self.target = target
        self.U = []
        for points, normals, frames, coefficients, pushed, pulled in contacts:
            U = np.zeros((len(points), points.shape[1], K))   # the relative motion (pushed - pulled) at the nodes
            if len(points):
                if pushed >= 0:
                    U[:, :, offsets[pushed]:offsets[pushed + 1]] += motions[pushed].at(points)
                if pulled >= 0:
                    U[:, :, offsets[pulled]:offsets[pulled + 1]] -= motions[pulled].at(points)
            self.U.append(U)

    def solve(self, friction_scale: float):
        """(weights, residual, scaled generators) of the balance with every friction coefficient
        times friction_scale."""
        from scipy.optimize import nnls

        cols = []
        for (points, normals, frames, coefficients, _, _), U in zip(self.contacts, self.U):
            if len(points):
                gens = _generators(normals, frames, self.law, coefficients, friction_scale)
                cols.append(np.einsum("cdk,cgd->kcg", U, gens).reshape(self.K, -1))
        G = np.hstack(cols) if cols else np.zeros((self.K, 0))
        weights, residual, Gs = self._nnls(G)
        if self.law == "coulomb" and residual > 1e-9 and any(len(c[0]) and c[0].shape[1] == 3 for c in self.contacts):
            for _ in range(6):  # the cone's edges the load needs, while they help
                extra = self._needed_edges(Gs @ weights - self.target, friction_scale)
                if extra.shape[1] == 0:
                    break
                G = np.hstack([G, extra])
                weights, r_new, Gs = self._nnls(G)
                if r_new > residual * (1 - 1e-3):
                    residual = r_new
                    break
                residual = r_new
        return weights, residual, Gs

    def _nnls(self, G):
        from scipy.optimize import nnls

        if G.shape[1] == 0:
            return np.zeros(0), float(np.linalg.norm(self.target)), G
        gscale = np.linalg.norm(G, axis=0)
        Gs = G / np.where(gscale > 0, gscale, 1.0)
        weights, residual = nnls(Gs, self.target)
        return weights, residual, Gs

    def _needed_edges(self, rho, friction_scale):
        """One cone edge a node: the friction that pushes against the motion rho (the unbalanced
        load's direction in the free motions) makes at the node."""
        cols = []
        for (points, normals, frames, coefficients, _, _), U in zip(self.contacts, self.U):
            if not len(points) or points.shape[1] != 3:
                continue
            v = -np.einsum("cdk,k->cd", U, rho)                   # the force direction that reduces the residual
            vt = v - np.einsum("cd,cd->c", v, normals)[:, None] * normals
            size = np.linalg.norm(vt, axis=1)
            ok = size > 1e-12 * max(float(size.max(initial=0.0)), 1e-300)
            if not np.any(ok):
                continue
            edge = -normals[ok] + (friction_scale * coefficients[ok])[:, None] * vt[ok] / size[ok, None]
            cols.append(np.einsum("cdk,cd->kc", U[ok], edge))
        return np.hstack(cols) if cols else np.zeros((self.K, 0))


def _needed_friction(balance) -> float:
    """The least factor on every friction coefficient with which the contacts balance the load
    (bisection to 1 %), or inf where no friction does (the load pulls the body off)."""
    lo, hi = 1.0, 2.0
    while balance.solve(hi)[1] > 1e-6:
        lo, hi = hi, 2 * hi
        if hi > 1e4:
            return float("inf")
    while hi / lo > 1.01:
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if balance.solve(mid)[1] <= 1e-6 else (mid, hi)
    return hi


def _refuse(balance, residual: float, unbalanced: np.ndarray, force_name) -> None:
    """The ValueError of a load the contacts cannot balance, naming its real cause: a body pulled off
    its obstacles (no friction would hold it), or one the load drives beyond its friction, with the
    friction it needs."""
    if balance.law == "coulomb":
        factor = _needed_friction(balance)
        if np.isfinite(factor):
            F = np.concatenate([c[3] for c in balance.contacts if len(c[0])])
            given = float(np.max(F)) if len(F) else 0.0
            w, _, Gs = balance.solve(factor / 1.02)
            rho = Gs @ w - balance.target
            raise ValueError(f"nothing holds {force_name(rho, slide=True)}: the load drives it that way beyond what friction holds: "
                             f"it needs a friction coefficient of about {factor * given:.3g} where the contacts have "
                             f"{given:.3g} (hold it by a Dirichlet condition or a spring, or give more friction)")
    raise ValueError(f"nothing holds {force_name(unbalanced)}: the load pushes it that way and its contacts cannot push back "
                     "(the load pulls it off every obstacle, or beyond what friction holds); hold it by a Dirichlet "
                     "condition or a spring, or check the load's direction")


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
    normal_rows = []
    for points, normals, frames, coefficients, pushed, pulled in contacts:
        if len(points) == 0:
            continue
        U = np.zeros((len(points), points.shape[1], K))    # the relative motion (pushed - pulled) at the nodes
        if pushed >= 0:
            U[:, :, offsets[pushed]:offsets[pushed + 1]] += motions[pushed].at(points)
        if pulled >= 0:
            U[:, :, offsets[pulled]:offsets[pulled + 1]] -= motions[pulled].at(points)
        normal_rows.append(np.einsum("cdk,cd->ck", U, normals))

    def name(c):
        j = int(np.argmax([np.linalg.norm(c[offsets[a]:offsets[a + 1]]) for a in range(len(motions))]))
        return motions[j].describe(c[offsets[j]:offsets[j + 1]])

    # per piece the mean normal of the contacts that push it (into their obstacles)
    pressed = np.zeros((len(motions), contacts[0][1].shape[1] if contacts else 2))
    for points, normals, frames, coefficients, pushed, pulled in contacts:
        if len(points):
            if pushed >= 0:
                pressed[pushed] += normals.sum(axis=0)
            if pulled >= 0:
                pressed[pulled] -= normals.sum(axis=0)

    def force_name(rho, slide=False):
        """The piece and the motion an unbalanced generalized force rho (work on the free motions)
        drives: a translation along the net force where the force, not its moment, dominates; with
        `slide` (friction too weak: the body stays on its obstacles) the force's part along them,
        which is the direction it slides."""
        j = int(np.argmax([np.linalg.norm(rho[offsets[a]:offsets[a + 1]]) for a in range(len(motions))]))
        m = motions[j]
        g = m.modes @ rho[offsets[j]:offsets[j + 1]]          # net force (d) and moment about the centroid
        d = m.x.shape[1]
        size = float(np.ptp(m.x, axis=0).max()) or 1.0
        force, moment = g[:d], g[d:]
        nbar = pressed[j] / max(float(np.linalg.norm(pressed[j])), 1e-300)
        if slide and np.linalg.norm(nbar) > 0:
            force = force - (force @ nbar) * nbar
        if np.linalg.norm(force) * size >= 0.5 * np.linalg.norm(moment) and np.linalg.norm(force) > 0:
            direction = np.round(force / np.linalg.norm(force), 3) + 0.0
            return f"{m.name} in a translation along {direction.tolist()}"
        return f"{m.name} in {describe(m.x, g)}"

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
    target = -f / fnorm if fnorm > 0 else np.zeros(K)
    balance = _Balance(contacts, motions, offsets, K, law, target)
    weights, residual, Gs = balance.solve(1.0)
    if residual > 1e-6:
        _refuse(balance, residual, Gs @ weights - target, force_name)
    # Unique only if the contacts' forces balance the load with room to spare in every direction of
    # the free motions (the load inside the cone of the contact forces, not on its edge): else some
    # motion -- lifting off, rolling -- changes nothing, and the body may take it by any amount.
    delta = 1e-4
    for a in range(K):
        for sign in (1.0, -1.0):
            shifted = target + sign * delta * np.eye(K)[a]
            r = nnls(Gs, shifted)[1] if Gs.shape[1] else float(np.linalg.norm(shifted))
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
