// Transfer of vectors between consecutive levels: prolongation and restriction through the
// truncated P~ = diag(mask) P (the prolongation itself: mg/prolongation.hpp).
#pragma once
#include <algorithm>
#include <cmath>
#include "mg/prolongation.hpp"
#include "base/parallel.hpp"

namespace cmg {

// The rows of P x_coarse: w x on a plain row (the bits of (w I) x), R^T w x on a rotated one.
template <int d>
inline Vec<d> prolongated_row(const Prolongation<d>& P, const double* xc, Index i) {
  Vec<d> s = Vec<d>::Zero();
  if (!P.rotated(i)) {
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) s.noalias() += P.values[k] * CVecMap<d>(xc + d * P.indices[k]);
    return s;
  }
  for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) s.noalias() += P.block(i, k) * CVecMap<d>(xc + d * P.indices[k]);
  return s;
}

// x_fine += diag(mask) P x_coarse
template <int d>
void prolongate_add(const Prolongation<d>& P, const std::uint8_t* mask, const double* xc, double* xf) {
  parallel_for(P.rows, [&](Index i) {
    Vec<d> s = prolongated_row<d>(P, xc, i);
    if (mask)
      for (int c = 0; c < d; ++c) s[c] *= mask[i * d + c];
    VecMap<d>(xf + d * i) += s;
  });
}

// x_fine = diag(mask) P x_coarse
template <int d>
void prolongate(const Prolongation<d>& P, const std::uint8_t* mask, const double* xc, double* xf) {
  parallel_for(P.rows, [&](Index i) {
    Vec<d> s = prolongated_row<d>(P, xc, i);
    if (mask)
      for (int c = 0; c < d; ++c) s[c] *= mask[i * d + c];
    VecMap<d>(xf + d * i) = s;
  });
}

// y_coarse += P^T diag(mask) r over the fine rows [first, last), in row order; r_i = row(i), a Vec<d>
template <int d, class Row>
inline void restrict_rows_of(const Prolongation<d>& P, const std::uint8_t* mask, Row&& row, double* yc, Index first, Index last) {
  for (Index i = first; i < last; ++i) {
    Vec<d> r = row(i);
    if (mask)
      for (int c = 0; c < d; ++c) r[c] *= mask[i * d + c];
    if (!P.rotated(i)) {
      for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.values[k] * r;
      continue;
    }
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.block(i, k).transpose() * r;
  }
}

// y_coarse = P^T diag(mask) r with r_i = row(i). A scatter: the fine rows are split into two fixed
// halves, the first summed into y, the second into `scratch` (coarse size), then y += scratch -- on
// two threads at once, and the same sums in the same order on any thread count (bit for bit).
template <int d, class Row>
void restrict_of(const Prolongation<d>& P, const std::uint8_t* mask, Row&& row, double* yc, double* scratch) {
  const Index nc = d * P.cols, half = P.rows / 2;
  if (P.rows < kParallelGrain) {
    std::fill(yc, yc + nc, 0.0);
    restrict_rows_of<d>(P, mask, row, yc, 0, P.rows);
    return;
  }
  parallel_for(2, [&](Index h) {
    double* y = h == 0 ? yc : scratch;
    std::fill(y, y + nc, 0.0);
    restrict_rows_of<d>(P, mask, row, y, h == 0 ? 0 : half, h == 0 ? half : P.rows);
  }, 1);
  parallel_for(nc, [&](Index k) { yc[k] += scratch[k]; });
}

// y_coarse = P^T diag(mask) r_fine
template <int d>
void restrict_residual(const Prolongation<d>& P, const std::uint8_t* mask, const double* rf, double* yc, double* scratch) {
  restrict_of<d>(P, mask, [&](Index i) { return Vec<d>(CVecMap<d>(rf + d * i)); }, yc, scratch);
}

// y_coarse = P^T (b - A x) in one pass over A: each row's residual restricted as it is formed
// (BlockMatrix::residual_row), never stored -- a level's residual pass wrote a vector that the
// restriction read straight back (32 of the ~290 bytes a row of a 2D coarse level streamed;
// docs/dev/decisions/0013-fused-residual.md). The same rows, sums and order as A.residual then
// restrict_residual: the same bits.
template <int d>
void restrict_level_residual(const BlockMatrix<d>& A, const Prolongation<d>& P, const double* x, const double* b, double* yc,
                             double* scratch) {
  constexpr Index ahead = kPrefetchValueRows;
  const double* vals = A.values.data();
  restrict_of<d>(P, nullptr, [&](Index i) {
    Vec<d> s;
    A.residual_row(vals, x, b, i, ahead, s.data());
    return s;
  }, yc, scratch);
}

}  // namespace cmg
