// The multilevel coarse correction of (truncated monotone) multigrid: Galerkin coarse matrices
// from the fine matrix and the (truncated) prolongations, projected Gauss-Seidel on each coarse
// level within bounds restricted monotonically from the fine level, an exact coarsest solve.
// Without bounds this is the coarse part of a plain linear V/W/F-cycle.
#pragma once
#include <chrono>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include "smoothers.hpp"
#include "transfer.hpp"

namespace cmg {

enum class CycleType : int { V = 0, W = 1, F = 2 };

struct CycleOptions {
  CycleType cycle = CycleType::V;
  int nu1 = 3, nu2 = 3;
  // Projected Gauss-Seidel sweeps on the coarsest level when its exact solve violates the bounds.
  // Each sweep lowers the energy, so any number keeps the cycle monotone; on the Hertz benchmark
  // (triangles levels 3-7, quads 3-6, F = 0.4 and 5) 10, 50, 200 and 2000 gave the same cycle
  // counts, and 2000 (run to a relative change of 1e-14) cost 84 % of a quad level-3 solve.
  int coarsest_max_sweeps = 50;
};

template <int d>
class CoarseCorrection {
 public:
  // P[l] prolongs level l to level l+1; P.back() ends on the fine level.
  CoarseCorrection(std::vector<BlockMatrix<d>> P, CycleOptions opt) : P_(std::move(P)), opt_(opt) {
    const int nc = (int)P_.size();
    lv_.resize(nc);
    gp_.resize(nc);
    for (int l = 0; l < nc; ++l) {
      const Index n = P_[l].cols;
      Level& L = lv_[l];
      L.x.assign(n * d, 0); L.b.assign(n * d, 0); L.r.assign(n * d, 0);
      L.lo.assign(n * d, -kInf); L.hi.assign(n * d, kInf); L.bounded.assign(n, 0);
    }
  }

  int num_coarse_levels() const { return (int)lv_.size(); }
  const BlockMatrix<d>& matrix(int l) const { return lv_[l].A; }
  const BlockMatrix<d>& prolongation(int l) const { return P_[l]; }
  std::size_t memory_bytes() const {
    std::size_t s = 0;
    for (auto& L : lv_) s += L.A.memory_bytes() + sizeof(double) * (L.Dinv.size() + 5 * L.x.size());
    for (auto& P : P_) s += 2 * P.memory_bytes();
    return s;
  }

