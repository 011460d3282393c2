// Which rows of a level a Gauss-Seidel sweep visits, and in which order: every row forward or
// backward today; a subset (the changed region of an adaptive hierarchy) or colours later.
#pragma once
#include "common.hpp"

namespace cmg {

class SweepOrder {
 public:
  SweepOrder() = default;                                   // every row
  explicit SweepOrder(std::vector<Index> rows) : rows_(std::move(rows)), all_(false) {}

  bool all() const { return all_; }
  const std::vector<Index>& rows() const { return rows_; }

  // f(i) for the rows of a level of n rows, in order (forward) or reversed.
  template <class F>
  void visit(Index n, bool forward, F&& f) const {
    if (all_) {
      for (Index ii = 0; ii < n; ++ii) f(forward ? ii : n - 1 - ii);
      return;
    }
    const Index m = (Index)rows_.size();
    for (Index ii = 0; ii < m; ++ii) f(rows_[forward ? ii : m - 1 - ii]);
  }

  void check(Index n) const {
    for (Index i : rows_)
      if (i < 0 || i >= n) throw InputError("a row to smooth (" + std::to_string(i) + ") is outside 0.." + std::to_string(n - 1));
  }

 private:
  std::vector<Index> rows_;
  bool all_ = true;
};

}  // namespace cmg
