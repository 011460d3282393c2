// Which rows of a level a Gauss-Seidel sweep visits, and in which order: every row or a subset
// (the changed region of an adaptive hierarchy), lexicographic, or by colours of the block graph
// (greedy in row order, or in the hashed order of the distributed solver: hashed_visit below).
// In the coloured order no two rows of one colour are coupled, so the rows of a colour are
// updated at once (threads); the colouring does not depend on the thread count, so neither does
// the result.
#pragma once
#include <algorithm>
#include "base/block_matrix.hpp"
#include "base/hashed_priority.hpp"
#include "base/parallel.hpp"
#include "base/solver_options.hpp"

namespace cmg {

class SweepOrder {
 public:
  SweepOrder() = default;                                   // every row
  explicit SweepOrder(std::vector<Index> rows) : rows_(std::move(rows)), all_(false) {}

  bool all() const { return all_; }
  bool coloured() const { return !colour_ptr_.empty(); }
  const std::vector<Index>& rows() const { return rows_; }  // empty when all or contiguous
  // The same rows in the hashed order of their node numbers (number(k): the number of stored row k,
  // the user's one, which the distributed solver's global ids equal): coloured_by() on the result
  // is the greedy colouring in that order, the colours of distributed/colouring.py.
  template <class Number>
  SweepOrder hashed_visit(Index n, Number&& number) const {
    std::vector<Index> rows = rows_;
    if (all_) {
      rows.resize(n);
      for (Index i = 0; i < n; ++i) rows[i] = i;
    }
    struct Key { std::uint64_t priority; Index number, row; };
    std::vector<Key> key(rows.size());
    for (std::size_t q = 0; q < rows.size(); ++q) {
      const Index m = (Index)number(rows[q]);
      key[q] = {hashed_priority(m), m, rows[q]};
    }
    std::sort(key.begin(), key.end(), [](const Key& a, const Key& b) {
      return a.priority != b.priority ? a.priority > b.priority : a.number > b.number;
    });
    for (std::size_t q = 0; q < rows.size(); ++q) rows[q] = key[q].row;
    return SweepOrder(std::move(rows));
  }
  // Every colour a contiguous range of rows (a level stored by colours).
  bool contiguous() const { return contiguous_; }
  std::size_t memory_bytes() const { return sizeof(Index) * (rows_.size() + colour_ptr_.size()); }
  Index num_colours() const { return coloured() ? (Index)colour_ptr_.size() - 1 : 0; }
  // coloured: the rows of colour c are rows()[colour_ptr()[c] .. colour_ptr()[c + 1])
  const std::vector<Index>& colour_ptr() const { return colour_ptr_; }

  // The same rows by colours of the block graph of A: greedy, visiting the rows in their order
  // and giving each the smallest colour none of its coupled rows has (coupled rows outside the
  // order are not coloured and constrain nothing); rows ascending per colour.
  template <int d>
  SweepOrder coloured_by(const BlockMatrix<d>& A) const {
    std::vector<Index> rows = rows_;
    if (all_) {
      rows.resize(A.rows);
      for (Index i = 0; i < A.rows; ++i) rows[i] = i;
    }
    std::vector<int> colour(A.rows, -1);
    std::vector<Index> seen;  // seen[c] == i: colour c is taken by a neighbour of row i
    int ncol = 0;
    for (Index i : rows) {
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
        const int c = colour[A.indices[k]];
        if (c >= 0) seen[c] = i;
      }
      int c = 0;
      while (c < ncol && seen[c] == i) ++c;
      if (c == ncol) { ++ncol; seen.push_back(-1); }
      colour[i] = c;
    }
    SweepOrder S;
    S.all_ = false;
    S.colour_ptr_.assign(ncol + 1, 0);
    for (Index i : rows) S.colour_ptr_[colour[i] + 1]++;
    for (int c = 0; c < ncol; ++c) S.colour_ptr_[c + 1] += S.colour_ptr_[c];
    std::vector<Index> fill(S.colour_ptr_.begin(), S.colour_ptr_.end() - 1);
    S.rows_.resize(rows.size());
    std::vector<Index> sorted = rows;
    std::sort(sorted.begin(), sorted.end());
    for (Index i : sorted) S.rows_[fill[colour[i]]++] = i;
    // Stored by colours (mg/renumbering.hpp), every colour is the range colour_ptr_[c] .. [c + 1):
    // the list of rows is then the identity and is dropped.
    S.contiguous_ = true;
    for (std::size_t k = 0; k < S.rows_.size() && S.contiguous_; ++k) S.contiguous_ = S.rows_[k] == (Index)k;
    if (S.contiguous_) std::vector<Index>().swap(S.rows_);
    return S;
  }

