"""The dual mortar coupling of a nonmortar (slave) and a mortar (master) boundary (Wohlmuth), its 2D
construction, and the steps 2D and 3D share (mortar_3d.py builds the 3D overlaps).

On each nonmortar element e the dual basis psi_i = sum_j A_ij phi_j is biorthogonal to the trace hat
functions on the part of e that the mortar side covers (Omega_e, the overlap of e with the mortar
elements projected along e's normal): int_Omega psi_i phi_j = delta_ij int_Omega phi_i. So the
nonmortar matrix D_p = int psi_p phi_p is diagonal, and the mortar matrix M_pq = int psi_p phi_q^mortar
has rows summing to D_p (sum_q phi_q^mortar = 1 on Omega): a rigid translation of both bodies leaves
every weighted gap unchanged, however much of a nonmortar element the mortar side covers. Where it
covers all of e this is the standard dual basis (psi_a = 2 phi_a - phi_b in 2D); on a partly covered
element (the edge of the mortar surface, faceted curved surfaces whose projections fall short by
round-off or by O(h^2)) the basis is the one of the covered part (Popp, Wohlmuth, Gee & Wall 2012).

Nonmortar nodes that cannot carry their own condition are taken out of the multiplier space by the
boundary modification of the dual basis (Wohlmuth 2001; Popp & Wall): a node whose displacement is
prescribed along its normal or in every component (a clamped edge of the contact surface), or whose
support faces the mortar side over less than MIN_NODE_COVER of its measure. On each element such a
node's psi is shared among the element's kept nodes (psi_b += psi_a / #kept), so the modified basis
still sums to 1 (constants stay in the multiplier space, and rows still sum to D) and D stays
diagonal; the kept nodes' conditions then couple the excluded node's displacement (S below), which
is the mortar side's role for it. A node with only tangential components prescribed (a symmetry plane
through the contact zone) keeps its condition: its normal is turned into the free directions (the
normal of the mirrored model) and the transformation leaves the prescribed components alone.

With Mhat = D^{-1} M and Shat = D^{-1} S the condition of kept node p reads
(u_p + (Shat u_s)_p - (Mhat u_m)_p) . n_p <= g_p, g_p = (Mhat x_m - x_p - Shat x_s)_p . n_p: a nodal
condition on the relative displacement w_p, which the basis transformation u = T w (T = I + N, N =
Mhat on the nonmortar rows and mortar columns, -Shat in the excluded nonmortar columns, projected onto
the node's free directions) hands to the nodal solvers.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

_GAUSS2 = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))

# A nonmortar element covered to within this fraction of its measure takes the standard dual basis
# (the covered measure is exact for triangles and segments; 1e-4 for warped or non-parallelogram
# quadrilaterals, whose overlap integrands the rule integrates to about that).
FULL_COVER = {2: 1e-9, 3: 1e-9, 4: 1e-4}
# An element covered over less than this fraction counts as not covered: the overlap's mass matrix
# would be near-singular (its condition grows like the inverse square of the fraction).
MIN_ELEMENT_COVER = 1e-3
# A node whose covered measure is below this fraction of its support's is taken out of the
# multiplier space (boundary modification): it faces the mortar side only at its support's edge.
MIN_NODE_COVER = 1e-2
# A node with tangential components prescribed keeps its condition if its normal turned into the
# free directions keeps at least this length (the angle to the free directions at most 60 degrees).
MIN_FREE_NORMAL = 0.5


@dataclass
class MortarCoupling:
    """The dual mortar coupling of one pair: the nonmortar nodes that carry a contact condition (node
    ids of the nonmortar mesh) with D (per node), M (nodes x mortar mesh points), S (nodes x nonmortar
    mesh points: the excluded nonmortar nodes' weights under the modified dual basis; empty where no
    node is excluded), unit normals out of the nonmortar body, and free[p, a]: whether axis a of node
    p is free (False: prescribed, left alone by the transformation). `excluded`: nonmortar nodes taken
    out of the multiplier space because Dirichlet data holds them along their normal (or in every
    component); `uncovered`: nonmortar nodes whose support the mortar side does not cover (within the
    search distance) over MIN_NODE_COVER of its measure."""

    nonmortar_nodes: np.ndarray   # (ns,) node ids of the nonmortar mesh
    D: np.ndarray                 # (ns,)
    M: sp.csr_matrix              # (ns, num mortar mesh points)
    normals: np.ndarray           # (ns, d) unit, out of the nonmortar body
    S: sp.csr_matrix = None       # (ns, num nonmortar mesh points)
    free: np.ndarray = None       # (ns, d) bool
    excluded: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    uncovered: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def Mhat(self) -> sp.csr_matrix:
        """D^{-1} M: the nonmortar rows of the coupling in the mortar nodes' columns."""
        return sp.diags(1.0 / self.D) @ self.M

    @property
    def Shat(self) -> sp.csr_matrix:
        """D^{-1} S: the weights of the excluded nonmortar nodes in the kept nodes' conditions."""
        return sp.diags(1.0 / self.D) @ self.S

    def gaps(self, nonmortar_points: np.ndarray, mortar_points: np.ndarray) -> np.ndarray:
        """g_p = (Mhat x_m - x_p - Shat x_s) . n_p: the weighted gap of the dual basis between the
        facets (see true_gaps for the gap between the surfaces the facets approximate)."""
        x = self.Mhat @ mortar_points - nonmortar_points[self.nonmortar_nodes] - self.Shat @ nonmortar_points
        return np.einsum("ij,ij->i", x, self.normals)

    def true_gaps(self, nonmortar_points: np.ndarray, project_mortar, mortar_tags: np.ndarray,
                  project_nonmortar=None, nonmortar_tags: np.ndarray = None) -> np.ndarray:
        """g_p: the distance along n_p from each node (on its body's surface) to the mortar surface,
        where `project_mortar(points, tags)` (the closest point) describes that surface (see
        covers_facets; `mortar_tags` per node: the tag of the mortar facets it faces). The ray is
        followed to the tangent plane at the closest point until it lands (Newton's method on the
        distance: the closest point's direction alone is the mortar's normal, 35 degrees off n_p at
        a third of the radius from two touching spheres' contact point). With `project_nonmortar`
        (and the nodes' `nonmortar_tags`) the ray starts from the node's closest point on its own
        surface: a node refined on an edge between a curved and a flat facet may have been left on
        the chord (0.3 % of the radius off a sphere's octant edge).
        Why: two faceted approximations of one curved surface (concentric rings meshed apart) cut
        into each other by about h^2 / 8R between their facets, an interference that does not scale
        with the load and dominates the pressure of stiff bodies; between the surfaces it is zero.
        The nodal value is the one-body obstacle's gap: a dual-weighted average of a curved gap
        (two spheres touching, a gap of r^2 / R) falls below the nodal value by O(h^2 / R) where
        the dual basis has its negative lobes."""
        x = nonmortar_points[self.nonmortar_nodes]
        if project_nonmortar is not None:
            x = np.asarray(project_nonmortar(x, nonmortar_tags), float)
        n = self.normals
        s = np.zeros(len(x))
        for _ in range(20):
            y = x + s[:, None] * n
            v = np.asarray(project_mortar(y, mortar_tags), float) - y
            vv, vn = np.einsum("ij,ij->i", v, v), np.einsum("ij,ij->i", v, n)
            # the step to the tangent plane at the closest point; none where the ray grazes it
            step = np.where(np.abs(vn) > 1e-3 * np.sqrt(vv), vv / np.where(vn == 0, 1.0, vn), 0.0)
            s += step
            if np.all(np.abs(step) <= 1e-15 * (1.0 + np.abs(s))):
                break
        return s


