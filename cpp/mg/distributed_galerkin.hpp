// One rank's coarse-level kernels of the distributed cycle (python/contactmg/distributed/cycle.py):
// the Galerkin rows P^T (M A M) P of the owned coarse nodes, the level's residual, restriction,
// prolongation and monotone bound restriction. Nodes are local (owned and ghost) in an order that is
// the same global order on every rank (ascending (colour, global id), python/contactmg/distributed/
// hierarchy.py), so every sum below, taken in ascending local index, runs in an order that does not
// depend on the partition: each value has the same bits on every number of ranks
// (docs/dev/decisions/0030-distributed-cycle.md). The ghost exchanges stay in Python (mpi4py); these
// are the flat kernels between them.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include "mg/distributed_levels.hpp"

namespace cmg {


// The transfer P onto the local fine nodes (rows; ghost rows are their owners' rows) from the local
// coarse nodes (columns), and the Galerkin rows it forms on the coarse level: for each owned coarse
// row I, the sum over its fine rows i in ascending index of P_iI^T Z_i with Z_i = ((M A M) P)_i. An
// owned fine row's Z_i is formed where it is needed, from the fine matrix; a ghost row's comes from
// its owner (set_ghost_*) and is the only Z row held, so the Galerkin kernel holds a halo's worth of
// blocks, not a second fine matrix (docs/dev/decisions/0030-distributed-cycle.md).
//
// P is held as the serial Prolongation holds it: a weight per entry where a row's blocks are w I
// (every row of uniform refinement), full d x d blocks only on the other rows (contact frames). A
// kernel reads a plain entry as w I: the same bits as the full block up to the sign of a zero.
//
// A rebuild forms a coarse row again only when one of its fine rows' inputs changed (the mask of the
// row or of a neighbour, its Hessian block, its row of A, or a ghost Z row's bits); a row formed
// again is formed exactly as in a full pass, so the values are those of a full rebuild bit for bit
// (the serial hierarchy's incremental update adds differences instead, which rounds otherwise and
// would tie the bits to the history of truncations).
template <int d>
class DistributedTransfer {
 public:
  DistributedTransfer(const BlockMatrix<d>& P, std::vector<std::uint8_t> owned_fine, std::vector<std::uint8_t> owned_coarse)
      : rows_(P.rows), cols_(P.cols), ptr_(P.indptr), col_(P.indices), owned_f_(std::move(owned_fine)), owned_c_(std::move(owned_coarse)) {
    if ((Index)owned_f_.size() != rows_ || (Index)owned_c_.size() != cols_)
      throw InputError("the ownership flags must have one entry per fine and per coarse node");
    w_.assign(P.nnz(), 0.0);
    for (Index i = 0; i < rows_; ++i) {
      bool plain = true;
      for (Index k = ptr_[i]; k < ptr_[i + 1] && plain; ++k) plain = is_scaled_identity<d>(P.block(k));
      if (plain) {
        for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k) w_[k] = P.block(k)(0, 0);
        continue;
      }
      if (full_at_.empty()) full_at_.assign(rows_, -1);
      if (full_.size() / (d * d) >= (std::size_t)std::numeric_limits<std::int32_t>::max())
        throw InputError("a transfer has too many full blocks");
      full_at_[i] = (std::int32_t)(full_.size() / (d * d));
      for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k) full_.insert(full_.end(), P.values.begin() + k * d * d, P.values.begin() + (k + 1) * d * d);
    }
    z_changed_.assign(rows_, 1);
  }

  Index fine_nodes() const { return rows_; }
  Index coarse_nodes() const { return cols_; }
  bool has_ghost_pattern() const { return ghost_pattern_done_; }

  // ---- the Galerkin rows -------------------------------------------------------------------------

  // The inputs of the next Galerkin rows: the fine matrix A (owned rows complete), the mask per fine
  // dof (nullptr: all ones), Hessian blocks added to the diagonal blocks of `hess_nodes`, and the rows
  // of A whose values changed since the last call (nullptr: none; ignored on the first call). Marks
  // the owned fine rows whose Z row these inputs change.
  void set_fine(const BlockMatrix<d>& A, const std::uint8_t* mask, const std::vector<Index>& hess_nodes, const double* hess,
                const std::uint8_t* a_changed) {
    check_fine(A);
    const Index n = rows_;
    const bool first = !inputs_set_;
    std::vector<std::int32_t> hess_at(hess_nodes.empty() ? 0 : n, -1);  // empty: no Hessian block
    for (std::size_t m = 0; m < hess_nodes.size(); ++m) {
      if (hess_nodes[m] < 0 || hess_nodes[m] >= n) throw InputError("a Hessian node is outside the level");
      if (hess_at[hess_nodes[m]] >= 0) throw InputError("a Hessian node is given twice");
      hess_at[hess_nodes[m]] = (std::int32_t)m;
    }
    for (Index i = 0; i < n; ++i)
      if (owned_f_[i]) z_changed_[i] = first;
    if (!first) {
      std::vector<std::uint8_t> mask_moved(n, 0);
      for (Index i = 0; i < n; ++i)
        for (int c = 0; c < d; ++c)
          if ((mask ? mask[i * d + c] : 1) != mask_[i * d + c]) mask_moved[i] = 1;
      for (Index i = 0; i < n; ++i) {
        if (!owned_f_[i]) continue;
        if (mask_moved[i] || (a_changed && a_changed[i])) { z_changed_[i] = 1; continue; }
        for (Index k = A.indptr[i]; k < A.indptr[i + 1] && !z_changed_[i]; ++k)
          if (mask_moved[A.indices[k]]) z_changed_[i] = 1;
      }
      // a Hessian block that appeared, vanished or changed
      for (std::size_t m = 0; m < hess_nodes_.size(); ++m) {
        const Index i = hess_nodes_[m];
        const Index now = hess_at.empty() ? -1 : hess_at[i];
        if (now < 0 || std::memcmp(hess + now * d * d, hess_.data() + m * d * d, sizeof(double) * d * d) != 0) z_changed_[i] = 1;
      }
      std::vector<std::uint8_t> had(n, 0);
      for (Index i : hess_nodes_) had[i] = 1;
      for (Index i : hess_nodes)
        if (!had[i]) z_changed_[i] = 1;
    }
    mask_.resize(n * d);
    for (Index q = 0; q < n * d; ++q) mask_[q] = mask ? mask[q] : 1;
    hess_nodes_ = hess_nodes;
    hess_.assign(hess, hess + hess_nodes.size() * d * d);
    hess_at_.swap(hess_at);
    inputs_set_ = true;
  }

  // The owned Z rows of `nodes` (to their ghosts' ranks): (block-row pointer, local coarse column of
  // each block) once, the blocks (k, d, d) per rebuild, for the A of the last set_fine.
  std::pair<std::vector<Index>, std::vector<Index>> z_pattern(const BlockMatrix<d>& A, const std::vector<Index>& nodes) const {
    check_fine(A);
    std::vector<Index> ptr{0}, cols;
    std::vector<ColIndex> row;
    std::vector<Index> slot(cols_, -1);
    for (Index i : nodes) {
      check_node(i, true);
      z_columns(A, i, row, slot);
      cols.insert(cols.end(), row.begin(), row.end());
      ptr.push_back((Index)cols.size());
    }
    return {ptr, cols};
  }
  std::vector<double> z_values(const BlockMatrix<d>& A, const std::vector<Index>& nodes) const {
    check_fine(A);
    if (!inputs_set_) throw InputError("z_values before set_fine");
    std::vector<double> out, vals;
    std::vector<ColIndex> row;
    std::vector<Index> slot(cols_, -1);
    for (Index i : nodes) {
      check_node(i, true);
      z_row(A, i, row, vals, slot);
      out.insert(out.end(), vals.begin(), vals.end());
    }
    return out;
  }

  // The patterns of the ghost Z rows as their owners sent them (nodes: ghosts, ptr/cols: their
  // blocks' local coarse columns, ascending per row, -1 for a coarse node this rank does not hold),
  // once. A row reaching a coarse node not held is left out: no owned coarse row sums it. (If an owned
  // coarse node J has P_iJ != 0, every column K of Z_i shares a coarse cell with J: the fine cell of i
  // and a neighbour j lies in one coarse cell, whose vertices are J (the smallest face holding i has J)
  // and K (P_jK != 0), so K is held. A ghost at the edge of the layer may have such a row; it is sent
  // because the halo sends every ghost its owner's values.)
  void set_ghost_pattern(const std::vector<Index>& nodes, const std::vector<Index>& ptr, const std::vector<Index>& cols) {
    if (ghost_pattern_done_) throw InputError("the ghost Z pattern is set once");
    if (ptr.size() != nodes.size() + 1 || ptr.front() != 0 || ptr.back() != (Index)cols.size()) throw InputError("a ghost Z pattern is malformed");
    ghost_at_.assign(nodes.empty() ? 0 : rows_, -1);  // empty: no ghost row
    gptr_.assign(1, 0);
    gcol_.clear();
    given_.clear();
    for (std::size_t m = 0; m < nodes.size(); ++m) {
      check_node(nodes[m], false);
      if (ghost_at_[nodes[m]] >= 0) throw InputError("a ghost Z row is given twice");
      bool held = true;
      for (Index k = ptr[m]; k < ptr[m + 1]; ++k) {
        if (cols[k] < -1 || cols[k] >= cols_ || (k > ptr[m] && cols[k] >= 0 && cols[k] <= cols[k - 1]))
          throw InputError("a ghost Z row's columns must be local coarse nodes (or -1), ascending");
        held = held && cols[k] >= 0;
      }
      given_.push_back({nodes[m], ptr[m + 1] - ptr[m], held});
      if (!held) continue;
      ghost_at_[nodes[m]] = (std::int32_t)(gptr_.size() - 1);
      for (Index k = ptr[m]; k < ptr[m + 1]; ++k) gcol_.push_back((ColIndex)cols[k]);
      gptr_.push_back((Index)gcol_.size());
    }
    gval_.assign(gcol_.size() * d * d, 0.0);
    ghost_pattern_done_ = true;
  }

  // The ghost Z rows' blocks, every row of the pattern in its order (the rows left out skipped); a
  // row whose bits differ from the held ones is marked changed.
  void set_ghost_values(const double* values, Index count) {
    if (!ghost_pattern_done_) throw InputError("set_ghost_values before set_ghost_pattern");
    Index q = 0;
    for (const Given& r : given_) {
      const Index len = r.blocks * d * d;
      if (q + len > count) throw InputError("too few ghost Z values for the pattern");
      if (r.held) {
        double* stored = gval_.data() + gptr_[ghost_at_[r.node]] * d * d;
        if (std::memcmp(stored, values + q, sizeof(double) * len) != 0) {
          std::copy(values + q, values + q + len, stored);
          z_changed_[r.node] = 1;
        }
      }
      q += len;
    }
    if (q != count) throw InputError("more ghost Z values than the pattern holds");
  }

  // The owned coarse rows of C = P^T Z into C (ghost rows empty), A the fine matrix of the last
  // set_fine: row I is the sum over its fine rows i in ascending index of P_iI^T Z_i, formed again
  // where one of those Z rows changed; C.changed marks the rows whose bits changed. The first call
  // sets C's pattern: the columns of the Z rows of I's fine rows, and a diagonal slot (a row every
  // fine row of which is truncated stays, inert). visit: the order the rows are formed in (nullptr:
  // ascending; each row is formed alone, so the order changes no bit): in ascending global id the
  // rows formed one after the other share fine rows, and their Z rows are read from the cache.
  void form_coarse(const BlockMatrix<d>& A, CoarseRows<d>& C, const Index* visit = nullptr) {
    check_fine(A);
    if (!inputs_set_) throw InputError("form_coarse before set_fine");
    if (!ghost_pattern_done_) throw InputError("form_coarse before the ghost Z pattern is set");
    const Index nc = cols_;
    // P's columns: for coarse node I, its fine rows ascending and the entry of each (formed per call,
    // as the serial GalerkinProduct forms P's transposed pattern: one pass over P)
    std::vector<Index> tptr(nc + 1, 0), trow(nnz()), tpos(nnz());
    for (Index k = 0; k < nnz(); ++k) tptr[col_[k] + 1]++;
    for (Index I = 0; I < nc; ++I) tptr[I + 1] += tptr[I];
    {
      std::vector<Index> fill(tptr.begin(), tptr.end() - 1);
      for (Index i = 0; i < rows_; ++i)
        for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k) {
          const Index q = fill[col_[k]]++;
          trow[q] = i;
          tpos[q] = k;
        }
    }
    std::vector<Index> slot(nc, -1);
    std::vector<ColIndex> zc;
    std::vector<double> zv;
    const bool first = C.A.rows != nc;
    if (first) coarse_pattern(A, tptr, trow, C, zc, slot);
    C.changed.assign(nc, first ? 1 : 0);
    std::vector<Index> pos(nc, -1);
    std::vector<double> row;
    for (Index q = 0; q < nc; ++q) {
      const Index I = visit ? visit[q] : q;
      if (!owned_c_[I]) continue;
      bool dirty = first;
      for (Index a = tptr[I]; a < tptr[I + 1] && !dirty; ++a) dirty = z_changed_[trow[a]];
      if (!dirty) continue;
      const Index c0 = C.A.indptr[I], c1 = C.A.indptr[I + 1];
      row.assign((c1 - c0) * d * d, 0.0);
      for (Index k = c0; k < c1; ++k) pos[C.A.indices[k]] = k - c0;
      for (Index a = tptr[I]; a < tptr[I + 1]; ++a) {
        const Index i = trow[a];
        const Mat<d> PT = block(i, tpos[a]).transpose();
        if (PT.isZero(0.0)) continue;
        const ColIndex* zcol;
        const double* zval;
        Index len;
        if (owned_f_[i]) {
          z_row(A, i, zc, zv, slot);
          zcol = zc.data(), zval = zv.data(), len = (Index)zc.size();
        } else {
          const Index g = ghost_at_.empty() ? -1 : ghost_at_[i];
          if (g < 0) continue;  // a ghost row left out reaches a coarse node this rank does not hold
          zcol = gcol_.data() + gptr_[g], zval = gval_.data() + gptr_[g] * d * d, len = gptr_[g + 1] - gptr_[g];
        }
        for (Index k = 0; k < len; ++k) {
          MatMap<d> Cb(row.data() + pos[zcol[k]] * d * d);
          multiply_add<d>(PT, CMatMap<d>(zval + k * d * d), Cb);
        }
      }
      double* stored = C.A.values.data() + c0 * d * d;
      if (first || std::memcmp(stored, row.data(), sizeof(double) * row.size()) != 0) {
        std::copy(row.begin(), row.end(), stored);
        C.changed[I] = 1;
      }
    }
    std::fill(z_changed_.begin(), z_changed_.end(), 0);
  }

  // ---- the transfers of the cycle -----------------------------------------------------------------

  // bc_I = sum_i P_iI^T (m_i r_i) over the fine rows i of I ascending, on the owned coarse rows (zero
  // elsewhere); mask per fine dof or nullptr. The fine rows are visited in ascending order and each
  // adds into its coarse rows: every coarse row receives its terms in ascending fine row.
  void restrict_residual(const double* r, const std::uint8_t* mask, double* bc) const {
    restrict_rows([r](Index i, double* ri) { std::copy(r + d * i, r + d * (i + 1), ri); }, mask, bc);
  }

  // The same with r_i = b_i - (A x)_i formed in the pass where known[i] is 0 (the rest read from r):
  // the fine residual restricted as it is formed (the serial restriction's fused pass, 0013), the
  // same row kernel, so the same bits as restrict_residual of a residual pass.
  void restrict_residual(const BlockMatrix<d>& A, const double* x, const double* b, const double* r, const std::uint8_t* known,
                         const std::uint8_t* mask, double* bc) const {
    const double* vals = A.values.data();
    restrict_rows([&](Index i, double* ri) {
      if (known[i]) std::copy(r + d * i, r + d * (i + 1), ri);
      else A.residual_row(vals, x, b, i, kPrefetchValueRows, ri);
    }, mask, bc);
  }

  // the scatter of restrict_residual with fine row i's residual from row(i, ri)
  template <class Row>
  void restrict_rows(Row&& row, const std::uint8_t* mask, double* bc) const {
    std::fill(bc, bc + d * cols_, 0.0);
    for (Index i = 0; i < rows_; ++i) {
      double ri[d];
      row(i, ri);
      if (mask)
        for (int c = 0; c < d; ++c) ri[c] = mask[i * d + c] ? ri[c] : 0.0;
      const double* F = full_row(i);
      for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k) {
        const Index I = col_[k];
        if (!owned_c_[I]) continue;
        double* out = bc + d * I;
        if (!F) {
          for (int e = 0; e < d; ++e) out[e] += w_[k] * ri[e];
          continue;
        }
        const double* B = F + (k - ptr_[i]) * d * d;  // row-major P_iI: entry (c, e) at c * d + e
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
    for (Index i = 0; i < rows_; ++i) {
      double t[d] = {};
      const double* F = full_row(i);
      if (F) {
        accumulate_blocks<d, false>(F, col_.data() + ptr_[i], 0, ptr_[i + 1] - ptr_[i], xc, t);
      } else {
        for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k) {
          const double* x = xc + d * (Index)col_[k];
          for (int c = 0; c < d; ++c) t[c] += w_[k] * x[c];
        }
      }
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
    std::fill(lo_c, lo_c + d * cols_, -kInf);
    std::fill(hi_c, hi_c + d * cols_, kInf);
    for (Index i = 0; i < rows_; ++i) {
      if (rows && !rows[i]) continue;
      const double* F = full_row(i);
      // entry (c, a) of the block of entry k on row i
      const auto weight = [&](Index k, int c, int a) { return F ? F[(k - ptr_[i]) * d * d + c * d + a] : (c == a ? w_[k] : 0.0); };
      for (int c = 0; c < d; ++c) {
        double l = lo[i * d + c], h = hi[i * d + c];
        if ((mask && !mask[i * d + c]) || (l == -kInf && h == kInf)) continue;
        if (x) { l -= x[i * d + c]; h -= x[i * d + c]; }
        double sigma = 0;
        for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k)
          for (int a = 0; a < d; ++a) sigma += std::abs(weight(k, c, a));
        const double scale = 1.0 / std::max(1.0, sigma);
        const double ls = l * scale, hs = h * scale;
        for (Index k = ptr_[i]; k < ptr_[i + 1]; ++k)
          for (int a = 0; a < d; ++a) {
            const double w = weight(k, c, a);
            if (w == 0) continue;
            const Index g = (Index)col_[k] * d + a;
            if (w > 0) { hi_c[g] = std::min(hi_c[g], hs); lo_c[g] = std::max(lo_c[g], ls); }
            else { hi_c[g] = std::min(hi_c[g], -ls); lo_c[g] = std::max(lo_c[g], -hs); }
          }
      }
    }
  }

  std::size_t bytes() const {
    return ptr_.size() * sizeof(Index) + col_.size() * sizeof(ColIndex) + w_.size() * sizeof(double) + full_at_.size() * sizeof(std::int32_t) +
           full_.size() * sizeof(double) + owned_f_.size() + owned_c_.size() + z_changed_.size() + mask_.size() +
           hess_nodes_.size() * sizeof(Index) + hess_at_.size() * sizeof(std::int32_t) + hess_.size() * sizeof(double) +
           ghost_at_.size() * sizeof(std::int32_t) +
           gptr_.size() * sizeof(Index) + gcol_.size() * sizeof(ColIndex) + gval_.size() * sizeof(double) + given_.size() * sizeof(Given);
  }

 private:
  Index nnz() const { return (Index)col_.size(); }

  // the full blocks of row i (nullptr: a plain row, w I)
  const double* full_row(Index i) const { return full_at_.empty() || full_at_[i] < 0 ? nullptr : full_.data() + full_at_[i] * d * d; }

  // the block of entry k (on row i) as the d x d block P held it
  Mat<d> block(Index i, Index k) const {
    const double* F = full_row(i);
    if (F) return Mat<d>(CMatMap<d>(F + (k - ptr_[i]) * d * d));
    Mat<d> B = Mat<d>::Zero();
    for (int a = 0; a < d; ++a) B(a, a) = w_[k];
    return B;
  }

  void check_fine(const BlockMatrix<d>& A) const {
    if (A.rows != rows_) throw InputError("the fine matrix and the transfer have different numbers of fine nodes");
  }

  void check_node(Index i, bool owned) const {
    if (i < 0 || i >= rows_ || (bool)owned_f_[i] != owned)
      throw InputError(std::string("node ") + std::to_string(i) + " is not an " + (owned ? "owned" : "ghost") + " fine node");
  }

  // The columns of owned row i of Z: the coarse nodes reached through A's row (its pattern, not its
  // values, so the truncation never changes it), ascending. slot: -1 per coarse node, left so.
  void z_columns(const BlockMatrix<d>& A, Index i, std::vector<ColIndex>& cols, std::vector<Index>& slot) const {
    cols.clear();
    for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k)
      for (Index b = ptr_[A.indices[k]]; b < ptr_[A.indices[k] + 1]; ++b)
        if (slot[col_[b]] < 0) { slot[col_[b]] = 0; cols.push_back(col_[b]); }
    for (ColIndex J : cols) slot[J] = -1;
    std::sort(cols.begin(), cols.end());
  }

  // Owned row i of Z = (M A M) P (with the Hessian block of the last set_fine): its columns
  // (z_columns) and blocks, each the sum over A's row in ascending column of Y_ij P_jJ.
  void z_row(const BlockMatrix<d>& A, Index i, std::vector<ColIndex>& cols, std::vector<double>& vals, std::vector<Index>& slot) const {
    z_columns(A, i, cols, slot);
    vals.assign(cols.size() * d * d, 0.0);
    for (std::size_t m = 0; m < cols.size(); ++m) slot[cols[m]] = (Index)m;
    for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
      const Index j = A.indices[k];
      // Y = M_i (A_ij + H_i [i == j]) M_j; the mask is 0/1, so these products are exact
      Mat<d> Y = A.block(k);
      if (j == i && !hess_at_.empty() && hess_at_[i] >= 0) Y += CMatMap<d>(hess_.data() + hess_at_[i] * d * d);
      for (int a = 0; a < d; ++a)
        for (int c = 0; c < d; ++c)
          if (!mask_[i * d + a] || !mask_[j * d + c]) Y(a, c) = 0.0;
      if (Y.isZero(0.0)) continue;
      for (Index b = ptr_[j]; b < ptr_[j + 1]; ++b) {
        MatMap<d> Zb(vals.data() + slot[col_[b]] * d * d);
        multiply_add<d>(Y, block(j, b), Zb);
      }
    }
    for (ColIndex J : cols) slot[J] = -1;
  }

  // The pattern of C's owned rows into C.A (ghost rows empty), values zero.
  void coarse_pattern(const BlockMatrix<d>& A, const std::vector<Index>& tptr, const std::vector<Index>& trow, CoarseRows<d>& C,
                      std::vector<ColIndex>& zc, std::vector<Index>& slot) const {
    const Index nc = cols_;
    C.A.rows = C.A.cols = nc;
    C.A.indptr.assign(nc + 1, 0);
    C.A.indices.clear();
    std::vector<Index> marker(nc, -1);
    std::vector<ColIndex> row;
    for (Index I = 0; I < nc; ++I) {
      row.clear();
      if (owned_c_[I]) {
        const auto add = [&](ColIndex J) {
          if (marker[J] != I) { marker[J] = I; row.push_back(J); }
        };
        for (Index a = tptr[I]; a < tptr[I + 1]; ++a) {
          const Index i = trow[a];
          if (owned_f_[i]) {
            z_columns(A, i, zc, slot);
            for (ColIndex J : zc) add(J);
          } else if (!ghost_at_.empty() && ghost_at_[i] >= 0) {
            for (Index k = gptr_[ghost_at_[i]]; k < gptr_[ghost_at_[i] + 1]; ++k) add(gcol_[k]);
          }
        }
        add((ColIndex)I);
      }
      std::sort(row.begin(), row.end());
      C.A.indices.insert(C.A.indices.end(), row.begin(), row.end());
      C.A.indptr[I + 1] = (Index)C.A.indices.size();
    }
    C.A.indices.shrink_to_fit();
    C.A.values.assign(C.A.indices.size() * d * d, 0.0);
    C.A.find_diagonal();
  }

  Index rows_, cols_;
  std::vector<Index> ptr_;                       // P: rows_ + 1
  std::vector<ColIndex> col_;                    // coarse node of each entry, ascending per row
  std::vector<double> w_;                        // the weight of each entry of a plain row
  std::vector<std::int32_t> full_at_;            // per row: its first block in full_, or -1 (empty: none)
  std::vector<double> full_;                     // the blocks of the rows that are not w I
  std::vector<std::uint8_t> owned_f_, owned_c_;
  std::vector<std::uint8_t> z_changed_;          // per fine row: its Z row changed since the last form_coarse
  std::vector<std::uint8_t> mask_;               // the inputs of the last set_fine
  std::vector<Index> hess_nodes_;
  std::vector<std::int32_t> hess_at_;            // per fine row: its Hessian block, or -1 (empty: none)
  std::vector<double> hess_;
  std::vector<std::int32_t> ghost_at_;           // per fine row: its ghost Z row, or -1 (empty: none)
  std::vector<Index> gptr_{0};                   // the ghost Z rows held
  std::vector<ColIndex> gcol_;
  std::vector<double> gval_;
  struct Given {
    Index node, blocks;
    bool held;
  };
  std::vector<Given> given_;                     // the ghost rows as sent: node, blocks, whether held
  bool inputs_set_ = false, ghost_pattern_done_ = false;
};

}  // namespace cmg
