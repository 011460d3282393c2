// The exact local solver of the nonlinear Gauss-Seidel smoother (DESIGN section 3):
//   minimize 1/2 x^T B x - b^T x + s |x_T|  subject to x_n <= g,
// in the node's frame (component 0 normal, the rest tangential). One routine for d = 2 and 3.
// The cases x_n = g and x_T = 0 are assigned exactly, so "active" and "sticking" are exact tests.
// A tangential component fixed by a Dirichlet condition has been eliminated before (identity row
// and column in B, its value in b): friction then acts on the free tangential components only,
// |x_T| read as |x_free| (`free`: bit a-1 set for a free frame component a), so that a prescribed
// tangential value stays exact.
#pragma once
#include <cmath>
#include "common.hpp"

namespace cmg {

// Bit mask of the free tangential components of a contact node (bit a-1 for frame component a).
using TangentMask = unsigned;
template <int d> constexpr TangentMask all_tangents() { return (1u << (d - 1)) - 1; }

template <int d>
struct Tangential {
  static constexpr int m = d - 1;
  using V = Eigen::Matrix<double, m, 1>;
  using M = Eigen::Matrix<double, m, m>;

  // argmin 1/2 x^T S x - c^T x + s |x_free|, S symmetric positive definite, s >= 0; a fixed
  // component is decoupled in S (eliminated Dirichlet dof).
  static V solve(const M& S, const V& c, double s, TangentMask free = all_tangents<d>()) {
    if (s <= 0) return S.ldlt().solve(c);
    if (free != all_tangents<d>()) return solve_partly_fixed(S, c, s, free);
    const double cn = c.norm();
    if (cn <= s) return V::Zero();
    if constexpr (m == 1) {
      return V::Constant((c[0] > 0 ? cn - s : s - cn) / S(0, 0));
    } else {
      // x = (S + (s/rho) I)^{-1} c with rho = |x| the root of sum c~_i^2 / (sigma_i rho + s)^2 = 1;
      // the left side is convex and decreasing, so Newton from rho = 0 increases monotonically.
      Eigen::SelfAdjointEigenSolver<M> eig(S);
      const V sig = eig.eigenvalues();
      const V ct = eig.eigenvectors().transpose() * c;
      double rho = 0;
      for (int it = 0; it < 200; ++it) {
        double phi = -1, dphi = 0;
        for (int i = 0; i < m; ++i) {
          const double q = sig[i] * rho + s;
          phi += ct[i] * ct[i] / (q * q);
          dphi -= 2 * ct[i] * ct[i] * sig[i] / (q * q * q);
        }
        const double step = -phi / dphi;
        rho += step;
        if (!(step > 1e-15 * rho)) break;
      }
      V xt;
      for (int i = 0; i < m; ++i) xt[i] = ct[i] * rho / (sig[i] * rho + s);
      return eig.eigenvectors() * xt;
    }
  }

