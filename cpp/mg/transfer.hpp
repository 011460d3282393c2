// Transfer of vectors between consecutive levels: prolongation and restriction through the
// truncated P~ = diag(mask) P (the prolongation itself: mg/prolongation.hpp).
#pragma once
#include <algorithm>
#include <cmath>
#include "mg/prolongation.hpp"
#include "parallel.hpp"

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

// y_coarse += P^T diag(mask) r_fine over the fine rows [first, last), in row order
template <int d>
inline void restrict_rows(const Prolongation<d>& P, const std::uint8_t* mask, const double* rf, double* yc, Index first, Index last) {
  for (Index i = first; i < last; ++i) {
    Vec<d> r = CVecMap<d>(rf + d * i);
    if (mask)
      for (int c = 0; c < d; ++c) r[c] *= mask[i * d + c];
    if (!P.rotated(i)) {
      for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.values[k] * r;
      continue;
    }
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.block(i, k).transpose() * r;
  }
}

// y_coarse = P^T diag(mask) r_fine. A scatter: the fine rows are split into two fixed halves, the
// first summed into y, the second into `scratch` (coarse size), then y += scratch -- on two
// threads at once, and the same sums in the same order on any thread count (bit for bit).
template <int d>
void restrict_residual(const Prolongation<d>& P, const std::uint8_t* mask, const double* rf, double* yc, double* scratch) {
  const Index nc = d * P.cols, half = P.rows / 2;
  if (P.rows < kParallelGrain) {
    std::fill(yc, yc + nc, 0.0);
    restrict_rows<d>(P, mask, rf, yc, 0, P.rows);
    return;
  }
  parallel_for(2, [&](Index h) {
    double* y = h == 0 ? yc : scratch;
    std::fill(y, y + nc, 0.0);
    restrict_rows<d>(P, mask, rf, y, h == 0 ? 0 : half, h == 0 ? half : P.rows);
  }, 1);
  parallel_for(nc, [&](Index k) { yc[k] += scratch[k]; });
}

}  // namespace cmg
