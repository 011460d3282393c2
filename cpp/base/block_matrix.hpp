// Block sparse rows with fixed d x d blocks: the one matrix type of the core.
#pragma once
#include <algorithm>
#include "base/parallel.hpp"

namespace cmg {

using ColIndex = std::int32_t;

// Block rows/columns must fit ColIndex.
inline void check_block_count(Index n) {
  if (n > (Index)std::numeric_limits<ColIndex>::max())
    throw InputError("too many nodes for one matrix (" + std::to_string(n) + ")");
}

// The row passes over a level (sweeps, products, residuals) prefetch x at the block columns of the row
// this far ahead. On a level stored by colours a row's columns are rows of the other colours -- loads
// from several other ranges of x, which the hardware prefetcher does not follow -- and those loads were
// where the fine sweep stalled (docs/dev/decisions/0015-locality-order.md). About two rows' worth of
// memory latency ahead; 4-32 measured alike on the level-9 Hertz matrix.
constexpr Index kPrefetchRows = 8;

// The prefetch helpers are forced inline: a function holding nothing but __builtin_prefetch has no side
// effect in GCC's eyes (IPA pure-const), so where it was not inlined GCC 12 deleted the call itself --
// the residual, the product and the norm passes prefetched nothing
// (docs/dev/decisions/0015-locality-order.md; 48 prefetch instructions in the whole module, all in the
// fine sweep's inlined kernel).
#define CMG_PREFETCH_INLINE inline __attribute__((always_inline))

// Prefetch x at the block columns k in [b, e) (a hint: no result depends on it).
template <int d>
CMG_PREFETCH_INLINE void prefetch_block_columns(const ColIndex* indices, Index b, Index e, const double* x) {
  for (Index k = b; k < e; ++k) __builtin_prefetch(x + d * (Index)indices[k]);
}

// The row passes also prefetch the matrix values of the row this many rows ahead. The values are
// one sequential stream, but beside the gathers of x and the other arrays the hardware prefetcher
// did not keep ahead of it: level 9, one thread, fine sweep 35.8 -> 27.1 ms, cycle 0.499 -> 0.403 s;
// 16 and 64 alike (docs/dev/decisions/0015-locality-order.md).
constexpr Index kPrefetchValueRows = 16;

// The cache lines of the values of row j; V: the stored value type
template <int d, class V>
CMG_PREFETCH_INLINE void prefetch_block_values(const V* values, const Index* ptr, Index j) {
  const char* b = reinterpret_cast<const char*>(values + ptr[j] * d * d);
  const char* e = reinterpret_cast<const char*>(values + ptr[j + 1] * d * d);
  for (; b < e; b += 64) __builtin_prefetch(b);
}

// A row loop over row(0), row(1), ... at step q: x at the columns of the row kPrefetchRows ahead and
// the values of the row kPrefetchValueRows ahead, where has(q') says that row q' is to be read
// (the fine and coarse sweeps' range and list loops).
template <int d, class V, class Row, class Has>
CMG_PREFETCH_INLINE void prefetch_rows_ahead(const V* values, const ColIndex* cols, const Index* ptr, const double* x, Index q,
                                             Row&& row, Has&& has) {
  if (has(q + kPrefetchRows)) {
    const Index j = row(q + kPrefetchRows);
    prefetch_block_columns<d>(cols, ptr[j], ptr[j + 1], x);
  }
  if (has(q + kPrefetchValueRows)) prefetch_block_values<d>(values, ptr, row(q + kPrefetchValueRows));
}

// The cache lines of the values of row i + ahead (if there is one)
template <int d, class V>
CMG_PREFETCH_INLINE void prefetch_row_values(const V* values, const Index* ptr, Index i, Index ahead, Index n) {
  if (ahead <= 0 || i + ahead >= n) return;
  prefetch_block_values<d>(values, ptr, i + ahead);
}

// s (+/-)= sum_{k in [b, e)} A_k x_{col k} over d x d row-major blocks. Scalar accumulators: with
// Eigen's small vector as the accumulator GCC kept it in memory across the loop (a store-to-load
// chain per block, the hottest instructions of the fine sweep's profile) and summed each block
// row by a horizontal add. The same products and sums in the same order: the same bits.
template <int d, bool subtract, class V>
inline void accumulate_blocks(const V* values, const ColIndex* indices, Index b, Index e, const double* x, double* s) {
  double acc[d];
  for (int a = 0; a < d; ++a) acc[a] = s[a];
  for (Index k = b; k < e; ++k) {
    const V* B = values + k * d * d;
    const double* xj = x + d * (Index)indices[k];
    for (int a = 0; a < d; ++a) {
      double t = (double)B[a * d] * xj[0];
      for (int c = 1; c < d; ++c) t += (double)B[a * d + c] * xj[c];
      if (subtract) acc[a] -= t;
      else acc[a] += t;
    }
  }
  for (int a = 0; a < d; ++a) s[a] = acc[a];
}

// s += sum_{k in [b, e)} A_k (x - z)_{col k}, as accumulate_blocks (the difference formed per block
// column, as Eigen's block * (x - z) formed it).
template <int d>
inline void accumulate_block_differences(const double* values, const ColIndex* indices, Index b, Index e, const double* x,
                                         const double* z, double* s) {
  double acc[d];
  for (int a = 0; a < d; ++a) acc[a] = s[a];
  for (Index k = b; k < e; ++k) {
    const double* B = values + k * d * d;
    const Index j = d * (Index)indices[k];
    double w[d];
    for (int c = 0; c < d; ++c) w[c] = x[j + c] - z[j + c];
    for (int a = 0; a < d; ++a) {
      double t = B[a * d] * w[0];
      for (int c = 1; c < d; ++c) t += B[a * d + c] * w[c];
      acc[a] += t;
    }
  }
  for (int a = 0; a < d; ++a) s[a] = acc[a];
}

template <int d>
struct BlockMatrix {
  static constexpr int bs = d * d;
  Index rows = 0, cols = 0;          // in blocks
  std::vector<Index> indptr;         // rows + 1
  // Block column of each stored block, sorted per row. 32 bits: the sweeps and products stream the
  // matrix and are bound by memory bandwidth, and 64-bit columns were a fifth of the bytes read.
  std::vector<ColIndex> indices;
  std::vector<double> values;        // nnz * d * d, each block row-major
  std::vector<Index> diag;           // position of the diagonal block per row (-1 if absent)