def dual_coupling(nodes: np.ndarray, local: np.ndarray, n_nonmortar: int, A_full: np.ndarray, De_full: np.ndarray,
                  covered_moments: tuple, pairs: tuple, mortar_facets: np.ndarray, n_mortar: int,
                  node_normals: np.ndarray, fixed: np.ndarray = None, k_full: int = 2) -> MortarCoupling:
    """The coupling from the overlaps, in both dimensions.

    nodes (ns,): the nonmortar facets' node ids; local (E, k): each facet's nodes as indices into
    `nodes`; A_full (E, k, k), De_full (E, k): the standard dual coefficients and int_e phi_i of each
    facet; covered_moments = (Mc (E, k, k), mc (E, k), area (E,)): int phi_i phi_j, int phi_i and the
    measure over each facet's covered part; pairs = (facet (P,), mortar facet (P,), E (P, k, km)):
    per overlapping pair int phi_i phi_j^mortar over the overlap; node_normals (ns, d): averaged
    outward normals; fixed (n_nonmortar, d) or None: the Dirichlet-prescribed axes of the nonmortar
    mesh's nodes; k_full: the facets' vertex count for FULL_COVER."""
    Mc, mc, area = covered_moments
    E, k = local.shape
    ns, d = len(nodes), node_normals.shape[1]
    full_area = De_full.sum(axis=1)
    frac = np.where(full_area > 0, area / np.where(full_area > 0, full_area, 1.0), 0.0)
    full = frac >= 1 - FULL_COVER[k_full]
    part = ~full & (frac >= MIN_ELEMENT_COVER)
    A = np.zeros((E, k, k))
    De = np.zeros((E, k))
    A[full], De[full] = A_full[full], De_full[full]
    if np.any(part):
        # the basis of the covered part: A = diag(int_Omega phi) (int_Omega phi phi^T)^{-1}
        A[part] = mc[part][:, :, None] * np.linalg.inv(Mc[part])
        De[part] = mc[part]
    D = np.zeros(ns)
    np.add.at(D, local.ravel(), De.ravel())
    D_support = np.zeros(ns)
    np.add.at(D_support, local.ravel(), De_full.ravel())

    # which nodes carry a condition, and their normals and free axes
    normals = node_normals.copy()
    free = np.ones((ns, d), bool)
    held = np.zeros(ns, bool)
    if fixed is not None:
        fx = np.asarray(fixed, bool)[nodes]
        free = ~fx
        turned = normals * free
        length = np.linalg.norm(turned, axis=1)
        held = fx.all(axis=1) | (length < MIN_FREE_NORMAL)
        some = fx.any(axis=1) & ~held
        normals[some] = turned[some] / length[some, None]
    uncovered = ~held & (D < MIN_NODE_COVER * D_support)
    out = held | uncovered
    # boundary modification: an excluded node's psi is shared among its element's kept nodes
    out_e = out[local] & (De > 0)
    kept_e = ~out[local] & (De > 0)
    nkept = kept_e.sum(axis=1)
    mod = np.flatnonzero(out_e.any(axis=1))
    S_rows, S_cols, S_vals = [], [], []
    for e in mod:
        if nkept[e] == 0:
            A[e] = 0.0
            continue
        share = A[e][out_e[e]].sum(axis=0) / nkept[e]
        for i in np.flatnonzero(kept_e[e]):
            A[e, i] += share
            for a in np.flatnonzero(out_e[e]):
                # int psi_i^mod phi_a = int psi_a phi_a / #kept (biorthogonality on the covered part)
                S_rows.append(local[e, i])
                S_cols.append(nodes[local[e, a]])
                S_vals.append(De[e, a] / nkept[e])
        A[e][out_e[e]] = 0.0
    fe, fm, Epair = pairs
    keep_rows = np.flatnonzero(~out & (D > 0))
    new_row = np.full(ns, -1)
    new_row[keep_rows] = np.arange(len(keep_rows))
    if len(fe):
        contrib = np.einsum("pij,pjk->pik", A[fe], Epair)      # int psi_i phi_k^mortar per pair
        rows = np.broadcast_to(local[fe][:, :, None], contrib.shape).ravel()
        cols = np.broadcast_to(mortar_facets[fm][:, None, :], contrib.shape).ravel()
        vals = contrib.ravel()
        sel = new_row[rows] >= 0
        M = sp.csr_matrix((vals[sel], (new_row[rows[sel]], cols[sel])), shape=(len(keep_rows), n_mortar))
    else:
        M = sp.csr_matrix((len(keep_rows), n_mortar))
    M.sum_duplicates()
    S_rows = new_row[np.asarray(S_rows, np.int64)] if S_rows else np.zeros(0, np.int64)
    S = sp.csr_matrix((np.asarray(S_vals, float), (S_rows, np.asarray(S_cols, np.int64))),
                      shape=(len(keep_rows), n_nonmortar))
    S.sum_duplicates()
    return MortarCoupling(nodes[keep_rows], D[keep_rows], M, np.ascontiguousarray(normals[keep_rows]), S=S,
                          free=free[keep_rows], excluded=nodes[held & (D > 0)], uncovered=nodes[uncovered])


