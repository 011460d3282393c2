// One rank's coarse levels of the distributed cycle (python/contactmg/distributed/cycle.py): a
// level's rows and their smoother, and the coarsest level gathered onto every rank and factorized.
// Every sum runs in ascending local index, an order that does not depend on the partition
// (mg/distributed_galerkin.hpp says why): each value has the same bits on every number of ranks.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include "mg/bounded_coarsest.hpp"
#include "mg/coarsest_solver.hpp"
#include "mg/level_smoothers.hpp"
#include "mg/sweep_order.hpp"

namespace cmg {

// Whether B is w I, its diagonal entries bitwise equal (a transfer's plain row)
template <int d>
bool is_scaled_identity(const Mat<d>& B) {
  for (int a = 0; a < d; ++a)
    for (int c = 0; c < d; ++c)
      if (a == c ? std::memcmp(&B(a, a), &B(0, 0), sizeof(double)) != 0 : B(a, c) != 0.0) return false;
  return true;
}

// Y += X B (d x d), the products of each entry summed over the inner index in ascending order
// (fixed code, so the same bits on every rank)
template <int d, class MX, class MB, class MY>
void multiply_add(const MX& X, const MB& B, MY& Y) {
  for (int a = 0; a < d; ++a)
    for (int c = 0; c < d; ++c) {
      double t = X(a, 0) * B(0, c);
      for (int e = 1; e < d; ++e) t += X(a, e) * B(e, c);
      Y(a, c) += t;
    }
}

// A coarse level's rows on one rank (owned rows complete, ghost rows empty) and their smoother: the
// matrix is held once, written in place by the Galerkin kernel, swept by block or projected
// Gauss-Seidel with the inverted diagonal blocks of level_smoothers.hpp.
template <int d>
struct CoarseRows {
  BlockMatrix<d> A;
  std::vector<double> Dinv;
  std::vector<std::uint8_t> inert;
  std::vector<std::uint8_t> changed;  // per row: its values changed in the last Galerkin pass
  double inverted_scale = -1;         // the scale of the inverses held (-1: none)

  Index n() const { return A.rows; }

  // The largest diagonal entry of the rows flagged in `owned` (the caller takes the maximum over the ranks).
  double max_diagonal(const std::uint8_t* owned) const {
    double m = 0.0;
    for (Index i = 0; i < A.rows; ++i)
      if (owned[i] && A.diag[i] >= 0)
        for (int c = 0; c < d; ++c) m = std::max(m, A.block(A.diag[i])(c, c));
    return m;
  }

  // The diagonal inverses for a level-wide `scale` (the inert threshold is relative to it, so a
  // changed scale touches every row); with the scale of the inverses held, only the rows the last
  // Galerkin pass changed (a row's inverse reads only its own diagonal block: the same bits).
  void invert(double scale) {
    const bool all = scale != inverted_scale || Dinv.size() != (std::size_t)(A.rows * d * d) || changed.size() != (std::size_t)A.rows;
    if (all) invert_diagonal<d>(A, Dinv, inert, scale);
    else
      for (Index i = 0; i < A.rows; ++i)
        if (changed[i]) invert_diagonal<d>(A, Dinv, inert, scale, i, i + 1);
    inverted_scale = scale;
  }

  // r_i = b_i - sum_k A_ik x_k on the rows flagged in `owned` (blocks in ascending column), zero elsewhere.
  void residual(const double* x, const double* b, const std::uint8_t* owned, double* r) const {
    for (Index i = 0; i < A.rows; ++i) {
      double* ri = r + d * i;
      if (!owned[i]) { std::fill(ri, ri + d, 0.0); continue; }
      for (int c = 0; c < d; ++c) ri[c] = b[d * i + c];
      accumulate_blocks<d, true>(A.values.data(), A.indices.data(), A.indptr[i], A.indptr[i + 1], x, ri);
    }
  }

  std::size_t bytes() const {
    return A.indptr.size() * sizeof(Index) + A.indices.size() * sizeof(ColIndex) + A.values.size() * sizeof(double) +
           A.diag.size() * sizeof(Index) + Dinv.size() * sizeof(double) + inert.size() + changed.size();
  }
};

// The coarsest level gathered onto every rank (the same matrix everywhere), factorized by the
// core's sparse LDL^T and kept current across rebuilds by the serial solver's low-rank correction
// (mg/coarsest_solver.hpp). SuperLU took 60 ms a factorization on the half ball's coarsest level
// (2,286 dofs), most of a rebuild once the Galerkin rows were in C++. Every step here is serial and
// in a fixed order, and every rank sees the same sequence of matrices: the solutions have the same
// bits on every rank (they depend on that sequence, as the serial solver's do). The factorization
// rule is the serial GalerkinHierarchy::factorize's (mg/hierarchy.hpp): each pivot against its own
// row's diagonal entry, and a matrix that truncation through rotated frames leaves semi-definite is
// shifted by 1e-10 diag.
class GatheredCoarsestFactor {
 public:
  using SpMat = Eigen::SparseMatrix<double>;
  using LDLT = Eigen::SimplicialLDLT<SpMat>;

