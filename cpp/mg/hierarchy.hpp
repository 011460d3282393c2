// The Galerkin hierarchy of (truncated monotone) multigrid: coarse matrices from the fine matrix
// and the prolongations, A_{l} = P_l^T A_{l+1} P_l, truncated on the fine level by a mask, plus
// the Hessian blocks of the coarse problem on the fine diagonal (3D sliding nodes); kept current
// by incremental updates, and the factorized coarsest matrix.
#pragma once
#include <chrono>
#include <tuple>
#include <unordered_map>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include "mg/coarsest_solver.hpp"
#include "mg/galerkin.hpp"
#include "mg/level_smoothers.hpp"
#include "mg/line_smoother.hpp"

namespace cmg {

template <int d>
class GalerkinHierarchy {
 public:
  struct Level {
    BlockMatrix<d> A;
    std::vector<double> Dinv;
    std::vector<std::uint8_t> inert;
    double scale = 0;  // largest diagonal entry at the last full rebuild
    // line Gauss-Seidel of the level: lines found at the first build, from the untruncated
    // Galerkin matrix; factored on first use after the matrix changed (a monotone cycle, which
    // keeps point sweeps, never pays for it), with the non-inert dofs active
    mutable LineGaussSeidel<d> lines;
    mutable std::vector<std::uint8_t> active;
    mutable bool lines_stale = true;
    const LineGaussSeidel<d>& factored_lines() const {
      if (lines_stale) {
        active.resize(inert.size());
        for (std::size_t k = 0; k < inert.size(); ++k) active[k] = !inert[k];
        lines.factor(A, active.data());
        lines_stale = false;
      }
      return lines;
    }
  };

  // P[l] prolongs level l to level l+1; P.back() ends on the fine level.
  explicit GalerkinHierarchy(std::vector<Prolongation<d>> P) : P_(std::move(P)) {
    const int nc = (int)P_.size();
    lv_.resize(nc);
    gp_.resize(nc);
    delta_.resize(nc);
    slot_.resize(nc);
  }

  int num_coarse_levels() const { return (int)lv_.size(); }
  const Level& level(int l) const { return lv_[l]; }
  const BlockMatrix<d>& matrix(int l) const { return lv_[l].A; }
  const Prolongation<d>& prolongation(int l) const { return P_[l]; }
  // x = A_0^{-1} b on the coarsest level (inert dofs: x = b). Not const inside: a solve whose
  // low-rank correction is not accurate enough factorizes the coarsest matrix anew
  // (mg/coarsest_solver.hpp), which changes how, not what, is solved.
  void solve_coarsest(const double* b, double* x) const {
    coarsest_.solve(b, x, [&](Eigen::SparseMatrix<double>& S, Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& f) {
      return factorize(S, f);
    });
  }
  int coarsest_factorizations() const { return coarsest_.factorizations(); }
  // whether the coarsest matrix was only semi-definite (shifted by 1e-10 diag to factorize it): a
  // body its contacts hold, with motions no truncated coarse function resists yet
  bool coarsest_shifted() const { return coarsest_.shifted(); }
  int rebuilds() const { return rebuilds_; }
  // incremental updates since the last full rebuild (0: the levels are the Galerkin products of
  // the mask and Hessian they were built for, bit for bit)
  int incremental_updates() const { return incremental_; }
  double rebuild_seconds() const { return rebuild_seconds_; }
  std::size_t memory_bytes() const {
    std::size_t s = 0;
    for (auto& L : lv_) s += L.A.memory_bytes() + sizeof(double) * L.Dinv.size() + L.lines.memory_bytes() + L.inert.size();
    for (auto& P : P_) s += P.memory_bytes();
    return s + coarsest_.memory_bytes();
  }