def _segment_normals(x: np.ndarray, segs: np.ndarray) -> np.ndarray:
    t = x[segs[:, 1]] - x[segs[:, 0]]
    # boundary facets run counter-clockwise around their body: the outward normal is (t_y, -t_x)
    return np.c_[t[:, 1], -t[:, 0]] / np.linalg.norm(t, axis=1)[:, None]


def mortar_coupling_2d(xs: np.ndarray, slave_segs: np.ndarray, xm: np.ndarray, master_segs: np.ndarray,
                       search: float, fixed: np.ndarray = None) -> MortarCoupling:
    """The dual mortar matrices of the nonmortar segments `slave_segs` (pairs of node ids of the
    points xs, oriented with the body on the left) against the mortar segments `master_segs` of
    xm. A nonmortar point sees the mortar segment hit by its normal ray within distance `search`
    (the nearest one, on either side: an initial penetration is seen too). `fixed` (len(xs), 2):
    the nonmortar mesh's Dirichlet-prescribed axes (see dual_coupling)."""
    slave_segs = np.asarray(slave_segs, dtype=np.int64).reshape(-1, 2)
    master_segs = np.asarray(master_segs, dtype=np.int64).reshape(-1, 2)
    if len(slave_segs) == 0 or len(master_segs) == 0:
        raise ValueError("a contact pair needs nonmortar and mortar segments")
    if not (search > 0 and np.isfinite(search)):
        raise ValueError(f"the mortar search distance must be positive and finite, got {search!r}")
    nodes, local = np.unique(slave_segs, return_inverse=True)
    local = local.reshape(-1, 2)
    ns, E = len(nodes), len(slave_segs)
    seg_n = _segment_normals(xs, slave_segs)
    seg_len = np.linalg.norm(xs[slave_segs[:, 1]] - xs[slave_segs[:, 0]], axis=1)
    normals = np.zeros((ns, 2))
    np.add.at(normals, local[:, 0], seg_n * seg_len[:, None])
    np.add.at(normals, local[:, 1], seg_n * seg_len[:, None])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    Mc, mc, area = np.zeros((E, 2, 2)), np.zeros((E, 2)), np.zeros(E)
    pair_e, pair_m, pair_E = [], [], []

    ma, mb = xm[master_segs[:, 0]], xm[master_segs[:, 1]]
    for k, (a, b) in enumerate(slave_segs):
        A, B, n = xs[a], xs[b], seg_n[k]
        L = seg_len[k]
        t = (B - A) / L
        # mortar nodes projected onto the segment (orthogonal projection = along its normal)
        xi_a, xi_b = (ma - A) @ t / L, (mb - A) @ t / L
        near = (np.maximum(xi_a, xi_b) > 0) & (np.minimum(xi_a, xi_b) < 1)
        if not np.any(near):
            continue
        cuts = np.unique(np.clip(np.r_[0.0, 1.0, xi_a[near], xi_b[near]], 0.0, 1.0))
        cand = np.flatnonzero(near)
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            if hi - lo <= 1e-14:
                continue
            mid = A + 0.5 * (lo + hi) * (B - A)
            j, _ = _ray_hit(mid, n, ma[cand], mb[cand], search)
            if j < 0:
                continue
            q = cand[j]
            Ek = np.zeros((2, 2))
            for g in _GAUSS2:
                xi = lo + g * (hi - lo)
                w = (hi - lo) * L / 2  # Gauss weight 1/2 on [0, 1] times ds
                eta = _line_parameter(A + xi * (B - A), n, ma[q], mb[q])
                phi = np.array([1 - xi, xi])
                Ek += w * np.outer(phi, [1 - eta, eta])
                Mc[k] += w * np.outer(phi, phi)
                mc[k] += w * phi
                area[k] += w
            pair_e.append(k)
            pair_m.append(q)
            pair_E.append(Ek)
    A_full = np.broadcast_to(np.array([[2.0, -1.0], [-1.0, 2.0]]), (E, 2, 2))
    De_full = np.repeat(seg_len[:, None] / 2, 2, axis=1)
    pairs = (np.asarray(pair_e, np.int64), np.asarray(pair_m, np.int64),
             np.asarray(pair_E, float).reshape(-1, 2, 2))
    return dual_coupling(nodes, local, len(xs), A_full, De_full, (Mc, mc, area), pairs, master_segs, len(xm),
                         normals, fixed, k_full=2)


