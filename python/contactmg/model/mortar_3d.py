"""The 3D dual mortar coupling of a nonmortar (slave) and a mortar (master) surface (Wohlmuth), by
the segment integration of Puso & Laursen / Popp & Wall.

Nonmortar surface: triangles (faces of P1 tetrahedra) or quadrilaterals (faces of Q1 hexahedra).
On each nonmortar element e the dual basis psi_i = sum_j A_ij phi_j, A = D_e M_e^{-1} (D_e =
diag(int_e phi_i), M_e = (int_e phi_i phi_j)), is biorthogonal to the trace hat functions:
int_e psi_i phi_j = delta_ij int_e phi_i. On a triangle this is psi_i = 4 phi_i - 1 = 3 phi_i -
sum_{j != i} phi_j (the 1D form 3 phi_i - 1 is not biorthogonal on triangles: int (3 phi_i - 1)
phi_j = -A/12 for j != i); on a parallelogram the tensor product of the 1D duals 2 phi_a - phi_b. So D_p = int phi_p (summed over
the nonmortar surface) is diagonal.

M_pq = int psi_p phi_q^mortar is integrated element pair by element pair: the mortar element is
projected along the nonmortar element's normal n_e onto the nonmortar element's plane (the
auxiliary plane through its centre), the two convex polygons are clipped (Sutherland-Hodgman),
the intersection is cut into triangles (a fan: it is convex) and each is integrated by a
degree-5 Gauss rule. At a quadrature point the nonmortar and mortar local coordinates are those
whose (projected) images are the point; the measure is the nonmortar surface's (the plane's area
times J_surface / J_plane, 1 on a flat triangle). The integrals are kept per overlapping pair
(int phi_i phi_j^mortar) and per nonmortar element over its covered part, and mortar.dual_coupling
makes the dual basis of each element's covered part from them (the standard one where the element is
covered), takes out the nodes that cannot carry a condition by the boundary modification, and
assembles M = sum over pairs of A_e (int phi phi^mortar).

Normal and gap per nonmortar node: n_p the area-weighted average of the element normals around p
(outward of the nonmortar body), g_p = (D^{-1} M x_m - x_p) . n_p: D^{-1} times the weighted gap
integral of the dual basis. The result is the MortarCoupling of mortar.py (dimension-generic).

Everything is vectorized over the element pairs (numpy): a pair costs a few hundred flops. The
mortar element is searched near the nonmortar element (its centre within reach of the centre,
within `search` of the plane along the normal, facing it: n_m . n_e < 0)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..model.mortar import MortarCoupling, dual_coupling

# points per direction of the collapsed Gauss rule on the fan triangles of nonmortar quads
QUAD_RULE_POINTS = 5
# Dunavant's degree-5 rule on a triangle: barycentric points and weights (summing to 1)
_A1, _B1, _W1 = 0.059715871789770, 0.470142064105115, 0.132394152788506
_A2, _B2, _W2 = 0.797426985353087, 0.101286507323456, 0.125939180544827
_BARY5 = np.array([[1 / 3, 1 / 3, 1 / 3], [_A1, _B1, _B1], [_B1, _A1, _B1], [_B1, _B1, _A1],
                   [_A2, _B2, _B2], [_B2, _A2, _B2], [_B2, _B2, _A2]])
_W5 = np.array([0.225, _W1, _W1, _W1, _W2, _W2, _W2])

def _collapsed_gauss(n: int):
    """An n x n Gauss rule on the square collapsed onto the triangle (Duffy): exact to degree 2n - 1,
    barycentric points and weights summing to 1. For the rational integrands of non-parallelogram
    quads (psi of the inverse bilinear map) a higher degree pays."""
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = 0.5 * (x + 1), 0.5 * w
    U, V = np.meshgrid(x, x, indexing="ij")
    s, t = U.ravel(), (V * (1 - U)).ravel()
    W = (np.outer(w, w) * (1 - U)).ravel() * 2
    return np.c_[1 - s - t, s, t], W


_BARY_QUAD, _W_QUAD = _collapsed_gauss(QUAD_RULE_POINTS)
_G3 = np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)])
_G3W = np.array([5.0, 8.0, 5.0]) / 18.0


# -- the reference elements ------------------------------------------------------------------------
def shape(k: int, xi: np.ndarray) -> np.ndarray:
    """The k = 3 (linear triangle, reference (0,0),(1,0),(0,1)) or k = 4 (bilinear quadrilateral on
    [0,1]^2, VTK order) shape functions at local coordinates xi (..., 2): (..., k)."""
    s, t = xi[..., 0], xi[..., 1]
    if k == 3:
        return np.stack([1 - s - t, s, t], axis=-1)
    return np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], axis=-1)


def shape_gradients(k: int, xi: np.ndarray) -> np.ndarray:
    """d phi_i / d xi_a at xi (..., 2): (..., k, 2)."""
    s, t = xi[..., 0], xi[..., 1]
    if k == 3:
        g = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
        return np.broadcast_to(g, xi.shape[:-1] + (3, 2)).copy()
    return np.stack([np.stack([-(1 - t), -(1 - s)], -1), np.stack([1 - t, -s], -1),
                     np.stack([t, s], -1), np.stack([-t, 1 - s], -1)], axis=-2)


def _reference_rule(k: int):
    """Points (m, 2) and weights (m,) on the reference element (exact for the element's mass
    matrix with a constant Jacobian)."""
    if k == 3:
        return np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 6)
    S, T = np.meshgrid(_G3, _G3, indexing="ij")
    return np.c_[S.ravel(), T.ravel()], np.outer(_G3W, _G3W).ravel()


def surface_jacobian(X: np.ndarray, k: int, xi: np.ndarray) -> np.ndarray:
    """|x_s x x_t| of the elements with vertices X (E, k, 3) at local points xi (E, m, 2) or (m, 2)."""
    xi = np.broadcast_to(xi, (len(X),) + xi.shape[-2:])
    G = shape_gradients(k, xi)                       # (E, m, k, 2)
    dx = np.einsum("emka,ekd->emad", G, X)          # (E, m, 2, 3)
    return np.linalg.norm(np.cross(dx[..., 0, :], dx[..., 1, :]), axis=-1)


def element_dual_coefficients(X: np.ndarray):
    """For elements with vertices X (E, k, 3): (A (E, k, k), De (E, k)) with psi_i = sum_j A_ij phi_j
    biorthogonal to phi_j on each element: int psi_i phi_j = delta_ij De_i, De_i = int phi_i."""
    k = X.shape[1]
    pts, w = _reference_rule(k)
    J = surface_jacobian(X, k, pts)                 # (E, m)
    phi = shape(k, pts)                             # (m, k)
    Me = np.einsum("em,mi,mj->eij", J * w, phi, phi)
    De = np.einsum("em,mi->ei", J * w, phi)
    A = De[:, :, None] * np.linalg.inv(Me)          # D_e M_e^{-1} (M_e symmetric)
    return A, De


# -- planar geometry -------------------------------------------------------------------------------
def polygon_area(P: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Signed area (shoelace) of polygons P (n, V, 2) with count[i] vertices each (counter-clockwise
    positive); slots beyond count are ignored."""
    V = P.shape[1]
    idx = np.arange(V)[None, :]
    nxt = np.where(idx + 1 < count[:, None], idx + 1, 0)
    Q = np.take_along_axis(P, nxt[:, :, None], axis=1)
    valid = idx < count[:, None]
    cr = P[:, :, 0] * Q[:, :, 1] - P[:, :, 1] * Q[:, :, 0]
    return 0.5 * np.where(valid, cr, 0.0).sum(axis=1)