  Index nnz() const { return (Index)indices.size(); }
  MatMap<d> block(Index k) { return MatMap<d>(values.data() + k * bs); }
  CMatMap<d> block(Index k) const { return CMatMap<d>(values.data() + k * bs); }

  void find_diagonal() {
    diag.assign(rows, -1);
    for (Index i = 0; i < rows; ++i)
      for (Index k = indptr[i]; k < indptr[i + 1]; ++k)
        if (indices[k] == i) { diag[i] = k; break; }
  }

  // Position of block (i, j), or -1.
  Index find(Index i, Index j) const {
    auto b = indices.begin() + indptr[i], e = indices.begin() + indptr[i + 1];
    auto it = std::lower_bound(b, e, j);
    return (it != e && *it == j) ? Index(it - indices.begin()) : -1;
  }

  // x at the columns of row i + kPrefetchRows (if there is one) into the cache
  CMG_PREFETCH_INLINE void prefetch_ahead(Index i, const double* x) const {
    if (i + kPrefetchRows < rows) prefetch_block_columns<d>(indices.data(), indptr[i + kPrefetchRows], indptr[i + kPrefetchRows + 1], x);
  }

  // ... and z too (the passes over a difference x - z)
  CMG_PREFETCH_INLINE void prefetch_ahead(Index i, const double* x, const double* z) const {
    if (i + kPrefetchRows >= rows) return;
    for (Index k = indptr[i + kPrefetchRows]; k < indptr[i + kPrefetchRows + 1]; ++k) {
      __builtin_prefetch(x + d * (Index)indices[k]);
      __builtin_prefetch(z + d * (Index)indices[k]);
    }
  }

