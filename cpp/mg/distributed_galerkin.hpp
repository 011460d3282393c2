// One rank's coarse-level kernels of the distributed cycle (python/contactmg/distributed/cycle.py):
// the Galerkin rows P^T (M A M) P of the owned coarse nodes, the level's residual, restriction,
// prolongation and monotone bound restriction. Nodes are local (owned and ghost) in ascending global
// id, so "ascending local index" is "ascending global id" and every sum below is taken in an order
// that does not depend on the partition: each value has the same bits on every number of ranks
// (docs/dev/decisions/0030-distributed-cycle.md). The ghost exchanges stay in Python (mpi4py); these
// are the flat kernels between them.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include "mg/coarsest_solver.hpp"
#include "mg/level_smoothers.hpp"
#include "mg/sweep_order.hpp"

namespace cmg {

// A coarse level's rows on one rank (owned rows complete, ghost rows empty) and their smoother: the
// matrix is held once, written in place by the Galerkin kernel, swept by block or projected
// Gauss-Seidel with the inverted diagonal blocks of level_smoothers.hpp.
template <int d>
struct CoarseRows {
  BlockMatrix<d> A;
  std::vector<double> Dinv;
  std::vector<std::uint8_t> inert;
  std::vector<std::uint8_t> changed;  // per row: its values changed in the last Galerkin pass

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
  // changed scale touches every row: d^3 work a row, small beside a Galerkin pass).
  void invert(double scale) { invert_diagonal<d>(A, Dinv, inert, scale); }

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

// The transfer P onto the local fine nodes (rows; ghost rows are their owners' rows) from the local
// coarse nodes (columns), d x d blocks, and the Galerkin rows it forms on the coarse level:
// Z = (M A M) P on the owned fine rows, Z's ghost rows from their owners (set_ghost_*), then for each
// owned coarse row I the sum over its fine rows i in ascending index of P_iI^T Z_i.
//
// Patterns once, values per rebuild, and only where an input changed: a Z row is recomputed when the
// mask of its row or of a neighbour, its Hessian block or its row of A changed; a coarse row when one
// of its fine Z rows changed. A recomputed row is formed exactly as in a full pass, so the values are
// those of a full rebuild bit for bit (the serial hierarchy's incremental update adds differences
// instead, which rounds otherwise and would tie the bits to the history of truncations).
template <int d>
class DistributedTransfer {
 public:
  DistributedTransfer(BlockMatrix<d> P, std::vector<std::uint8_t> owned_fine, std::vector<std::uint8_t> owned_coarse)
      : P_(std::move(P)), owned_f_(std::move(owned_fine)), owned_c_(std::move(owned_coarse)) {
    if ((Index)owned_f_.size() != P_.rows || (Index)owned_c_.size() != P_.cols)
      throw InputError("the ownership flags must have one entry per fine and per coarse node");
    // P's columns row by row: for coarse node I, its fine rows ascending and the block of each
    tptr_.assign(P_.cols + 1, 0);
    for (Index k = 0; k < P_.nnz(); ++k) tptr_[P_.indices[k] + 1]++;
    for (Index I = 0; I < P_.cols; ++I) tptr_[I + 1] += tptr_[I];
    trow_.resize(P_.nnz());
    tpos_.resize(P_.nnz());
    std::vector<Index> fill(tptr_.begin(), tptr_.end() - 1);
    for (Index i = 0; i < P_.rows; ++i)
      for (Index k = P_.indptr[i]; k < P_.indptr[i + 1]; ++k) {
        const Index q = fill[P_.indices[k]]++;
        trow_[q] = i;
        tpos_[q] = k;
      }
  }

  Index fine_nodes() const { return P_.rows; }
  Index coarse_nodes() const { return P_.cols; }
  const BlockMatrix<d>& matrix() const { return P_; }
  bool has_ghost_pattern() const { return ghost_pattern_done_; }

  // ---- the Galerkin rows -------------------------------------------------------------------------

