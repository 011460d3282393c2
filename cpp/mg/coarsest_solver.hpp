// Exact solves with the coarsest-level matrix, kept current across incremental coarse updates by a
// low-rank correction of one kept factorization instead of a new factorization per update.
//
// Why: on the 3D sphere (tetrahedra, level 3, F = 0.4) the friction Hessian of the
// sliding nodes changes in every cycle, so the coarse levels are updated in every cycle; the
// update itself is cheap (proportional to the change), but the coarsest matrix (2,286 dofs) was
// analysed and factorized again each time: ~40 ms, a third of an Algorithm-2 cycle and most of
// its cost above a linear cycle.
//
// What: S0 is the matrix of the last factorization. An update changes S only on a few rows K
// (the coarse dofs under the nodes whose truncation or Hessian changed), so S = S0 + E M E^T with
// E the columns of the identity at K and M = (S - S0)[K, K]. Then (Woodbury)
//   S^{-1} b = y - Z (I + M Z_K)^{-1} M y_K,   y = S0^{-1} b,   Z = S0^{-1} E,
// with Z_K, y_K the rows K. The columns of Z are kept per dof while S0 lives (the changed rows of
// consecutive updates are mostly the same), so an update costs the new columns and a |K| x |K|
// LU. S0 is factorized anew when K grows past kMaxRank, when the capacitance I + M Z_K is
// ill-conditioned, when a solve's componentwise backward error is not at round-off level after
// one step of iterative refinement, and on every full
// rebuild of the hierarchy. The solutions equal those of a new factorization to round-off (not
// bit for bit); everything here is serial and its order fixed, so they do not depend on the
// thread count (no Eigen matrix-matrix product, which may run on OpenMP threads).
#pragma once
#include <cmath>
#include <unordered_map>
#include <vector>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include "base/common.hpp"
#include "base/parallel.hpp"

namespace cmg {

// Each pivot against its own row's diagonal entry, not against the largest pivot: the friction
// Hessian s (I - t t^T)/|u_T| of a node that has just begun to slide (a load step's tiny slip
// increment) put entries of 1e12 on the coarsest diagonal next to entries of 1e2 (largest pivot
// 4e17, smallest 11.5), and that positive definite matrix was refused as singular (the 8-layer
// cork's load path, step 2).
inline bool ldlt_pivots_ok(const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& f, const Eigen::VectorXd& diag) {
  if (f.info() != Eigen::Success) return false;
  const auto D = f.vectorD();
  const auto& to = f.permutationP().indices();  // row i of S is row to[i] of the factor
  for (Index i = 0; i < (Index)diag.size(); ++i)
    if (!(D[to[i]] > 1e-13 * diag[i])) return false;
  return true;
}

class CoarsestSolver {
 public:
  using SpMat = Eigen::SparseMatrix<double>;
  // Above this many changed rows a new factorization is cheaper than the columns of Z (each one a
  // solve with S0: at 2,286 dofs a solve is ~1 % of a factorization).
  static constexpr Index kMaxRank = 96;

  // The matrix S to solve with from now on (symmetric, compressed). may_update: a low-rank
  // correction of the kept factorization is allowed (incremental coarse updates); false forces a
  // new one. factor(S, ldlt) factorizes S into ldlt and returns 1, or 2 when it had to shift S
  // (semi-definite: it then holds the shifted matrix; no low-rank corrections of that), or throws.
  template <class Factor>
  void set(SpMat S, bool may_update, Factor&& factor) {
    S.makeCompressed();
    S_ = std::move(S);
    if (may_update && have_factor_ && !shifted_ && low_rank_update()) return;
    refactor(factor);
  }

  // x = S^{-1} b (n entries each)
  template <class Factor>
  void solve(const double* b, double* x, Factor&& factor) {
    const Index n = S_.rows();
    Eigen::Map<const Eigen::VectorXd> bv(b, n);
    Eigen::Map<Eigen::VectorXd> xv(x, n);
    if (K_.empty()) { xv = ldlt_.solve(bv); return; }
    woodbury_solve(bv, xv);
    // The correction cancels large terms when M is large against S0 (a node that has just begun
    // to slide: friction Hessian entries of 1e12 beside 1e2, see factorization_ok). Accept the
    // result at round-off level componentwise backward error, row by row (a norm-wise test is
    // dominated by those rows and passed errors of 1e-2 in the others: the cork's load path took
    // other cycle counts), after one step of iterative refinement if need be; else factorize S.
    if (accurate(bv, xv)) return;
    const Eigen::VectorXd r = bv - S_ * Eigen::VectorXd(xv);
    Eigen::VectorXd dx(S_.rows());
    Eigen::Map<const Eigen::VectorXd> rv(r.data(), r.size());
    Eigen::Map<Eigen::VectorXd> dv(dx.data(), dx.size());
    woodbury_solve(rv, dv);
    xv += dx;
    if (accurate(bv, xv)) return;
    refactor(factor);
    xv = ldlt_.solve(bv);
  }

  // whether the factorization in use is of the shifted matrix (S only semi-definite)
  bool shifted() const { return shifted_; }
  int factorizations() const { return factorizations_; }
  Index rank() const { return (Index)K_.size(); }
  std::size_t memory_bytes() const {
    return sizeof(double) * (Z_.size() + S0_.nonZeros() + S_.nonZeros()) + sizeof(int) * (S0_.nonZeros() + S_.nonZeros());
  }

