"""The 2D dual mortar coupling of a nonmortar (slave) and a mortar (master) boundary (Wohlmuth).

On each nonmortar segment [a, b] the dual basis functions psi_a = 2 phi_a - phi_b, psi_b =
2 phi_b - phi_a are biorthogonal to the trace hat functions: int psi_p phi_q = delta_pq D_p with
D_p = int phi_p (half the lengths of the segments at p), so the nonmortar matrix D is diagonal.
The mortar matrix M_pq = int psi_p phi_q^master is integrated segment by segment on the overlap
of the nonmortar segment with the mortar segments projected onto it along the segment's normal:
the overlap is cut at the projected mortar nodes, so on each piece both factors are linear and a
2-point Gauss rule is exact.

With Mhat = D^{-1} M the discrete non-penetration condition of node p reads
(u_p - sum_q Mhat_pq u_q) . n_p <= g_p, g_p = (sum_q Mhat_pq x_q - x_p) . n_p: a nodal condition on
the relative displacement w_p = u_p - (Mhat u_m)_p, which is what the basis transformation
u = T w (T = I + N, N = Mhat on the nonmortar rows and mortar columns) hands to the nodal solvers.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

_GAUSS2 = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))


@dataclass
class MortarCoupling:
    """D (per nonmortar node), M (nonmortar x mortar nodes, local ids of the two meshes), the
    nodes of the nonmortar boundary with their averaged outward normals, and covered[p]: whether
    the projected mortar boundary covers the whole support of psi_p (sum_q M_pq = D_p)."""

    nonmortar_nodes: np.ndarray   # (ns,) node ids of the nonmortar mesh
    D: np.ndarray                 # (ns,)
    M: sp.csr_matrix              # (ns, num mortar mesh points)
    normals: np.ndarray           # (ns, 2) unit, out of the nonmortar body
    covered: np.ndarray           # (ns,) bool

    @property
    def Mhat(self) -> sp.csr_matrix:
        """D^{-1} M: the nonmortar rows of the coupling in the mortar nodes' columns."""
        return sp.diags(1.0 / self.D) @ self.M

    def gaps(self, nonmortar_points: np.ndarray, mortar_points: np.ndarray) -> np.ndarray:
        """g_p = (Mhat x_m - x_p) . n_p: the weighted gap of the dual basis."""
        xm = self.Mhat @ mortar_points
        return np.einsum("ij,ij->i", xm - nonmortar_points[self.nonmortar_nodes], self.normals)


def _segment_normals(x: np.ndarray, segs: np.ndarray) -> np.ndarray:
    t = x[segs[:, 1]] - x[segs[:, 0]]
    # boundary facets run counter-clockwise around their body: the outward normal is (t_y, -t_x)
    return np.c_[t[:, 1], -t[:, 0]] / np.linalg.norm(t, axis=1)[:, None]


def mortar_coupling_2d(xs: np.ndarray, slave_segs: np.ndarray, xm: np.ndarray, master_segs: np.ndarray,
                       search: float) -> MortarCoupling:
    """The dual mortar matrices of the nonmortar segments `slave_segs` (pairs of node ids of the
    points xs, oriented with the body on the left) against the mortar segments `master_segs` of
    xm. A nonmortar point sees the mortar segment hit by its normal ray within distance `search`
    (the nearest one, on either side: an initial penetration is seen too)."""
    slave_segs = np.asarray(slave_segs, dtype=np.int64).reshape(-1, 2)
    master_segs = np.asarray(master_segs, dtype=np.int64).reshape(-1, 2)
    if len(slave_segs) == 0 or len(master_segs) == 0:
        raise ValueError("a contact pair needs nonmortar and mortar segments")
    if not (search > 0 and np.isfinite(search)):
        raise ValueError(f"the mortar search distance must be positive and finite, got {search!r}")
    nodes, local = np.unique(slave_segs, return_inverse=True)
    local = local.reshape(-1, 2)
    ns = len(nodes)
    seg_n = _segment_normals(xs, slave_segs)
    seg_len = np.linalg.norm(xs[slave_segs[:, 1]] - xs[slave_segs[:, 0]], axis=1)
    D = np.zeros(ns)
    np.add.at(D, local.ravel(), np.repeat(seg_len / 2, 2))
    normals = np.zeros((ns, 2))
    np.add.at(normals, local[:, 0], seg_n * seg_len[:, None])
    np.add.at(normals, local[:, 1], seg_n * seg_len[:, None])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    covered_len = np.zeros(ns)

    ma, mb = xm[master_segs[:, 0]], xm[master_segs[:, 1]]
    rows, cols, vals = [], [], []
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
            for g in _GAUSS2:
                xi = lo + g * (hi - lo)
                w = (hi - lo) * L / 2  # Gauss weight 1/2 on [0, 1] times ds
                x = A + xi * (B - A)
                eta = _line_parameter(x, n, ma[q], mb[q])
                psi = (2 - 3 * xi, 3 * xi - 1)
                phi = (1 - eta, eta)
                for p_loc, ps in zip(local[k], psi):
                    for q_node, ph in zip(master_segs[q], phi):
                        rows.append(p_loc)
                        cols.append(q_node)
                        vals.append(w * ps * ph)
                    covered_len[p_loc] += w * (1 - xi if p_loc == local[k][0] else xi)
    M = sp.csr_matrix((vals, (rows, cols)), shape=(ns, len(xm)))
    M.sum_duplicates()
    covered = covered_len >= D * (1 - 1e-9)
    return MortarCoupling(nodes, D, M, normals, covered)


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