  // A term added to the top coarse level's matrix alone and not restricted to the levels below (the
  // Petrov-Galerkin coupling of steps/petrov_galerkin_coupling.hpp): blocks (I, J, M) of that level.
  // The rows it touches get the inverse of their new, non-symmetric diagonal block; their sweeps
  // read rows only, so nothing else changes. Refused (false, nothing changed) where a block lies
  // outside the Galerkin pattern, a touched diagonal block is singular or a touched diagonal entry
  // is not positive (the projected sweep's component solve divides by it). Replaces an overlay in
  // place; undone bit for bit by clear_top_overlay(), which update() and rebuild() call first (an
  // incremental update applies differences to the values and inverts the diagonals it touches as
  // symmetric blocks).
  bool set_top_overlay(const std::vector<std::tuple<Index, Index, Mat<d>>>& blocks) {
    clear_top_overlay();
    if (lv_.size() < 2) return false;  // the top level is the coarsest: solved by a symmetric factorization
    Level& L = lv_.back();
    std::unordered_map<Index, Mat<d>> add;
    for (const auto& [I, J, M] : blocks) {
      const Index pos = L.A.find(I, J);
      if (pos < 0) return false;
      auto [it, fresh] = add.try_emplace(pos, M);
      if (!fresh) it->second += M;
    }
    std::vector<Index> rows;
    for (const auto& [I, J, M] : blocks) rows.push_back(I);
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    std::vector<Mat<d>> inv(rows.size());
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const Index i = rows[r], k = L.A.diag[i];
      Mat<d> D = L.A.block(k);
      if (auto it = add.find(k); it != add.end()) D += it->second;
      for (int c = 0; c < d; ++c) {
        if (L.inert[i * d + c]) { D.row(c).setZero(); D.col(c).setZero(); D(c, c) = 1; }
        if (!(D(c, c) > 0)) return false;
      }
      const Eigen::FullPivLU<Mat<d>> lu(D);
      if (lu.rank() < d) return false;
      inv[r] = lu.inverse();
    }
    for (auto& [pos, M] : add) {
      overlay_.blocks.emplace_back(pos, Mat<d>(L.A.block(pos)));
      L.A.block(pos) += M;
    }
    for (std::size_t r = 0; r < rows.size(); ++r) {
      MatMap<d> Di(L.Dinv.data() + rows[r] * d * d);
      overlay_.dinv.emplace_back(rows[r], Mat<d>(Di));
      Di = inv[r];
    }
    factor_lines((int)lv_.size() - 1);
    overlay_.on = true;
    return true;
  }
  void clear_top_overlay() {
    if (!overlay_.on) return;
    Level& L = lv_.back();
    for (const auto& [pos, M] : overlay_.blocks) L.A.block(pos) = M;
    for (const auto& [i, M] : overlay_.dinv) MatMap<d>(L.Dinv.data() + i * d * d) = M;
    overlay_ = Overlay();
    factor_lines((int)lv_.size() - 1);
  }
  bool has_top_overlay() const { return overlay_.on; }

