// Transfer between consecutive levels: the prolongation from interpolation weights, its transpose,
// prolongation and restriction of vectors through the truncated P~ = diag(mask) P.
#pragma once
#include <algorithm>
#include <cmath>
#include "block_matrix.hpp"
#include "parallel.hpp"

namespace cmg {

// Prolongation from interpolation weights (fine node <- coarse nodes), canonical basis on both
// levels (a basis transform of the fine level is applied afterwards, basis_transform.hpp).
template <int d>
BlockMatrix<d> make_prolongation(Index n_fine, Index n_coarse, const Index* ptr, const Index* parent, const double* weight) {
  BlockMatrix<d> P;
  P.rows = n_fine;
  P.cols = n_coarse;
  check_block_count(n_fine);
  check_block_count(n_coarse);
  P.indptr.assign(ptr, ptr + n_fine + 1);
  P.indices.resize(ptr[n_fine]);
  P.values.assign(ptr[n_fine] * d * d, 0.0);
  for (Index i = 0; i < n_fine; ++i) {
    std::vector<std::pair<Index, double>> row;
    for (Index k = ptr[i]; k < ptr[i + 1]; ++k) {
      if (parent[k] < 0 || parent[k] >= n_coarse) throw InputError("prolongation refers to a coarse node out of range");
      row.emplace_back(parent[k], weight[k]);
    }
    std::sort(row.begin(), row.end());
    for (std::size_t m = 0; m < row.size(); ++m) {
      P.indices[ptr[i] + m] = row[m].first;
      P.block(ptr[i] + m) = row[m].second * Mat<d>::Identity();
    }
  }
  return P;
}

template <int d>
BlockMatrix<d> transpose(const BlockMatrix<d>& P) {
  BlockMatrix<d> T;
  T.rows = P.cols;
  T.cols = P.rows;
  T.indptr.assign(T.rows + 1, 0);
  for (Index k = 0; k < P.nnz(); ++k) T.indptr[P.indices[k] + 1]++;
  for (Index i = 0; i < T.rows; ++i) T.indptr[i + 1] += T.indptr[i];
  T.indices.resize(P.nnz());
  T.values.resize(P.values.size());
  std::vector<Index> fill(T.indptr.begin(), T.indptr.end() - 1);
  for (Index i = 0; i < P.rows; ++i)
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) {
      Index pos = fill[P.indices[k]]++;
      T.indices[pos] = i;
      T.block(pos) = P.block(k).transpose();
    }
  return T;
}

// x_fine += diag(mask) P x_coarse
template <int d>
void prolongate_add(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* xc, double* xf) {
  parallel_for(P.rows, [&](Index i) {
    Vec<d> s = Vec<d>::Zero();
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) s.noalias() += P.block(k) * CVecMap<d>(xc + d * P.indices[k]);
    if (mask)
      for (int c = 0; c < d; ++c) s[c] *= mask[i * d + c];
    VecMap<d>(xf + d * i) += s;
  });
}

// x_fine = diag(mask) P x_coarse
template <int d>
void prolongate(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* xc, double* xf) {
  parallel_for(P.rows, [&](Index i) {
    Vec<d> s = Vec<d>::Zero();
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) s.noalias() += P.block(k) * CVecMap<d>(xc + d * P.indices[k]);
    if (mask)
      for (int c = 0; c < d; ++c) s[c] *= mask[i * d + c];
    VecMap<d>(xf + d * i) = s;
  });
}

// y_coarse += P^T diag(mask) r_fine over the fine rows [first, last), in row order
template <int d>
inline void restrict_rows(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* rf, double* yc, Index first, Index last) {
  for (Index i = first; i < last; ++i) {
    Vec<d> r = CVecMap<d>(rf + d * i);
    if (mask)
      for (int c = 0; c < d; ++c) r[c] *= mask[i * d + c];
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.block(k).transpose() * r;
  }
}

// y_coarse = P^T diag(mask) r_fine. A scatter: the fine rows are split into two fixed halves, the
// first summed into y, the second into `scratch` (coarse size), then y += scratch -- on two
// threads at once, and the same sums in the same order on any thread count (bit for bit).
template <int d>
void restrict_residual(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* rf, double* yc, double* scratch) {
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