def clip_polygons(subject: np.ndarray, sub_count: np.ndarray, clip: np.ndarray, clip_count: np.ndarray):
    """Sutherland-Hodgman, vectorized over n pairs: the subject polygons (n, Vs, 2) (counter-
    clockwise, sub_count vertices each) clipped by the convex counter-clockwise polygons clip
    (n, Vc, 2) (clip_count vertices). Returns (P (n, Vs + Vc, 2), count (n,)): the convex
    intersection (count < 3: empty)."""
    n = len(subject)
    V = subject.shape[1] + clip.shape[1]
    P = np.zeros((n, V, 2))
    P[:, :subject.shape[1]] = subject
    count = np.asarray(sub_count, dtype=np.int64).copy()
    idx = np.arange(V)[None, :]
    rows = np.arange(n)[:, None]
    for e in range(clip.shape[1]):
        has = e < clip_count
        a = clip[:, e]
        b = np.take_along_axis(clip, np.where(e + 1 < clip_count, e + 1, 0)[:, None, None].repeat(2, 2), axis=1)[:, 0]
        ab = b - a
        valid = idx < count[:, None]
        nxt = np.where(idx + 1 < count[:, None], idx + 1, 0)
        Q = np.take_along_axis(P, nxt[:, :, None], axis=1)
        dP = ab[:, None, 0] * (P[:, :, 1] - a[:, None, 1]) - ab[:, None, 1] * (P[:, :, 0] - a[:, None, 0])
        dQ = ab[:, None, 0] * (Q[:, :, 1] - a[:, None, 1]) - ab[:, None, 1] * (Q[:, :, 0] - a[:, None, 0])
        inP, inQ = dP >= 0, dQ >= 0
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(inP != inQ, dP / (dP - dQ), 0.0)
        X = P + t[:, :, None] * (Q - P)
        # each edge P->Q emits P if P is inside, then the crossing if it crosses: in this order
        emit = np.stack([valid & inP, valid & (inP != inQ)], axis=2).reshape(n, 2 * V)
        pts = np.stack([P, X], axis=2).reshape(n, 2 * V, 2)
        order = np.argsort(~emit, axis=1, kind="stable")[:, :V]
        newP = pts[rows, order]
        newc = emit.sum(axis=1)
        # a pair whose clip polygon has fewer edges keeps its polygon
        P = np.where(has[:, None, None], newP, P)
        count = np.where(has, np.minimum(newc, V), count)
    return P, count