  // Some tangential components fixed (m <= 2, so at most one free one): every component is
  // decoupled, the free one solves a scalar problem with the friction s |x_k|.
  static V solve_partly_fixed(const M& S, const V& c, double s, TangentMask free) {
    V x;
    for (int k = 0; k < m; ++k) {
      if (!(free >> k & 1u)) { x[k] = c[k] / S(k, k); continue; }
      const double a = std::abs(c[k]);
      x[k] = a <= s ? 0.0 : (c[k] > 0 ? a - s : s - a) / S(k, k);
    }
    return x;
  }
};

// Tresca (given bound s; s = 0 is frictionless): the exact minimizer.
template <int d>
Vec<d> solve_node_tresca(const Mat<d>& B, const Vec<d>& b, double g, double s, TangentMask free = all_tangents<d>()) {
  using T = Tangential<d>;
  constexpr int m = d - 1;
  Vec<d> x;
  const double Bnn = B(0, 0);
  const typename T::V BTn = B.template block<m, 1>(1, 0);
  const typename T::M BTT = B.template block<m, m>(1, 1);
  const typename T::V bT = b.template tail<m>();
  // x_n free: eliminate it.
  typename T::M S = BTT - BTn * BTn.transpose() / Bnn;
  typename T::V c = bT - BTn * (b[0] / Bnn);
  typename T::V xT = T::solve(S, c, s, free);
  double xn = (b[0] - BTn.dot(xT)) / Bnn;
  if (xn > g) {
    xn = g;
    xT = T::solve(BTT, bT - BTn * g, s, free);
  }
  x[0] = xn;
  x.template tail<m>() = xT;
  return x;
}

// Coulomb on the gap: x_n = g and x_T the Tresca minimizer for the bound s = F |s_n| with s_n =
// (A u - f)_n evaluated at (g, start_T) — the bound is lagged, not iterated to a local fixed point.
// s_n depends on x_T through the off-diagonal of the node's block, and where F |B_nT| exceeds the
// tangential stiffness (F > ~4.8 at Hertz boundary nodes, nu = 0.28) the sliding branch of the
// local problem has negative effective stiffness: a local fixed-point loop then runs off it into
// tension and the node lifts, so a solution with sliding nodes there is never a fixed point of the
// smoother (Hertz F = 5 level 7 stalled in a limit cycle that way). With the lagged bound a
// solution is a fixed point, and the map has no jumps. Returns s_n at the new position.
template <int d>
double coulomb_on_gap(const Mat<d>& B, const Vec<d>& b, double g, double F, const Vec<d>& start, Vec<d>& x,
                      TangentMask free = all_tangents<d>()) {
  constexpr int m = d - 1;
  using T = Tangential<d>;
  const typename T::V BTn = B.template block<m, 1>(1, 0);
  const double sn = B(0, 0) * g + BTn.dot(start.template tail<m>()) - b[0];
  const typename T::V xt = T::solve(B.template block<m, m>(1, 1), b.template tail<m>() - BTn * g, F * std::max(0.0, -sn), free);
  x[0] = g;
  x.template tail<m>() = xt;
  return B(0, 0) * g + BTn.dot(xt) - b[0];
}

// Coulomb inside the smoother (Algorithm 2). Every local Coulomb solution must be a fixed point of
// this rule, else a solution of the whole problem is not a fixed point of the smoother:
//  - a node on the gap (old x_n == g) first solves on the gap; it stays there while that solution
//    is compressive (s_n <= 0). A frictionless trial would release its friction force, and where the
//    block couples normal and tangential (B_nT != 0) the released tangential motion can lift it
//    (at F = 8 and 40 on Hertz level 7 nodes then alternated between lifted and sticking).
//  - a node off the gap (or whose gap solution pulls) takes the frictionless trial; if that leaves
//    it off the obstacle it carries no friction. Never a Tresca bound taken from the residual
//    before the visit: after a coarse correction a node about to lift can still show a compressive
//    residual and would stick sideways while it lifts (a prototype failed for F >= 5 that way).
//  - otherwise it goes onto the gap with the lagged bound of its old tangential position.
template <int d>
Vec<d> solve_node_coulomb(const Mat<d>& B, const Vec<d>& b, double g, double F, const Vec<d>& old,
                          TangentMask free = all_tangents<d>()) {
  if (F <= 0) return solve_node_tresca<d>(B, b, g, 0.0, free);
  Vec<d> x;
  const bool on_gap = old[0] >= g;
  if (on_gap && coulomb_on_gap<d>(B, b, g, F, old, x, free) <= 0) return x;
  Vec<d> trial = solve_node_tresca<d>(B, b, g, 0.0, free);
  if (trial[0] < g) return trial;
  if (!on_gap) coulomb_on_gap<d>(B, b, g, F, old, x, free);  // else x holds it already (same inputs)
  return x;
}

}  // namespace cmg
