// The memory bandwidth the sweeps are measured against (docs/dev/decisions/0015-locality-order.md), on
// the threads of the caller's ThreadScope, with the same static schedule as the core's loops (each
// thread touches its own pages first), on arrays far larger than the caches, compiled as the core is
// (its flags, no -march):
// - a STREAM-like triad a = b + s c (the reference of the issue);
// - reads: a sum over one array read as `streams` parts at once. A cycle mostly reads -- matrix
//   values and columns, x, b, the inverted diagonals -- from several streams at a time, and on this
//   project's VM one core's read rate depends on how many: 10.9 GB/s from one stream, 15.0 from four
//   (docs/dev/decisions/0012-thread-reproducibility.md);
// - a matrix-like read: d x d blocks of doubles with int32 columns, row by row through the row
//   passes' kernel (accumulate_blocks, with their value prefetch), x small enough for the caches:
//   the matrix bytes of a product at their best.
#pragma once
#include <chrono>
#include "base/block_matrix.hpp"
#include "base/parallel.hpp"

namespace cmg {

// Best of `repeats` runs of f(), in seconds
template <class F>
double best_seconds(int repeats, F&& f) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

// Bytes per second of the best of `repeats` triads over n doubles (24 bytes an entry: b and c read,
// a written; the STREAM convention: the write-allocate read of a's lines -- 8 more bytes an entry
// the memory moves with plain stores -- is not counted).
inline double triad_bytes_per_second(Index n, int repeats) {
  std::vector<double> a(n), b(n), c(n);
  parallel_for(n, [&](Index i) { a[i] = 0.0; b[i] = 1.0 + 1e-9 * (double)i; c[i] = 2.0; });
  const double best = best_seconds(repeats, [&] { parallel_for(n, [&](Index i) { a[i] = b[i] + 1.5 * c[i]; }); });
  volatile double sink = a[n / 2];
  (void)sink;
  return 24.0 * (double)n / best;
}

// The sum of a[b + s m + i], s < S, i < m: S pieces of m entries read at once, four accumulators a
// piece (no add latency chain: the loop waits for memory only); S a template parameter so that
// the accumulators stay in registers.
template <int S>
double sum_pieces(const double* a, Index m) {
  constexpr int kAcc = 4;
  double acc[S][kAcc] = {};
  for (Index i = 0; i + kAcc <= m; i += kAcc)
    for (int s = 0; s < S; ++s)
      for (int k = 0; k < kAcc; ++k) acc[s][k] += a[s * m + i + k];
  double sum = 0;
  for (int s = 0; s < S; ++s)
    for (int k = 0; k < kAcc; ++k) sum += acc[s][k];
  return sum;
}

// Bytes per second of the best of `repeats` sums over n doubles (8 bytes an entry, read only):
// each thread sums its own contiguous part as `streams` (1, 2, 4 or 8) equal pieces read at once.
inline double read_bytes_per_second(Index n, int repeats, int streams) {
  if (streams != 1 && streams != 2 && streams != 4 && streams != 8) throw InputError("streams must be 1, 2, 4 or 8");
  std::vector<double> a(n);
  const Index T = team_size();
  const Index m = n / T / (4 * streams) * 4;  // entries a piece, a multiple of the accumulators
  parallel_for(T, [&](Index t) {
    for (Index i = n * t / T; i < n * (t + 1) / T; ++i) a[i] = 1.0 + 1e-9 * (double)i;
  }, 1);
  std::vector<double> sums(T);
  const double best = best_seconds(repeats, [&] {
    parallel_for(T, [&](Index t) {
      const double* p = a.data() + n * t / T;
      sums[t] = streams == 1 ? sum_pieces<1>(p, m) : streams == 2 ? sum_pieces<2>(p, m) : streams == 4 ? sum_pieces<4>(p, m)
                                                                                                    : sum_pieces<8>(p, m);
    }, 1);
  });
  volatile double sink = sums[0];
  (void)sink;
  return 8.0 * (double)(T * streams * m) / best;
}

// Bytes per second of the best of `repeats` matrix-like reads: `blocks` d x d blocks of doubles and
// their int32 columns (8 d^2 + 4 bytes a block), `per_row` blocks a row (a P1 row: 7 in 2D, 15 in
// 3D), summed times x at the columns through accumulate_blocks with the row passes' prefetch of the
// values ahead; x holds 4096 nodes (in L2), so only the matrix streams from memory. Row pointers
// and the row results (12 bytes a row) are not counted.
template <int d>
double block_read_bytes_per_second(Index blocks, int repeats, int per_row) {
  const Index rows = blocks / per_row, nb = rows * per_row;
  constexpr Index kx = 4096;
  BlockMatrix<d> A;
  A.rows = rows;
  A.cols = kx;
  A.indptr.resize(rows + 1);
  for (Index i = 0; i <= rows; ++i) A.indptr[i] = i * per_row;
  A.indices.resize(nb);
  A.values.resize(nb * d * d);
  // columns near the row's own (mod kx), as a mesh's: the gathers hit the caches
  parallel_for(rows, [&](Index i) {
    for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
      A.indices[k] = (ColIndex)((i + 3 * (k - A.indptr[i])) % kx);
      for (int c = 0; c < d * d; ++c) A.values[k * d * d + c] = 1.0 + 1e-9 * (double)k;
    }
  });
  std::vector<double> x(kx * d, 1.0), y(rows * d);
  constexpr Index ahead = kPrefetchValueRows;
  const double best = best_seconds(repeats, [&] {
    parallel_for(rows, [&](Index i) {
      prefetch_row_values<d>(A.values.data(), A.indptr.data(), i, ahead, rows);
      double s[d] = {};
      accumulate_blocks<d, false>(A.values.data(), A.indices.data(), A.indptr[i], A.indptr[i + 1], x.data(), s);
      for (int a = 0; a < d; ++a) y[d * i + a] = s[a];
    });
  });
  volatile double sink = y[d * (rows / 2)];
  (void)sink;
  return (8.0 * d * d + 4.0) * (double)nb / best;
}

}  // namespace cmg