def _solve2(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """J^{-1} r for (n, 2, 2) and (n, 2), written out (a batched LAPACK call costs more)."""
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    return np.stack([J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1], J[:, 0, 0] * r[:, 1] - J[:, 1, 0] * r[:, 0]], 1) / det[:, None]


def plane_jacobian(verts: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """d x / d xi (n, 2, 2) (rows: x components) of planar elements verts (n, k, 2) at xi (n, 2)."""
    G = shape_gradients(verts.shape[1], xi)          # (n, k, 2)
    return (verts[:, :, :, None] * G[:, :, None, :]).sum(axis=1)


def local_coordinates(verts: np.ndarray, x: np.ndarray, iterations: int = 12) -> np.ndarray:
    """xi (n, 2) with sum_i phi_i(xi) verts[:, i] = x for planar elements verts (n, k, 2): affine
    for triangles, Newton for bilinear quadrilaterals (quadratic convergence from the centre on
    convex ones; stopped once every step is at round-off)."""
    k = verts.shape[1]
    v0 = verts[:, 0]
    if k == 3:
        J = np.stack([verts[:, 1] - v0, verts[:, 2] - v0], axis=2)  # columns
        return _solve2(J, x - v0)
    xi = np.full((len(x), 2), 0.5)
    for _ in range(iterations):
        r = (shape(4, xi)[:, :, None] * verts).sum(axis=1) - x
        step = _solve2(plane_jacobian(verts, xi), r)
        xi -= step
        if np.abs(step).max(initial=0.0) < 1e-15:
            break
    return xi


# -- the coupling ----------------------------------------------------------------------------------
def _element_frames(X: np.ndarray):
    """Centre (E, 3), unit normal (E, 3) (right-hand rule of the vertex order: outward for boundary
    facets), in-plane axes e1, e2 (E, 3) with e1 x e2 = n, and the vector area (E, 3)."""
    k = X.shape[1]
    c = X.mean(axis=1)
    if k == 3:
        area = 0.5 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    else:
        area = 0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    n = area / np.linalg.norm(area, axis=1)[:, None]
    e1 = X[:, 1] - X[:, 0]
    e1 -= np.einsum("ij,ij->i", e1, n)[:, None] * n
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return c, n, e1, np.cross(n, e1), area


def _check_surface(x: np.ndarray, facets: np.ndarray, name: str) -> np.ndarray:
    facets = np.asarray(facets, dtype=np.int64)
    if facets.ndim != 2 or facets.shape[1] not in (3, 4):
        raise ValueError(f"the {name} facets must be triangles (n, 3) or quadrilaterals (n, 4), got shape {facets.shape}")
    if len(facets) == 0:
        raise ValueError("a contact pair needs nonmortar and mortar facets")
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"3D mortar needs points of shape (n, 3), got {x.shape}")
    if facets.min() < 0 or facets.max() >= len(x):
        raise ValueError(f"the {name} facets refer to points that do not exist")
    return facets