  // Z's owned rows for the fine matrix A (owned rows complete), the mask per fine dof (nullptr: all
  // ones), Hessian blocks added to the diagonal blocks of `hess_nodes`, and the rows of A
  // whose values changed since the last call (nullptr: none; ignored on the first call).
  void form_owned_z(const BlockMatrix<d>& A, const std::uint8_t* mask, const std::vector<Index>& hess_nodes, const double* hess,
                    const std::uint8_t* a_changed) {
    if (A.rows != P_.rows) throw InputError("the fine matrix and the transfer have different numbers of fine nodes");
    const Index n = P_.rows;
    const bool first = !owned_pattern_done_;
    if (first) owned_pattern(A);
    // which owned rows to recompute
    std::vector<std::uint8_t> dirty(n, first ? 1 : 0);
    std::vector<Index> hess_at(n, -1);
    for (std::size_t m = 0; m < hess_nodes.size(); ++m) {
      if (hess_nodes[m] < 0 || hess_nodes[m] >= n) throw InputError("a Hessian node is outside the level");
      hess_at[hess_nodes[m]] = (Index)m;
    }
    if (!first) {
      std::vector<std::uint8_t> mask_moved(n, 0);
      for (Index i = 0; i < n; ++i)
        for (int c = 0; c < d; ++c)
          if ((mask ? mask[i * d + c] : 1) != mask_[i * d + c]) mask_moved[i] = 1;
      for (Index i = 0; i < n; ++i) {
        if (!owned_f_[i]) continue;
        if (mask_moved[i] || (a_changed && a_changed[i])) { dirty[i] = 1; continue; }
        for (Index k = A.indptr[i]; k < A.indptr[i + 1] && !dirty[i]; ++k)
          if (mask_moved[A.indices[k]]) dirty[i] = 1;
      }
      // a Hessian block that appeared, vanished or changed
      for (std::size_t m = 0; m < hess_nodes_.size(); ++m) {
        const Index i = hess_nodes_[m];
        const Index now = hess_at[i];
        if (now < 0 || std::memcmp(hess + now * d * d, hess_.data() + m * d * d, sizeof(double) * d * d) != 0) dirty[i] = 1;
      }
      std::vector<std::uint8_t> had(n, 0);
      for (Index i : hess_nodes_) had[i] = 1;
      for (Index i : hess_nodes)
        if (!had[i]) dirty[i] = 1;
    }
    mask_.resize(n * d);
    for (Index q = 0; q < n * d; ++q) mask_[q] = mask ? mask[q] : 1;
    hess_nodes_ = hess_nodes;
    hess_.assign(hess, hess + hess_nodes.size() * d * d);

    z_changed_.assign(n, first ? 1 : 0);
    std::vector<double> row;
    std::vector<Index> pos(P_.cols, -1);
    for (Index i = 0; i < n; ++i) {
      if (!owned_f_[i] || !dirty[i]) continue;
      const Index z0 = zptr_[i], z1 = zptr_[i + 1];
      row.assign((z1 - z0) * d * d, 0.0);
      for (Index k = z0; k < z1; ++k) pos[zcol_[k]] = k - z0;
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
        const Index j = A.indices[k];
        // Y = M_i (A_ij + H_i [i == j]) M_j; the mask is 0/1, so these products are exact
        Mat<d> Y = A.block(k);
        if (j == i && hess_at[i] >= 0) Y += CMatMap<d>(hess + hess_at[i] * d * d);
        for (int a = 0; a < d; ++a)
          for (int c = 0; c < d; ++c)
            if (!mask_[i * d + a] || !mask_[j * d + c]) Y(a, c) = 0.0;
        if (Y.isZero(0.0)) continue;
        for (Index b = P_.indptr[j]; b < P_.indptr[j + 1]; ++b) {
          MatMap<d> Zb(row.data() + pos[P_.indices[b]] * d * d);
          multiply_add(Y, P_.block(b), Zb);
        }
      }
      double* stored = zval_.data() + z0 * d * d;
      if (first || std::memcmp(stored, row.data(), sizeof(double) * row.size()) != 0) {
        std::copy(row.begin(), row.end(), stored);
        z_changed_[i] = 1;
      }
    }
  }

  // The owned Z rows of `nodes` (to their ghosts' ranks): (block-row pointer, local coarse column of
  // each block) once, the blocks (k, d, d) per rebuild.
  std::pair<std::vector<Index>, std::vector<Index>> z_pattern(const std::vector<Index>& nodes) const {
    std::vector<Index> ptr{0}, cols;
    for (Index i : nodes) {
      check_node(i, true);
      for (Index k = zptr_[i]; k < zptr_[i + 1]; ++k) cols.push_back(zcol_[k]);
      ptr.push_back((Index)cols.size());
    }
    return {ptr, cols};
  }
  std::vector<double> z_values(const std::vector<Index>& nodes) const {
    std::vector<double> out;
    for (Index i : nodes) {
      check_node(i, true);
      out.insert(out.end(), zval_.begin() + zptr_[i] * d * d, zval_.begin() + zptr_[i + 1] * d * d);
    }
    return out;
  }

