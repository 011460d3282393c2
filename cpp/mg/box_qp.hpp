// The exact minimizer of E(x) = 1/2 x^T A x - b^T x over a box lo <= x <= hi, for a symmetric
// positive semi-definite A: a primal active-set Newton method (projected Newton, Bertsekas 1982).
//
// Why: the coarsest level of a body that only its contacts hold is (nearly) semi-definite, and
// projected Gauss-Seidel contracts on it at the rate of its smallest eigenvalue: 50 sweeps left
// most of the rigid motion undone, and the cycles of the finest level took it up instead (a lone
// block falling onto its floor, 1,122 dofs: 63 cycles). Newton steps on the free dofs move the
// body as a whole and find the contact set in a few steps.
//
// Each step: the gradient g = A x - b; the free dofs are those not at a bound that g pushes them
// against (nor inert: a zero diagonal); the Newton step p solves A_FF p = -g_F (A_FF shifted by
// 1e-10 of its diagonal where it is only semi-definite: along a free motion p is then long, and
// the projection stops it at the first bound); x <- clamp(x + t p) with t the first of 1, 1/2, ...
// that lowers E. So E never rises, and the method stops at a point where the projected gradient
// vanishes to round-off (the box QP's optimality conditions), or after max_steps.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include "base/block_matrix.hpp"
#include "mg/coarsest_solver.hpp"

namespace cmg {

// Minimizes E over the box from the feasible x (n = A.rows * d entries, in place); returns the
// Newton steps taken. Serial and in a fixed order: the same bits on any thread count.
template <int d>
int minimize_box_qp(const BlockMatrix<d>& A, const double* b, const double* lo, const double* hi, double* x,
                    int max_steps, double rtol) {
  using SpMat = Eigen::SparseMatrix<double>;
  const Index n = A.rows * d;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve((std::size_t)A.nnz() * d * d);
  for (Index i = 0; i < A.rows; ++i)
    for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k)
      for (int a = 0; a < d; ++a)
        for (int c = 0; c < d; ++c)
          if (const double v = A.block(k)(a, c); v != 0) t.emplace_back(i * d + a, (Index)A.indices[k] * d + c, v);
  SpMat S(n, n);
  S.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd diag = S.diagonal();
  Eigen::Map<Eigen::VectorXd> xv(x, n);
  Eigen::Map<const Eigen::VectorXd> bv(b, n);
  Eigen::VectorXd g(n), y(n), p(n);
  std::vector<Index> where(n);
  int steps = 0;
  for (; steps < max_steps; ++steps) {
    g = S * xv - bv;
    // optimality: x is its own projected (diagonally scaled) gradient step
    double kkt = 0, scale = 0;
    std::vector<Index> free;
    for (Index k = 0; k < n; ++k) {
      scale = std::max(scale, std::abs(x[k]));
      where[k] = -1;
      if (!(diag[k] > 0)) continue;
      kkt = std::max(kkt, std::abs(std::clamp(x[k] - g[k] / diag[k], lo[k], hi[k]) - x[k]));
      const bool held = (x[k] <= lo[k] && g[k] >= 0) || (x[k] >= hi[k] && g[k] <= 0);
      where[k] = held ? -1 : (Index)free.size();
      if (!held) free.push_back(k);
    }
    if (kkt <= rtol * scale || free.empty()) break;
    const Index m = (Index)free.size();
    std::vector<Eigen::Triplet<double>> tf;
    Eigen::VectorXd rhs(m), dfree(m);
    for (Index j = 0; j < m; ++j) {
      const Index k = free[j];
      rhs[j] = -g[k];
      dfree[j] = diag[k];
      for (SpMat::InnerIterator it(S, k); it; ++it)
        if (const Index r = where[it.row()]; r >= 0) tf.emplace_back(r, j, it.value());
    }
    SpMat F(m, m);
    F.setFromTriplets(tf.begin(), tf.end());
    Eigen::SimplicialLDLT<SpMat> f(F);
    if (!ldlt_pivots_ok(f, dfree)) {
      for (Index j = 0; j < m; ++j) F.coeffRef(j, j) *= 1 + 1e-10;
      f.compute(F);
      if (f.info() != Eigen::Success) break;
    }
    const Eigen::VectorXd pf = f.solve(rhs);
    if (!pf.allFinite()) break;
    p.setZero();
    for (Index j = 0; j < m; ++j) p[free[j]] = pf[j];
    // the first of t = 1, 1/2, ... whose projected point lowers the energy
    bool lowered = false;
    for (double step = 1.0; step > 1e-12 && !lowered; step *= 0.5) {
      for (Index k = 0; k < n; ++k) y[k] = std::clamp(x[k] + step * p[k], lo[k], hi[k]);
      const Eigen::VectorXd dx = y - xv;
      const double de = g.dot(dx) + 0.5 * dx.dot(S * dx);
      lowered = de < 0;
    }
    if (!lowered) break;
    xv = y;
  }
  return steps;
}

}  // namespace cmg