def covers_facets(project, points: np.ndarray, facets: np.ndarray, tags: np.ndarray) -> bool:
    """Does `project(points, tags)` describe the surface of these boundary facets? A projector leaves
    points of tags it does not know where they are, so each tag is probed: of two points a little off
    a facet on either side (1 % of its size along its normal), the projector must move one by at least
    half that offset (a point on the surface moves by nothing; the facet's centre lies within its
    sag of the surface, so one of the two is at least the offset away)."""
    if project is None or len(facets) == 0:
        return False
    for tag in np.unique(tags):
        sel = np.flatnonzero(tags == tag)[:8]
        X = points[facets[sel]]
        c = X.mean(axis=1)
        if X.shape[2] == 2:
            t = X[:, 1] - X[:, 0]
            n = np.c_[t[:, 1], -t[:, 0]]
        else:
            n = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        size = np.linalg.norm(X - c[:, None], axis=2).max(axis=1)
        n = n / np.linalg.norm(n, axis=1)[:, None]
        off = 0.01 * size
        moved = np.zeros(len(sel))
        for sign in (1.0, -1.0):
            probe = c + sign * off[:, None] * n
            q = np.asarray(project(probe, np.full(len(sel), tag)), float)
            moved = np.maximum(moved, np.linalg.norm(q - probe, axis=1))
        if not np.all(moved >= 0.5 * off):
            return False
    return True