  // Galerkin products A_{l} = P~^T A_{l+1} P~, truncation mask on the fine level only.
  void rebuild(const BlockMatrix<d>& A_fine, const std::uint8_t* mask) {
    const int nc = (int)lv_.size();
    if (nc == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    for (int l = nc - 1; l >= 0; --l) {
      const BlockMatrix<d>& Af = (l == nc - 1) ? A_fine : lv_[l + 1].A;
      gp_[l].build(Af, P_[l], l == nc - 1 ? mask : nullptr, lv_[l].A);
      lv_[l].scale = max_diagonal<d>(lv_[l].A);
      invert_diagonal<d>(lv_[l].A, lv_[l].Dinv, lv_[l].inert, lv_[l].scale);
      if (lv_[l].slot.size() != lv_[l].A.indices.size()) lv_[l].slot.assign(lv_[l].A.indices.size(), -1);
    }
    factorize_coarsest();
    ++rebuilds_;
    incremental_ = 0;
    rebuild_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  int rebuilds() const { return rebuilds_; }

  // The same after the fine mask changed on a few dofs, at a cost proportional to the change:
  // with Delta = T_new - T_old,  C_new - C_old = X(T_new) + X(T_old)^T,  X(T) = P^T Delta A T P,
  // and each coarser level changes by P^T (change of the level above) P. A full rebuild every
  // kFullRebuildEvery updates keeps round-off from accumulating.
  void update(const BlockMatrix<d>& A, const std::uint8_t* old_mask, const std::uint8_t* new_mask) {
    const int nc = (int)lv_.size();
    if (nc == 0) return;
    if (incremental_ >= kFullRebuildEvery) { rebuild(A, new_mask); return; }
    const auto t0 = std::chrono::steady_clock::now();
    const int top = nc - 1;
    const BlockMatrix<d>& P = P_[top];
    Level& C = lv_[top];
    for (Index i = 0; i < A.rows; ++i)
      for (int a = 0; a < d; ++a) {
        const Index k = i * d + a;
        if (old_mask[k] == new_mask[k]) continue;
        const double delta = new_mask[k] ? 1.0 : -1.0;
        for (Index b = P.indptr[i]; b < P.indptr[i + 1]; ++b) {
          const Vec<d> p = delta * P.block(b).row(a).transpose();
          if (p.isZero(0.0)) continue;
          const Index I = P.indices[b];
          for (Index q = A.indptr[i]; q < A.indptr[i + 1]; ++q) {
            const Index j = A.indices[q];
            Eigen::Matrix<double, 1, d> vn = A.block(q).row(a), vo = vn;
            for (int c = 0; c < d; ++c) { vn[c] *= new_mask[j * d + c]; vo[c] *= old_mask[j * d + c]; }
            for (Index b2 = P.indptr[j]; b2 < P.indptr[j + 1]; ++b2) {
              const Index J = P.indices[b2];
              add_delta(C, I, J, p * (vn * P.block(b2)));
              add_delta(C, J, I, (p * (vo * P.block(b2))).transpose());
            }
          }
        }
      }
    for (int l = top; l >= 0; --l) {
      Level& L = lv_[l];
      if (l > 0) {  // propagate before applying: the entries of L.delta are what changed on level l
        Level& Cc = lv_[l - 1];
        const BlockMatrix<d>& Pl = P_[l - 1];
        for (const auto& e : L.delta)
          for (Index b = Pl.indptr[e.i]; b < Pl.indptr[e.i + 1]; ++b)
            for (Index b2 = Pl.indptr[e.j]; b2 < Pl.indptr[e.j + 1]; ++b2)
              add_delta(Cc, Pl.indices[b], Pl.indices[b2], Pl.block(b).transpose() * e.M * Pl.block(b2));
      }
      for (const auto& e : L.delta) {
        L.A.block(e.pos) += e.M;
        L.slot[e.pos] = -1;
      }
      for (const auto& e : L.delta) invert_diagonal<d>(L.A, L.Dinv, L.inert, L.scale, e.i, e.i + 1);
      L.delta.clear();
    }
    factorize_coarsest();
    ++rebuilds_;
    ++incremental_;
    rebuild_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  double rebuild_seconds() const { return rebuild_seconds_; }

  // u_fine += P~ c, with c the multilevel correction for the fine residual r and the fine
  // correction bounds [lo, hi] (ignored when !bounded).
  void apply(const double* r_fine, const std::uint8_t* mask, const double* lo_f, const double* hi_f, bool bounded,
             double* u_fine) {
    if (lv_.empty()) return;  // a single level: the smoother alone
    const int top = (int)lv_.size() - 1;
    const BlockMatrix<d>& P = P_[top];
    Level& C = lv_[top];
    restrict_residual<d>(P, mask, r_fine, C.b.data());
    if (bounded) restrict_bounds<d>(P, mask, lo_f, hi_f, C.lo.data(), C.hi.data());
    set_bounded(C, bounded);
    std::fill(C.x.begin(), C.x.end(), 0.0);
    cycle(top, opt_.cycle);
    prolongate_add<d>(P, mask, C.x.data(), u_fine);
  }

 private:
  struct DeltaEntry {
    Index pos, i, j;
    Mat<d> M;
  };
  struct Level {
    BlockMatrix<d> A;
    std::vector<double> Dinv, x, b, r, lo, hi;
    std::vector<std::uint8_t> bounded, inert;
    bool any_bounds = false;
    double scale = 0;                // largest diagonal entry at the last full rebuild
    std::vector<DeltaEntry> delta;   // pending incremental change of A
    std::vector<Index> slot;         // position in A -> entry of delta, or -1
  };
  static constexpr int kFullRebuildEvery = 64;

  static void add_delta(Level& L, Index I, Index J, const Mat<d>& M) {
    const Index pos = L.A.find(I, J);
    Index& s = L.slot[pos];
    if (s < 0) {
      s = (Index)L.delta.size();
      L.delta.push_back({pos, I, J, M});
    } else {
      L.delta[s].M += M;
    }
  }

  static void set_bounded(Level& L, bool bounded) {
    L.any_bounds = false;
    const Index n = (Index)L.bounded.size();
    for (Index i = 0; i < n; ++i) {
      bool b = false;
      if (bounded)
        for (int c = 0; c < d; ++c) b = b || L.lo[i * d + c] > -kInf || L.hi[i * d + c] < kInf;
      L.bounded[i] = b;
      L.any_bounds = L.any_bounds || b;
    }
  }

  void sweep(Level& L, bool forward) {
    if (L.any_bounds)
      projected_gs_sweep<d>(L.A, L.Dinv, L.bounded, L.inert, L.lo.data(), L.hi.data(), L.b.data(), L.x.data(), forward);
    else
      block_gs_sweep<d>(L.A, L.Dinv, L.b.data(), L.x.data(), forward);
  }

  void cycle(int l, CycleType type) {
    Level& L = lv_[l];
    if (l == 0) { solve_coarsest(); return; }
    for (int s = 0; s < opt_.nu1; ++s) sweep(L, true);
    const int visits = type == CycleType::V ? 1 : 2;
    Level& C = lv_[l - 1];
    const BlockMatrix<d>& P = P_[l - 1];
    for (int v = 0; v < visits; ++v) {
      L.A.multiply(L.x.data(), L.r.data());
      for (std::size_t k = 0; k < L.r.size(); ++k) L.r[k] = L.b[k] - L.r[k];
      restrict_residual<d>(P, nullptr, L.r.data(), C.b.data());
      if (L.any_bounds) {
        // the coarser level gets the slack that remains on this one
        std::vector<double>& slo = scratch_lo_, &shi = scratch_hi_;
        slo.resize(L.x.size()); shi.resize(L.x.size());
        for (std::size_t k = 0; k < L.x.size(); ++k) { slo[k] = L.lo[k] - L.x[k]; shi[k] = L.hi[k] - L.x[k]; }
        restrict_bounds<d>(P, nullptr, slo.data(), shi.data(), C.lo.data(), C.hi.data());
      }
      set_bounded(C, L.any_bounds);
      std::fill(C.x.begin(), C.x.end(), 0.0);
      cycle(l - 1, (type == CycleType::F && v == 1) ? CycleType::V : type);
      prolongate_add<d>(P, nullptr, C.x.data(), L.x.data());
    }
    for (int s = 0; s < opt_.nu2; ++s) sweep(L, false);
  }

  void factorize_coarsest() {
    const BlockMatrix<d>& A = lv_[0].A;
    const Index n = A.rows * d;
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(A.values.size());
    for (Index i = 0; i < A.rows; ++i)
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k)
        for (int a = 0; a < d; ++a)
          for (int b = 0; b < d; ++b) {
            const double v = A.block(k)(a, b);
            if (v != 0 && !lv_[0].inert[i * d + a] && !lv_[0].inert[A.indices[k] * d + b]) t.emplace_back(i * d + a, A.indices[k] * d + b, v);
          }
    // empty rows (truncated or unused dofs) become identity rows: their right-hand side is zero
    for (Index k = 0; k < n; ++k)
      if (lv_[0].inert[k]) t.emplace_back(k, k, 1.0);
    Eigen::SparseMatrix<double> S(n, n);
    S.setFromTriplets(t.begin(), t.end());
    // The pattern changes with the truncation (inert dofs, entries that cancel to zero): analysing
    // it once and refactorizing a different pattern wrote out of bounds (tilted obstacles). The
    // coarsest matrix is small, so it is analysed every time.
    ldlt_.compute(S);
    if (!factorization_ok()) {
      // Truncation through rotated fine frames can make coarse dofs linearly dependent: the Galerkin
      // matrix is then only semi-definite, with a right-hand side P~^T r in its range. Solving with
      // A + eps diag(A) still lowers the energy (J(x) = -x^T A x / 2 - eps x^T D x <= 0).
      for (Index k = 0; k < n; ++k) S.coeffRef(k, k) *= 1 + 1e-10;
      ldlt_.compute(S);
      if (!factorization_ok())
        throw InputError("the coarsest-level matrix is singular: is rigid-body motion left free by the Dirichlet conditions?");
    }
  }

  bool factorization_ok() const {
    if (ldlt_.info() != Eigen::Success) return false;
    const auto D = ldlt_.vectorD();
    return D.minCoeff() > 1e-13 * D.cwiseAbs().maxCoeff();
  }

  void solve_coarsest() {
    Level& L = lv_[0];
    const Index n = (Index)L.x.size();
    Eigen::Map<Eigen::VectorXd> x(L.x.data(), n);
    Eigen::Map<const Eigen::VectorXd> b(L.b.data(), n);
    x = ldlt_.solve(b);
    if (!L.any_bounds) return;
    bool inside = true;
    for (Index k = 0; k < n; ++k) inside = inside && x[k] >= L.lo[k] && x[k] <= L.hi[k];
    if (inside) return;
    // Start projected Gauss-Seidel from the clamped solution only if that beats x = 0 in energy,
    // so that the coarse correction never raises the energy.
    for (Index k = 0; k < n; ++k) x[k] = std::max(L.lo[k], std::min(x[k], L.hi[k]));
    L.A.multiply(L.x.data(), L.r.data());
    double e = 0;
    for (Index k = 0; k < n; ++k) e += 0.5 * x[k] * L.r[k] - b[k] * x[k];
    if (!(e < 0)) x.setZero();
    double scale = 0;
    for (int s = 0; s < opt_.coarsest_max_sweeps; ++s) {
      L.r = L.x;
      sweep(L, s % 2 == 0);
      double change = 0;
      scale = 0;
      for (Index k = 0; k < n; ++k) {
        change = std::max(change, std::abs(L.x[k] - L.r[k]));
        scale = std::max(scale, std::abs(L.x[k]));
      }
      if (change <= 1e-14 * scale) break;
    }
  }

  std::vector<BlockMatrix<d>> P_;
  CycleOptions opt_;
  std::vector<Level> lv_;
  std::vector<GalerkinProduct<d>> gp_;
  std::vector<double> scratch_lo_, scratch_hi_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  int rebuilds_ = 0, incremental_ = 0;
  double rebuild_seconds_ = 0;
};

}  // namespace cmg