  // S: scalar CSR (n x n, symmetric to round-off), the rows and columns of the inert dofs (per dof,
  // nonzero: inert) replaced by identity rows, as the serial hierarchy does. may_update: a low-rank
  // correction of the kept factorization is allowed (false: factorize).
  void set(Index n, const Index* indptr, const Index* indices, const double* values, const std::uint8_t* inert, bool may_update) {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(indptr[n] + n);
    for (Index i = 0; i < n; ++i) {
      if (inert[i]) { t.emplace_back(i, i, 1.0); continue; }
      for (Index k = indptr[i]; k < indptr[i + 1]; ++k) {
        const Index j = indices[k];
        if (j < 0 || j >= n) throw InputError("a coarsest-level column is out of range");
        if (values[k] != 0 && !inert[j]) t.emplace_back(i, j, values[k]);
      }
    }
    SpMat S(n, n);
    S.setFromTriplets(t.begin(), t.end());
    n_ = n;
    solver_.set(std::move(S), may_update, [&](SpMat& M, LDLT& f) { return factorize(M, f); });
  }

  Index n() const { return n_; }
  bool shifted() const { return shifted_; }
  int factorizations() const { return solver_.factorizations(); }

  void solve(const double* b, double* x) {
    solver_.solve(b, x, [&](SpMat& M, LDLT& f) { return factorize(M, f); });
  }

  // the kept matrices and low-rank columns, and the factor (a value and a row index an entry)
  std::size_t bytes() const { return solver_.memory_bytes() + factor_entries_ * (sizeof(double) + sizeof(int)) + n_ * 3 * sizeof(double); }

 private:
  int factorize(SpMat& S, LDLT& f) {
    const Eigen::VectorXd diag = S.diagonal();
    f.compute(S);  // its lower triangle
    shifted_ = false;
    if (!ldlt_pivots_ok(f, diag)) {
      for (Index k = 0; k < S.rows(); ++k) S.coeffRef(k, k) *= 1 + 1e-10;
      f.compute(S);
      shifted_ = true;
      if (!ldlt_pivots_ok(f, diag)) throw InputError("the coarsest-level matrix is singular: is rigid-body motion left free by the Dirichlet conditions?");
    }
    factor_entries_ = (std::size_t)f.matrixL().nestedExpression().nonZeros();
    return shifted_ ? 2 : 1;
  }

  CoarsestSolver solver_;
  Index n_ = 0;
  std::size_t factor_entries_ = 0;
  bool shifted_ = false;
};

// The gathered coarsest level's bounded correction (the same on every rank): the serial cycle's
// (mg/bounded_coarsest.hpp), its sweeps projected Gauss-Seidel over every row in global order with
// the inverted diagonal blocks of level_smoothers.hpp. `scale` (the largest diagonal entry of the
// level) sets the inert-dof threshold.
template <int d>
struct GatheredCoarsestSmoother {
  BlockMatrix<d> A;
  std::vector<double> Dinv, work;
  std::vector<std::uint8_t> inert;

  GatheredCoarsestSmoother(const BlockMatrix<d>& M, double scale) : A(M) { invert_diagonal<d>(A, Dinv, inert, scale); }

  // x: the exact solution in, the bounded correction out; a row is bounded where a bound of it is finite.
  void bound(double* x, const double* b, const double* lo, const double* hi, double omega, bool shifted) {
    const Index n = A.rows;
    std::vector<std::uint8_t> bounded(n, 0);
    for (Index q = 0; q < n * d; ++q)
      if (std::isfinite(lo[q]) || std::isfinite(hi[q])) bounded[q / d] = 1;
    work.resize(n * d);
    const SweepOrder all;
    bound_coarsest_solution<d>(A, b, lo, hi, x, work.data(), shifted, [&](bool forward) {
      projected_gs_sweep<d>(A, Dinv, bounded, inert, lo, hi, b, x, forward, all, omega);
    });
  }
};

}  // namespace cmg