 private:
  template <class Factor>
  void refactor(Factor&& factor) {
    shifted_ = factor(S_, ldlt_) == 2;
    S0_ = S_;
    K_.clear();
    zcol_.clear();
    Z_.resize(S_.rows(), 0);
    have_factor_ = true;
    ++factorizations_;
  }

  // K, M and the capacitance for S - S0; false when a new factorization is needed.
  bool low_rank_update() {
    // below 4 kMaxRank rows a factorization costs about what the columns of Z cost (the 2D
    // coarsest levels: 56 dofs): those keep the plain factorization, and their bits
    if (S_.rows() != S0_.rows() || S_.rows() < 4 * kMaxRank) return false;
    const SpMat D = S_ - S0_;
    // K: the rows and the columns of D's entries. The Galerkin products and their incremental
    // updates round the two triangles differently (S is symmetric only to round-off), so D may
    // have an entry (r, c) in a column c whose row is zero; with K the rows alone, M_(pos[r], -1)
    // wrote before M_'s storage: heap corruption, whose effect depended on the addresses (run-to-run
    // different second solves on the 3D sphere, now and then a crash).
    std::vector<Index> rows;
    std::vector<char> in(S_.rows(), 0);
    for (Index j = 0; j < D.outerSize(); ++j)
      for (SpMat::InnerIterator it(D, j); it; ++it)
        if (it.value() != 0)
          for (const Index r : {(Index)it.row(), (Index)it.col()})
            if (!in[r]) { in[r] = 1; rows.push_back(r); }
    if ((Index)rows.size() > kMaxRank) return false;
    std::sort(rows.begin(), rows.end());
    K_ = rows;
    if (K_.empty()) return true;  // S == S0: plain solves
    const Index k = (Index)K_.size(), n = S_.rows();
    // columns of Z for the dofs of K not seen since S0 was factorized
    Index missing = 0;
    for (Index r : K_) missing += !zcol_.count(r);
    if (Z_.cols() + missing > 2 * kMaxRank) { K_.clear(); return false; }  // bounds the memory of Z
    if (missing) {
      const Index old = Z_.cols();
      Z_.conservativeResize(n, old + missing);
      Index c = old;
      Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
      for (Index r : K_) {
        if (zcol_.count(r)) continue;
        e[r] = 1;
        Z_.col(c) = ldlt_.solve(e);
        e[r] = 0;
        zcol_[r] = c++;
      }
    }
    std::vector<Index> pos(n, -1);
    for (Index a = 0; a < k; ++a) pos[K_[a]] = a;
    M_.setZero(k, k);
    for (Index j = 0; j < D.outerSize(); ++j)
      for (SpMat::InnerIterator it(D, j); it; ++it)
        if (it.value() != 0) M_(pos[it.row()], pos[it.col()]) = it.value();
    // C = I + M Z_K, by explicit loops in a fixed order (see the header)
    Eigen::MatrixXd C = Eigen::MatrixXd::Identity(k, k);
    for (Index b = 0; b < k; ++b) {
      const Index zc = zcol_.at(K_[b]);
      for (Index a = 0; a < k; ++a) {
        double s = 0;
        for (Index q = 0; q < k; ++q) s += M_(a, q) * Z_(K_[q], zc);
        C(a, b) += s;
      }
    }
    {
      const ThreadScope one(1);  // Eigen's blocked LU may run its products on OpenMP threads
      cap_.compute(C);
    }
    if (!(cap_.rcond() > 1e-10)) { K_.clear(); return false; }
    return true;
  }

  void woodbury_solve(const Eigen::Map<const Eigen::VectorXd>& b, Eigen::Map<Eigen::VectorXd>& x) const {
    const Index k = (Index)K_.size(), n = S_.rows();
    x = ldlt_.solve(b);
    Eigen::VectorXd t(k);
    for (Index a = 0; a < k; ++a) {
      double s = 0;
      for (Index q = 0; q < k; ++q) s += M_(a, q) * x[K_[q]];
      t[a] = s;
    }
    const Eigen::VectorXd w = cap_.solve(t);
    for (Index a = 0; a < k; ++a) {
      const double* z = Z_.data() + zcol_.at(K_[a]) * n;
      const double wa = w[a];
      for (Index i = 0; i < n; ++i) x[i] -= z[i] * wa;
    }
  }

  // componentwise backward error max_i |b - S x|_i / (|S| |x| + |b|)_i at round-off level
  bool accurate(const Eigen::Map<const Eigen::VectorXd>& b, const Eigen::Map<Eigen::VectorXd>& x) const {
    if (!x.allFinite()) return false;
    const Index n = S_.rows();
    Eigen::VectorXd r = b, scale = b.cwiseAbs();
    for (Index j = 0; j < n; ++j)  // column-major: column j scatters x_j
      for (SpMat::InnerIterator it(S_, j); it; ++it) {
        r[it.row()] -= it.value() * x[j];
        scale[it.row()] += std::abs(it.value() * x[j]);
      }
    for (Index i = 0; i < n; ++i)
      if (std::abs(r[i]) > kBackwardError * scale[i]) return false;
    return true;
  }

  static constexpr double kBackwardError = 1e-12;

  SpMat S_, S0_;
  Eigen::SimplicialLDLT<SpMat> ldlt_;
  std::vector<Index> K_;
  std::unordered_map<Index, Index> zcol_;
  Eigen::MatrixXd Z_, M_;
  Eigen::PartialPivLU<Eigen::MatrixXd> cap_;
  bool have_factor_ = false, shifted_ = false;
  int factorizations_ = 0;
};

}  // namespace cmg