def _candidate_pairs(XS, cS, nS, XM, cM, nM, search: float):
    """(nonmortar, mortar) element pairs whose projections may overlap: the mortar element faces the
    nonmortar one (n_m . n_s < 0), lies within `search` (plus its radius) of the nonmortar plane
    along the normal, and its centre within the sum of the radii of the nonmortar centre across it.
    A k-d tree of the mortar centres gives the candidates."""
    rS = np.linalg.norm(XS - cS[:, None], axis=2).max(axis=1)
    rM = np.linalg.norm(XM - cM[:, None], axis=2).max(axis=1)
    # |c_m - c_s| <= lateral + |normal distance| <= (rS + rM) + (search + rM)
    near = cKDTree(cM).query_ball_point(cS, rS + 2 * rM.max() + search)
    iS = np.repeat(np.arange(len(XS)), [len(v) for v in near])
    iM = np.fromiter((j for v in near for j in v), dtype=np.int64, count=len(iS))
    dist = np.einsum("ij,ij->i", cM[iM] - cS[iS], nS[iS])
    lateral = np.linalg.norm(cM[iM] - cS[iS] - dist[:, None] * nS[iS], axis=1)
    ok = (np.abs(dist) <= search + rM[iM]) & (lateral <= rS[iS] + rM[iM]) & (np.einsum("ij,ij->i", nM[iM], nS[iS]) < 0)
    return iS[ok], iM[ok]