  // The patterns of every ghost Z row (nodes: the ghosts, ptr/cols: their blocks' local coarse
  // columns, ascending per row), once, after the first form_owned_z; the coarse pattern follows.
  void set_ghost_pattern(const std::vector<Index>& nodes, const std::vector<Index>& ptr, const std::vector<Index>& cols) {
    if (!owned_pattern_done_) throw InputError("set_ghost_pattern before the owned Z rows are formed");
    if (ghost_pattern_done_) throw InputError("the ghost Z pattern is set once");
    if (ptr.size() != nodes.size() + 1 || ptr.back() != (Index)cols.size()) throw InputError("a ghost Z pattern is malformed");
    const Index n = P_.rows;
    std::vector<Index> count(n, 0), at(n, -1);
    for (Index i = 0; i < n; ++i)
      if (owned_f_[i]) count[i] = zptr_[i + 1] - zptr_[i];
    for (std::size_t m = 0; m < nodes.size(); ++m) {
      check_node(nodes[m], false);
      at[nodes[m]] = (Index)m;
      count[nodes[m]] = ptr[m + 1] - ptr[m];
    }
    std::vector<Index> zptr(n + 1, 0);
    for (Index i = 0; i < n; ++i) zptr[i + 1] = zptr[i] + count[i];
    std::vector<ColIndex> zcol(zptr[n]);
    std::vector<double> zval(zptr[n] * d * d, 0.0);
    for (Index i = 0; i < n; ++i) {
      if (owned_f_[i]) {
        std::copy(zcol_.begin() + zptr_[i], zcol_.begin() + zptr_[i + 1], zcol.begin() + zptr[i]);
        std::copy(zval_.begin() + zptr_[i] * d * d, zval_.begin() + zptr_[i + 1] * d * d, zval.begin() + zptr[i] * d * d);
      } else if (at[i] >= 0) {
        for (Index k = ptr[at[i]]; k < ptr[at[i] + 1]; ++k) {
          if (cols[k] < 0 || cols[k] >= P_.cols || (k > ptr[at[i]] && cols[k] <= cols[k - 1]))
            throw InputError("a ghost Z row's columns must be local coarse nodes, ascending");
          zcol[zptr[i] + k - ptr[at[i]]] = (ColIndex)cols[k];
        }
      }
    }
    zptr_.swap(zptr);
    zcol_.swap(zcol);
    zval_.swap(zval);
    ghost_pattern_done_ = true;
    coarse_pattern();
  }

  // The ghost Z rows' blocks (nodes and their blocks in the order of the pattern); a row whose bits
  // differ from the stored ones is marked changed.
  void set_ghost_values(const std::vector<Index>& nodes, const double* values, Index count) {
    Index q = 0;
    for (Index i : nodes) {
      check_node(i, false);
      const Index len = (zptr_[i + 1] - zptr_[i]) * d * d;
      if (q + len > count) throw InputError("too few ghost Z values for the pattern");
      double* stored = zval_.data() + zptr_[i] * d * d;
      if (std::memcmp(stored, values + q, sizeof(double) * len) != 0) {
        std::copy(values + q, values + q + len, stored);
        z_changed_[i] = 1;
      }
      q += len;
    }
    if (q != count) throw InputError("more ghost Z values than the pattern holds");
  }

  // The owned coarse rows of C = P^T Z (ghost rows empty): row I is the sum over its fine rows i in
  // ascending index of P_iI^T Z_i, recomputed where one of those Z rows changed; C.changed marks the
  // rows whose bits changed.
  void form_coarse(CoarseRows<d>& C) {
    if (!ghost_pattern_done_) throw InputError("form_coarse before the ghost Z pattern is set");
    const Index nc = P_.cols;
    const bool first = C.A.rows != nc || C.A.indptr != cptr_;
    if (first) {
      C.A.rows = C.A.cols = nc;
      C.A.indptr = cptr_;
      C.A.indices = ccol_;
      C.A.values.assign(ccol_.size() * d * d, 0.0);
      C.A.find_diagonal();
    }
    C.changed.assign(nc, first ? 1 : 0);
    std::vector<Index> pos(nc, -1);
    std::vector<double> row;
    for (Index I = 0; I < nc; ++I) {
      if (!owned_c_[I]) continue;
      bool dirty = first;
      for (Index a = tptr_[I]; a < tptr_[I + 1] && !dirty; ++a) dirty = z_changed_[trow_[a]];
      if (!dirty) continue;
      const Index c0 = cptr_[I], c1 = cptr_[I + 1];
      row.assign((c1 - c0) * d * d, 0.0);
      for (Index k = c0; k < c1; ++k) pos[ccol_[k]] = k - c0;
      for (Index a = tptr_[I]; a < tptr_[I + 1]; ++a) {
        const Index i = trow_[a];
        const Mat<d> PT = P_.block(tpos_[a]).transpose();
        if (PT.isZero(0.0)) continue;
        for (Index k = zptr_[i]; k < zptr_[i + 1]; ++k) {
          MatMap<d> Cb(row.data() + pos[zcol_[k]] * d * d);
          multiply_add(PT, CMatMap<d>(zval_.data() + k * d * d), Cb);
        }
      }
      double* stored = C.A.values.data() + c0 * d * d;
      if (first || std::memcmp(stored, row.data(), sizeof(double) * row.size()) != 0) {
        std::copy(row.begin(), row.end(), stored);
        C.changed[I] = 1;
      }
    }
  }

