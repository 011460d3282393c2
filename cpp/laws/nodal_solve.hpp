// The exact local solver of the nonlinear Gauss-Seidel smoother:
//   minimize 1/2 x^T B x - b^T x + s |x_T|  subject to x_n <= g,
// in the node's frame (component 0 normal, the rest tangential). One routine for d = 2 and 3.
// The cases x_n = g and x_T = 0 are assigned exactly, so "active" and "sticking" are exact tests.
// A tangential component fixed by a Dirichlet condition has been eliminated before (identity row
// and column in B, its value in b): friction then acts on the free tangential components only,
// |x_T| read as |x_free| (`free`: bit a-1 set for a free frame component a), so that a prescribed
// tangential value stays exact.
#pragma once
#include <algorithm>
#include <cmath>
#include "base/common.hpp"

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

// The smallest tangential stiffness of B_TT over the free tangential components (the Tresca
// minimizer x_T(s) is Lipschitz in the bound s with constant 1 / this), and |B_Tn| over them.
template <int d>
void free_tangential_coupling(const Mat<d>& B, TangentMask free, double& stiffness, double& coupling) {
  constexpr int m = d - 1;
  stiffness = kInf;
  coupling = 0;
  for (int k = 0; k < m; ++k)
    if (free >> k & 1u) {
      stiffness = std::min(stiffness, B(1 + k, 1 + k));
      coupling += B(1 + k, 0) * B(1 + k, 0);
    }
  coupling = std::sqrt(coupling);
  if constexpr (m == 2)
    if (free == all_tangents<d>()) {
      // both free: the smaller eigenvalue of the symmetric 2 x 2 block
      const double a = B(1, 1), c = B(2, 2), o = B(1, 2);
      stiffness = 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + o * o);
    }
}

// Coulomb on the gap: x_n = g and x_T the Tresca minimizer x_T(s) for a bound s = F |s_n|, s_n =
// (A u - f)_n at the node. s_n depends on x_T through the off-diagonal of the node's block:
// -s_n = p(x_T) = b_n - B_nn g - B_nT x_T. Two cases, by q = F |B_nT| / lambda_min(B_TT):
//  - q < 1: the node's own Coulomb condition is solved exactly -- s is the root of
//    s = F max(0, p(x_T(s))). x_T(.) is 1/lambda_min-Lipschitz in s, so the right side is
//    q-Lipschitz: the root is unique and depends continuously on (B, b), not on the old position.
//    The lagged bound of the case below converged to it only by a factor q per visit, and at a
//    stick/slip edge node of a graded mesh (adaptive Hertz level 9, F = 40: q = 0.75) the slow
//    local iteration and the node's stick/slip switch let the cycle return to an iterate that
//    was no fixed point of the sweep (a stall).
//  - q >= 1 (F > ~4.8 at uniform Hertz boundary nodes, nu = 0.28): the sliding branch of the
//    local problem has negative effective stiffness, so it need not have a unique solution, and
//    a local fixed-point loop runs off it into tension and the node lifts (Hertz F = 5 level 7
//    stalled in a limit cycle that way). Then s is lagged: evaluated at (g, start_T). A local
//    solution is still a fixed point (it is its own start), and the map has no jumps.
// Returns s_n at the new position.
template <int d>
double coulomb_on_gap(const Mat<d>& B, const Vec<d>& b, double g, double F, const Vec<d>& start, Vec<d>& x,
                      TangentMask free = all_tangents<d>()) {
  constexpr int m = d - 1;
  using T = Tangential<d>;
  const typename T::V BTn = B.template block<m, 1>(1, 0);
  const typename T::M BTT = B.template block<m, m>(1, 1);
  const typename T::V c = b.template tail<m>() - BTn * g;
  const double p0 = b[0] - B(0, 0) * g;  // -s_n at (g, 0)
  auto pressure = [&](const typename T::V& xt) { return p0 - BTn.dot(xt); };
  double stiffness, coupling;
  free_tangential_coupling<d>(B, free, stiffness, coupling);
  const double q = stiffness > 0 ? F * coupling / stiffness : kInf;
  typename T::V xt;
  if (!(q < 1)) {
    xt = T::solve(BTT, c, F * std::max(0.0, pressure(start.template tail<m>())), free);
  } else {
    // phi(s) = F max(0, p(x_T(s))) - s decreases strictly (slope <= q - 1 < 0) from phi(0) >= 0.
    auto xt_of = [&](double s) { return T::solve(BTT, c, s, free); };
    auto phi = [&](double s, typename T::V& at) { at = xt_of(s); return F * std::max(0.0, pressure(at)) - s; };
    typename T::V at;
    const double s_stick = F * std::max(0.0, p0);  // sticking (x_T = 0) solves it if x_T(s_stick) = 0
    double f_lo = phi(0.0, at);
    xt = at;
    if (f_lo > 0) {
      double lo = 0, hi = s_stick, f_hi = phi(hi, at);
      if (f_hi > 0) {  // sliding: the root is above; phi(s) <= phi(0) - (1 - q) s brackets it
        lo = hi; f_lo = f_hi;
        hi = lo + f_lo / (1 - q);
        for (int k = 0; k < 60 && (f_hi = phi(hi, at)) > 0; ++k) { lo = hi; f_lo = f_hi; hi = lo + 2 * f_lo / (1 - q); }
      }
      // Illinois (regula falsi, the kept end's value halved when it is kept twice): exact in a
      // few steps on the piecewise-linear 2D phi; it ends at the point of smallest |phi| seen.
      double best = std::abs(f_lo) < std::abs(f_hi) ? lo : hi, f_best = std::min(std::abs(f_lo), std::abs(f_hi));
      int side = 0;
      for (int it = 0; it < 200 && f_best != 0 && hi - lo > 4e-16 * hi; ++it) {
        const double s = hi - f_hi * (hi - lo) / (f_hi - f_lo);
        if (!(s > lo && s < hi)) break;
        const double fs = phi(s, at);
        if (std::abs(fs) < f_best) { best = s; f_best = std::abs(fs); }
        if (fs > 0) { lo = s; f_lo = fs; if (side == -1) f_hi *= 0.5; side = -1; }
        else { hi = s; f_hi = fs; if (side == 1) f_lo *= 0.5; side = 1; }
      }
      xt = xt_of(best);
    }
  }
  x[0] = g;
  x.template tail<m>() = xt;
  return -pressure(xt);
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
//  - otherwise it goes onto the gap (coulomb_on_gap: its own Coulomb condition solved exactly where
//    q = F |B_Tn| / lambda_min(B_TT) < 1, the lagged bound of its old tangential position elsewhere).
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