  // f(i) for the rows of a level of n rows, in order (forward) or reversed; coloured: the colours in
  // order or reversed, the rows of one colour on all threads (f must then touch row i only). One
  // parallel region per sweep with a barrier between colours, not a region per colour: each region start
  // wakes the second thread, which sleeps between regions (OMP_WAIT_POLICY=PASSIVE), and a fork-join
  // costs about two such hand-overs where a barrier costs one
  // (docs/dev/decisions/0003-coloured-gauss-seidel.md). Sweeps whose colours average fewer than
  // kSerialColourRows rows run on the calling thread: the hand-overs would cost more than the second
  // thread saves. Rows of one colour are independent, so the result is the same bit for bit either way.
  template <class F>
  void visit(Index n, bool forward, F&& f) const {
    if (coloured()) {
      const Index nc = num_colours();
      const Index total = colour_ptr_.back() - colour_ptr_.front();
      const auto row = [&](Index q) { return contiguous_ ? q : rows_[q]; };
#ifdef CONTACTMG_OPENMP
      if (total >= kSerialColourRows * nc && team_size() > 1) {
#pragma omp parallel
        for (Index cc = 0; cc < nc; ++cc) {
          const Index c = forward ? cc : nc - 1 - cc;
          const Index b = colour_ptr_[c], e = colour_ptr_[c + 1];
#pragma omp for schedule(static)
          for (Index q = b; q < e; ++q) f(row(q));
        }
        return;
      }
#endif
      for (Index cc = 0; cc < nc; ++cc) {
        const Index c = forward ? cc : nc - 1 - cc;
        for (Index q = colour_ptr_[c]; q < colour_ptr_[c + 1]; ++q) f(row(q));
      }
      return;
    }
    if (all_) {
      for (Index ii = 0; ii < n; ++ii) f(forward ? ii : n - 1 - ii);
      return;
    }
    const Index m = (Index)rows_.size();
    for (Index ii = 0; ii < m; ++ii) f(rows_[forward ? ii : m - 1 - ii]);
  }

  // f(b, e) over contiguous ranges of rows, for a level stored by colours (contiguous()): the
  // colours in order or reversed, each colour's range split over the threads (f must touch rows
  // [b, e) only; within a range the rows ascend). The fine sweep's kernel runs on these. One
  // parallel region per sweep with a barrier between colours, and the same size rule, as visit().
  template <class F>
  void visit_ranges(bool forward, F&& f) const {
    const Index nc = num_colours();
#ifdef CONTACTMG_OPENMP
    const Index total = colour_ptr_.back() - colour_ptr_.front();
    if (total >= kSerialColourRows * nc && team_size() > 1) {
#pragma omp parallel
      {
        const Index t = omp_get_thread_num(), T = omp_get_num_threads();
        for (Index cc = 0; cc < nc; ++cc) {
          const Index c = forward ? cc : nc - 1 - cc;
          const Index b = colour_ptr_[c], m = colour_ptr_[c + 1] - b;
          const Index lo = m * t / T, hi = m * (t + 1) / T;
          if (lo < hi) f(b + lo, b + hi);
#pragma omp barrier
        }
      }
      return;
    }
#endif
    for (Index cc = 0; cc < nc; ++cc) {
      const Index c = forward ? cc : nc - 1 - cc;
      if (colour_ptr_[c] < colour_ptr_[c + 1]) f(colour_ptr_[c], colour_ptr_[c + 1]);
    }
  }

  void check(Index n) const {
    for (Index i : rows_)
      if (i < 0 || i >= n) throw InputError("a row to smooth (" + std::to_string(i) + ") is outside 0.." + std::to_string(n - 1));
  }

 private:
  std::vector<Index> rows_;
  std::vector<Index> colour_ptr_;  // coloured: rows_[colour_ptr_[c] .. colour_ptr_[c+1]) have colour c
  bool all_ = true;
  bool contiguous_ = false;
};

}  // namespace cmg