  // y = A x (rows on all threads: each writes its own entries)
  void multiply(const double* x, double* y) const {
    constexpr Index ahead = kPrefetchValueRows;
    const double* vals = values.data();
    parallel_for(rows, [&](Index i) {
      prefetch_ahead(i, x);
      prefetch_row_values<d>(vals, indptr.data(), i, ahead, rows);
      double s[d] = {};
      accumulate_blocks<d, false>(vals, indices.data(), indptr[i], indptr[i + 1], x, s);
      for (int a = 0; a < d; ++a) y[d * i + a] = s[a];
    });
  }

  // s = (b - A x)_i, with the prefetches of the row passes (vals: the values). The one
  // row kernel of residual() and of the residual restricted in the same pass (mg/transfer.hpp):
  // the same bits either way.
  template <class V>
  CMG_PREFETCH_INLINE void residual_row(const V* vals, const double* x, const double* b, Index i, Index ahead, double* s) const {
    prefetch_ahead(i, x);
    prefetch_row_values<d>(vals, indptr.data(), i, ahead, rows);
    for (int a = 0; a < d; ++a) s[a] = b[d * i + a];
    accumulate_blocks<d, true>(vals, indices.data(), indptr[i], indptr[i + 1], x, s);
  }

  // r = b - A x in one pass (a product and a vector update fused)
  void residual(const double* x, const double* b, double* r) const {
    constexpr Index ahead = kPrefetchValueRows;
    const double* vals = values.data();
    parallel_for(rows, [&](Index i) {
      double s[d];
      residual_row(vals, x, b, i, ahead, s);
      for (int a = 0; a < d; ++a) r[d * i + a] = s[a];
    });
  }

  std::size_t memory_bytes() const {
    return sizeof(Index) * (indptr.size() + diag.size()) + sizeof(ColIndex) * indices.size() + sizeof(double) * values.size();
  }
};

// Builds the block pattern of a square matrix from lists of coupled nodes (e.g. the cells of a mesh):
// every pair of nodes in one group is coupled.
template <int d>
BlockMatrix<d> pattern_from_groups(Index n, const Index* groups, Index num_groups, int group_size) {
  check_block_count(n);
  std::vector<Index> count(n + 1, 0);
  // Upper bound per row first, then sort and unique in place.
  for (Index g = 0; g < num_groups; ++g)
    for (int a = 0; a < group_size; ++a) count[groups[g * group_size + a] + 1] += group_size;
  for (Index i = 0; i < n; ++i) count[i + 1] += count[i];
  std::vector<Index> cols(count[n]);
  std::vector<Index> fill(count.begin(), count.end() - 1);
  for (Index g = 0; g < num_groups; ++g)
    for (int a = 0; a < group_size; ++a) {
      Index i = groups[g * group_size + a];
      for (int b = 0; b < group_size; ++b) cols[fill[i]++] = groups[g * group_size + b];
    }
  BlockMatrix<d> A;
  A.rows = A.cols = n;
  A.indptr.assign(n + 1, 0);
  for (Index i = 0; i < n; ++i) {
    auto b = cols.begin() + count[i], e = cols.begin() + count[i + 1];
    std::sort(b, e);
    A.indptr[i + 1] = A.indptr[i] + (std::unique(b, e) - b);
  }
  A.indices.resize(A.indptr[n]);
  for (Index i = 0; i < n; ++i) {
    Index len = A.indptr[i + 1] - A.indptr[i];
    std::copy(cols.begin() + count[i], cols.begin() + count[i] + len, A.indices.begin() + A.indptr[i]);
  }
  A.values.assign(A.indices.size() * BlockMatrix<d>::bs, 0.0);
  A.find_diagonal();
  return A;
}

}  // namespace cmg