def _in_plane(X: np.ndarray, c: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """Points X (p, k, 3) in the plane coordinates (p, k, 2) of the frames (c, e1, e2) (p, 3): the
    orthogonal projection along e1 x e2."""
    r = X - c[:, None]
    return np.stack([np.einsum("pkd,pd->pk", r, e1), np.einsum("pkd,pd->pk", r, e2)], axis=2)


def mortar_coupling_3d(xs: np.ndarray, slave_facets: np.ndarray, xm: np.ndarray, master_facets: np.ndarray,
                       search: float, fixed: np.ndarray = None) -> MortarCoupling:
    """The dual mortar matrices of the nonmortar surface `slave_facets` (triangles or quads of node
    ids of the points xs, oriented with the outward normal of their body by the right-hand rule)
    against the mortar surface `master_facets` of xm (oriented likewise, out of the other body).
    A nonmortar element couples with the mortar elements that face it within distance `search`
    along its normal (on either side: an initial penetration is seen too). `fixed` (len(xs), 3):
    the nonmortar mesh's Dirichlet-prescribed axes (see mortar.dual_coupling)."""
    xs, xm = np.asarray(xs, dtype=float), np.asarray(xm, dtype=float)
    sf = _check_surface(xs, slave_facets, "nonmortar")
    mf = _check_surface(xm, master_facets, "mortar")
    if not (search > 0 and np.isfinite(search)):
        raise ValueError(f"the mortar search distance must be positive and finite, got {search!r}")
    nodes, local = np.unique(sf, return_inverse=True)
    local = local.reshape(sf.shape)
    ns, ks, km, E = len(nodes), sf.shape[1], mf.shape[1], len(sf)
    XS, XM = xs[sf], xm[mf]
    A_full, De_full = element_dual_coefficients(XS)
    cS, nS, e1, e2, areaS = _element_frames(XS)
    cM, nM, _, _, _ = _element_frames(XM)
    normals = np.zeros((ns, 3))
    for j in range(ks):
        np.add.at(normals, local[:, j], areaS)
    normals /= np.linalg.norm(normals, axis=1)[:, None]

    iS, iM = _candidate_pairs(XS, cS, nS, XM, cM, nM, search)
    Mc, mc, area = np.zeros((E, ks, ks)), np.zeros((E, ks)), np.zeros(E)
    pair_e, pair_m, pair_E = [], [], []
    for chunk in np.array_split(np.arange(len(iS)), max(1, len(iS) // 20000)):
        if len(chunk) == 0:
            continue
        a, b = iS[chunk], iM[chunk]
        # both elements in the nonmortar element's plane coordinates (projection along its normal)
        S2, M2 = _in_plane(XS[a], cS[a], e1[a], e2[a]), _in_plane(XM[b], cS[a], e1[a], e2[a])
        # the mortar element faces the other way: reversed, its projection runs counter-clockwise
        P, cnt = clip_polygons(M2[:, ::-1], np.full(len(a), km), S2, np.full(len(a), ks))
        parea = polygon_area(P, cnt)
        keep = (cnt >= 3) & (parea > 1e-12 * np.linalg.norm(areaS[a], axis=1))
        if not np.any(keep):
            continue
        a, b, S2, M2, P, cnt = a[keep], b[keep], S2[keep], M2[keep], P[keep], cnt[keep]
        # fan triangles (v0, v_j, v_j+1), j = 1..cnt-2, and the Gauss points on each
        V = P.shape[1]
        j = np.arange(1, V - 1)
        tri_ok = (j[None, :] + 1) < cnt[:, None]
        pi, ji = np.nonzero(tri_ok)
        T0, T1, T2 = P[pi, 0], P[pi, ji + 1], P[pi, ji + 2]
        tarea = 0.5 * np.abs((T1[:, 0] - T0[:, 0]) * (T2[:, 1] - T0[:, 1]) - (T1[:, 1] - T0[:, 1]) * (T2[:, 0] - T0[:, 0]))
        bary, wts = (_BARY5, _W5) if ks == 3 else (_BARY_QUAD, _W_QUAD)
        g = np.einsum("gk,tkd->tgd", bary, np.stack([T0, T1, T2], axis=1)).reshape(-1, 2)
        w = (tarea[:, None] * wts[None, :]).ravel()
        q = np.repeat(pi, len(wts))                  # the pair of each point (sorted)
        xi_s = local_coordinates(S2[q], g)
        xi_m = local_coordinates(M2[q], g)
        phi_s, phi_m = shape(ks, xi_s), shape(km, xi_m)
        if ks == 4:
            # the nonmortar surface's measure: plane area times J_surface / J_plane
            Js = surface_jacobian(XS[a[q]], 4, xi_s[:, None, :])[:, 0]
            Gp = plane_jacobian(S2[q], xi_s)
            w = w * Js / np.abs(Gp[:, 0, 0] * Gp[:, 1, 1] - Gp[:, 0, 1] * Gp[:, 1, 0])
        wphi = w[:, None] * phi_s
        # summed per pair (the points of a pair are consecutive)
        starts = np.flatnonzero(np.r_[True, q[1:] != q[:-1]])
        pairs = q[starts]
        pair_e.append(a[pairs])
        pair_m.append(b[pairs])
        pair_E.append(np.add.reduceat(wphi[:, :, None] * phi_m[:, None, :], starts, axis=0))
        np.add.at(Mc, a[pairs], np.add.reduceat(wphi[:, :, None] * phi_s[:, None, :], starts, axis=0))
        np.add.at(mc, a[pairs], np.add.reduceat(wphi, starts, axis=0))
        np.add.at(area, a[pairs], np.add.reduceat(w, starts))
    if pair_e:
        pairs = (np.concatenate(pair_e), np.concatenate(pair_m), np.concatenate(pair_E))
    else:
        pairs = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, ks, km)))
    return dual_coupling(nodes, local, len(xs), A_full, De_full, (Mc, mc, area), pairs, mf, len(xm), normals,
                         fixed, k_full=ks)