  // Galerkin products for the fine mask, then the fine Hessian blocks (node -> block) on top.
  void rebuild(const BlockMatrix<d>& A_fine, const std::uint8_t* mask,
               const std::vector<std::pair<Index, Mat<d>>>& hessian = {}) {
    clear_top_overlay();
    const int nc = (int)lv_.size();
    if (nc == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    for (int l = nc - 1; l >= 0; --l) {
      const BlockMatrix<d>& Af = (l == nc - 1) ? A_fine : lv_[l + 1].A;
      gp_[l].build(Af, P_[l], l == nc - 1 ? mask : nullptr, lv_[l].A);
      lv_[l].scale = max_diagonal<d>(lv_[l].A);
      invert_diagonal<d>(lv_[l].A, lv_[l].Dinv, lv_[l].inert, lv_[l].scale);
      if (!lines_found_) lv_[l].lines = LineGaussSeidel<d>(find_lines<d>(lv_[l].A));
    }
    lines_found_ = true;
    if (!hessian.empty()) {
      for (const auto& [i, H] : hessian) add_fine_diagonal(i, H, mask);
      apply_deltas();
    }
    for (int l = 0; l < nc; ++l) factor_lines(l);
    factorize_coarsest(false);
    ++rebuilds_;
    incremental_ = 0;
    rebuild_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  // The same after the fine mask changed on a few dofs and/or the fine Hessian blocks changed, at
  // a cost proportional to the change: with Delta = T_new - T_old, C_new - C_old = X(T_new) +
  // X(T_old)^T, X(T) = P^T Delta A T P; a Hessian block H_i adds P~_i^T H_i P~_i; each coarser
  // level changes by P^T (change of the level above) P. A full rebuild every kFullRebuildEvery
  // updates keeps round-off from accumulating. old_hessian/new_hessian: the blocks before and
  // after (with the old and the new mask).
  void update(const BlockMatrix<d>& A, const std::uint8_t* old_mask, const std::uint8_t* new_mask,
              const std::vector<std::pair<Index, Mat<d>>>& old_hessian = {},
              const std::vector<std::pair<Index, Mat<d>>>& new_hessian = {}) {
    clear_top_overlay();
    const int nc = (int)lv_.size();
    if (nc == 0) return;
    if (incremental_ >= kFullRebuildEvery) { rebuild(A, new_mask, new_hessian); return; }
    const auto t0 = std::chrono::steady_clock::now();
    const int top = nc - 1;
    const Prolongation<d>& P = P_[top];
    for (const auto& [i, H] : old_hessian) add_fine_diagonal(i, -H, old_mask);
    for (Index i = 0; i < A.rows; ++i)
      for (int a = 0; a < d; ++a) {
        const Index k = i * d + a;
        if (old_mask[k] == new_mask[k]) continue;
        const double delta = new_mask[k] ? 1.0 : -1.0;
        for (Index b = P.indptr[i]; b < P.indptr[i + 1]; ++b) {
          const Vec<d> p = delta * P.block(i, b).row(a).transpose();
          if (p.isZero(0.0)) continue;
          const Index I = P.indices[b];
          for (Index q = A.indptr[i]; q < A.indptr[i + 1]; ++q) {
            const Index j = A.indices[q];
            Eigen::Matrix<double, 1, d> vn = A.block(q).row(a), vo = vn;
            for (int c = 0; c < d; ++c) { vn[c] *= new_mask[j * d + c]; vo[c] *= old_mask[j * d + c]; }
            for (Index b2 = P.indptr[j]; b2 < P.indptr[j + 1]; ++b2) {
              const Index J = P.indices[b2];
              const Mat<d> Pj = P.block(j, b2);
              add_delta(top, I, J, p * (vn * Pj));
              add_delta(top, J, I, (p * (vo * Pj)).transpose());
            }
          }
        }
      }
    for (const auto& [i, H] : new_hessian) add_fine_diagonal(i, H, new_mask);
    apply_deltas();
    factorize_coarsest(true);
    ++rebuilds_;
    ++incremental_;
    rebuild_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

 private:
  struct DeltaEntry {
    Index pos, i, j;
    Mat<d> M;
  };
  static constexpr int kFullRebuildEvery = 64;
  // the top level's values and inverted diagonal blocks before set_top_overlay
  struct Overlay {
    bool on = false;
    std::vector<std::pair<Index, Mat<d>>> blocks, dinv;  // (position, block) and (row, inverse)
  };
  Overlay overlay_;

  void add_delta(int l, Index I, Index J, const Mat<d>& M) {
    const Index pos = lv_[l].A.find(I, J);
    const auto [it, fresh] = slot_[l].try_emplace(pos, (std::int32_t)delta_[l].size());
    if (fresh) delta_[l].push_back({pos, I, J, M});
    else delta_[l][it->second].M += M;
  }

  // top coarse level += P~_i^T H P~_i for a block H on the diagonal of fine node i
  void add_fine_diagonal(Index i, const Mat<d>& H, const std::uint8_t* mask) {
    const int top = (int)lv_.size() - 1;
    const Prolongation<d>& P = P_[top];
    Mat<d> Hm = H;
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) Hm(a, b) *= (mask ? mask[i * d + a] * mask[i * d + b] : 1);
    if (Hm.isZero(0.0)) return;
    for (Index b1 = P.indptr[i]; b1 < P.indptr[i + 1]; ++b1)
      for (Index b2 = P.indptr[i]; b2 < P.indptr[i + 1]; ++b2)
        add_delta(top, P.indices[b1], P.indices[b2], P.block(i, b1).transpose() * Hm * P.block(i, b2));
  }

  // Applies the pending changes level by level, each propagated to the next coarser level first.
  void apply_deltas() {
    for (int l = (int)lv_.size() - 1; l >= 0; --l) {
      Level& L = lv_[l];
      if (l > 0) {  // propagate before applying: the entries of delta_[l] are what changed on level l
        const Prolongation<d>& Pl = P_[l - 1];
        for (const auto& e : delta_[l])
          for (Index b = Pl.indptr[e.i]; b < Pl.indptr[e.i + 1]; ++b)
            for (Index b2 = Pl.indptr[e.j]; b2 < Pl.indptr[e.j + 1]; ++b2)
              add_delta(l - 1, Pl.indices[b], Pl.indices[b2], Pl.block(e.i, b).transpose() * e.M * Pl.block(e.j, b2));
      }
      for (const auto& e : delta_[l]) L.A.block(e.pos) += e.M;
      slot_[l].clear();
      for (const auto& e : delta_[l]) invert_diagonal<d>(L.A, L.Dinv, L.inert, L.scale, e.i, e.i + 1);
      if (!delta_[l].empty()) factor_lines(l);
      delta_[l].clear();
    }
  }

  // the level's line factorization is out of date (refactored on its next use: O(rows))
  void factor_lines(int l) { lv_[l].lines_stale = true; }

  // The coarsest matrix with the inert dofs' rows and columns dropped and identity on their
  // diagonal, to the coarsest solver: after an incremental update (update) as a low-rank
  // correction of the kept factorization where the change allows it, else factorized anew.
  void factorize_coarsest(bool update) {
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
    coarsest_.set(std::move(S), update, [&](Eigen::SparseMatrix<double>& M, Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& f) {
      return factorize(M, f);
    });
  }

  // Factorizes S into f; 1, or 2 when S had to be shifted (S then holds the shifted matrix).
  static int factorize(Eigen::SparseMatrix<double>& S, Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& f) {
    const Index n = S.rows();
    // The pattern changes with the truncation (inert dofs, entries that cancel to zero): analysing
    // it once and refactorizing a different pattern wrote out of bounds (tilted obstacles). The
    // coarsest matrix is small, so it is analysed every time.
    f.compute(S);
    const Eigen::VectorXd diag = S.diagonal();
    if (ldlt_pivots_ok(f, diag)) return 1;
    // Truncation through rotated fine frames can make coarse dofs linearly dependent: the Galerkin
    // matrix is then only semi-definite, with a right-hand side P~^T r in its range. Solving with
    // A + eps diag(A) still lowers the energy (J(x) = -x^T A x / 2 - eps x^T D x <= 0).
    for (Index k = 0; k < n; ++k) S.coeffRef(k, k) *= 1 + 1e-10;
    f.compute(S);
    if (!ldlt_pivots_ok(f, diag))
      throw InputError("the coarsest-level matrix is singular: is rigid-body motion left free by the Dirichlet conditions?");
    return 2;
  }

  std::vector<Prolongation<d>> P_;
  std::vector<Level> lv_;
  std::vector<GalerkinProduct<d>> gp_;
  std::vector<std::vector<DeltaEntry>> delta_;  // pending incremental change of each level's A
  // position in A -> its entry of delta_: a map of the few touched blocks (a vector over every
  // coarse block was 5 bytes a dof at level 9, docs/dev/decisions/0011-memory-release.md)
  std::vector<std::unordered_map<Index, std::int32_t>> slot_;
  mutable CoarsestSolver coarsest_;
  int rebuilds_ = 0, incremental_ = 0;
  bool lines_found_ = false;
  double rebuild_seconds_ = 0;
};

}  // namespace cmg