def _ray_hit(x: np.ndarray, n: np.ndarray, a: np.ndarray, b: np.ndarray, search: float):
    """The segment [a_j, b_j] hit by the line x + s n with the smallest |s| <= search: (j, eta), eta
    the parameter on the segment; (-1, nan) if none."""
    e = b - a
    # x + s n = a + eta e  ->  [n, -e] [s, eta]^T = a - x
    det = n[0] * (-e[:, 1]) - n[1] * (-e[:, 0])
    r = a - x
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (r[:, 0] * (-e[:, 1]) - r[:, 1] * (-e[:, 0])) / det
        eta = (n[0] * r[:, 1] - n[1] * r[:, 0]) / det
    ok = (np.abs(det) > 1e-14 * np.linalg.norm(e, axis=1)) & (eta >= -1e-12) & (eta <= 1 + 1e-12) & (np.abs(s) <= search)
    if not np.any(ok):
        return -1, np.nan
    j = np.flatnonzero(ok)[np.argmin(np.abs(s[ok]))]
    return int(j), float(np.clip(eta[j], 0.0, 1.0))


def _line_parameter(x: np.ndarray, n: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """The parameter eta in [0, 1] where the line x + s n meets the line through the segment
    [a, b], clamped: at a Gauss point of a piece already known to lie over that segment. (A ray
    test with bounds rejected Gauss points of pieces a round-off wide at a segment end, eta =
    -1.05e-12, and gave M a NaN: cylinders with 4 k / 4 k arc segments at level 5.)"""
    e = b - a
    det = n[0] * (-e[1]) - n[1] * (-e[0])
    r = a - x
    return float(np.clip((n[0] * r[1] - n[1] * r[0]) / det, 0.0, 1.0))