  // ---- the transfers of the cycle -----------------------------------------------------------------

  // bc_I = sum_i P_iI^T (m_i r_i) over the fine rows i of I ascending, on the owned coarse rows (zero
  // elsewhere); mask per fine dof or nullptr.
  void restrict_residual(const double* r, const std::uint8_t* mask, double* bc) const {
    for (Index I = 0; I < P_.cols; ++I) {
      double* out = bc + d * I;
      std::fill(out, out + d, 0.0);
      if (!owned_c_[I]) continue;
      for (Index a = tptr_[I]; a < tptr_[I + 1]; ++a) {
        const Index i = trow_[a];
        const double* B = P_.values.data() + tpos_[a] * d * d;  // row-major P_iI: entry (c, e) at c * d + e
        double ri[d];
        for (int c = 0; c < d; ++c) ri[c] = mask && !mask[i * d + c] ? 0.0 : r[i * d + c];
        for (int e = 0; e < d; ++e) {
          double t = B[e] * ri[0];
          for (int c = 1; c < d; ++c) t += B[c * d + e] * ri[c];
          out[e] += t;
        }
      }
    }
  }

  // xf_i (+)= m_i sum_J P_iJ xc_J on every local fine row (ghost rows are their owners' rows, so no
  // exchange follows); add: into xf, else overwrite; mask per fine dof or nullptr.
  void prolong(const double* xc, const std::uint8_t* mask, double* xf, bool add) const {
    for (Index i = 0; i < P_.rows; ++i) {
      double t[d] = {};
      accumulate_blocks<d, false>(P_.values.data(), P_.indices.data(), P_.indptr[i], P_.indptr[i + 1], xc, t);
      for (int c = 0; c < d; ++c) {
        const double v = mask && !mask[i * d + c] ? 0.0 : t[c];
        xf[i * d + c] = add ? xf[i * d + c] + v : v;
      }
    }
  }

  // Monotone restriction (mg/bound_restriction.hpp) of the fine bounds lo <= c <= hi of the rows
  // flagged in `rows` (nullptr: all), less x where x is given, components with mask 0 skipped: a
  // coarse correction within lo_c, hi_c keeps every fine dof within its own. Minima and maxima: exact,
  // so the order does not matter; sigma sums a row's |w| in ascending coarse dof.
  void restrict_bounds(const double* lo, const double* hi, const double* x, const std::uint8_t* mask, const std::uint8_t* rows,
                       double* lo_c, double* hi_c) const {
    std::fill(lo_c, lo_c + d * P_.cols, -kInf);
    std::fill(hi_c, hi_c + d * P_.cols, kInf);
    for (Index i = 0; i < P_.rows; ++i) {
      if (rows && !rows[i]) continue;
      for (int c = 0; c < d; ++c) {
        double l = lo[i * d + c], h = hi[i * d + c];
        if ((mask && !mask[i * d + c]) || (l == -kInf && h == kInf)) continue;
        if (x) { l -= x[i * d + c]; h -= x[i * d + c]; }
        double sigma = 0;
        for (Index k = P_.indptr[i]; k < P_.indptr[i + 1]; ++k)
          for (int a = 0; a < d; ++a) sigma += std::abs(P_.values[k * d * d + c * d + a]);
        const double scale = 1.0 / std::max(1.0, sigma);
        const double ls = l * scale, hs = h * scale;
        for (Index k = P_.indptr[i]; k < P_.indptr[i + 1]; ++k)
          for (int a = 0; a < d; ++a) {
            const double w = P_.values[k * d * d + c * d + a];
            if (w == 0) continue;
            const Index g = P_.indices[k] * d + a;
            if (w > 0) { hi_c[g] = std::min(hi_c[g], hs); lo_c[g] = std::max(lo_c[g], ls); }
            else { hi_c[g] = std::min(hi_c[g], -ls); lo_c[g] = std::max(lo_c[g], -hs); }
          }
      }
    }
  }

  std::size_t bytes() const {
    return P_.indptr.size() * sizeof(Index) + P_.indices.size() * sizeof(ColIndex) + P_.values.size() * sizeof(double) +
           P_.diag.size() * sizeof(Index) + (tptr_.size() + trow_.size() + tpos_.size()) * sizeof(Index) +
           zptr_.size() * sizeof(Index) + zcol_.size() * sizeof(ColIndex) + zval_.size() * sizeof(double) + z_changed_.size() +
           (cptr_.size()) * sizeof(Index) + ccol_.size() * sizeof(ColIndex) + mask_.size() + hess_nodes_.size() * sizeof(Index) +
           hess_.size() * sizeof(double) + owned_f_.size() + owned_c_.size();
  }

 private:
  // Y += X B, the products of each entry summed over the inner index in ascending order (fixed code,
  // so the same bits on every rank).
  template <class MX, class MB, class MY>
  static void multiply_add(const MX& X, const MB& B, MY& Y) {
    for (int a = 0; a < d; ++a)
      for (int c = 0; c < d; ++c) {
        double t = X(a, 0) * B(0, c);
        for (int e = 1; e < d; ++e) t += X(a, e) * B(e, c);
        Y(a, c) += t;
      }
  }

  void check_node(Index i, bool owned) const {
    if (i < 0 || i >= P_.rows || (bool)owned_f_[i] != owned)
      throw InputError(std::string("node ") + std::to_string(i) + " is not an " + (owned ? "owned" : "ghost") + " fine node");
  }

  // The blocks of Z's owned rows: the coarse columns reached through A's row (pattern, not values,
  // so the truncation never changes it); ghost rows empty until set_ghost_pattern.
  void owned_pattern(const BlockMatrix<d>& A) {
    const Index n = P_.rows;
    zptr_.assign(n + 1, 0);
    zcol_.clear();
    std::vector<Index> marker(P_.cols, -1);
    std::vector<ColIndex> row;
    for (Index i = 0; i < n; ++i) {
      row.clear();
      if (owned_f_[i])
        for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k)
          for (Index b = P_.indptr[A.indices[k]]; b < P_.indptr[A.indices[k] + 1]; ++b) {
            const Index J = P_.indices[b];
            if (marker[J] != i) { marker[J] = i; row.push_back((ColIndex)J); }
          }
      std::sort(row.begin(), row.end());
      zcol_.insert(zcol_.end(), row.begin(), row.end());
      zptr_[i + 1] = (Index)zcol_.size();
    }
    zval_.assign(zcol_.size() * d * d, 0.0);
    mask_.assign(n * d, 1);
    owned_pattern_done_ = true;
  }

  // The blocks of the owned coarse rows: the columns of the Z rows of their fine rows, and a
  // diagonal slot (a row every fine row of which is truncated stays, inert).
  void coarse_pattern() {
    const Index nc = P_.cols;
    cptr_.assign(nc + 1, 0);
    ccol_.clear();
    std::vector<Index> marker(nc, -1);
    std::vector<ColIndex> row;
    for (Index I = 0; I < nc; ++I) {
      row.clear();
      if (owned_c_[I]) {
        for (Index a = tptr_[I]; a < tptr_[I + 1]; ++a) {
          const Index i = trow_[a];
          for (Index k = zptr_[i]; k < zptr_[i + 1]; ++k)
            if (marker[zcol_[k]] != I) { marker[zcol_[k]] = I; row.push_back(zcol_[k]); }
        }
        if (marker[I] != I) row.push_back((ColIndex)I);
      }
      std::sort(row.begin(), row.end());
      ccol_.insert(ccol_.end(), row.begin(), row.end());
      cptr_[I + 1] = (Index)ccol_.size();
    }
  }

  BlockMatrix<d> P_;
  std::vector<std::uint8_t> owned_f_, owned_c_;
  std::vector<Index> tptr_, trow_, tpos_;        // P's columns: fine rows ascending per coarse node
  std::vector<Index> zptr_;                      // Z = (M A M) P on every local fine row
  std::vector<ColIndex> zcol_;
  std::vector<double> zval_;
  std::vector<std::uint8_t> z_changed_;
  std::vector<Index> cptr_;                      // the pattern of the owned coarse rows
  std::vector<ColIndex> ccol_;
  std::vector<std::uint8_t> mask_;               // the inputs of the last pass (what a later pass compares)
  std::vector<Index> hess_nodes_;
  std::vector<double> hess_;
  bool owned_pattern_done_ = false, ghost_pattern_done_ = false;
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

}  // namespace cmg
