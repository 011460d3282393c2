// The memory bandwidth the sweeps are measured against (issue 15): a STREAM-like triad
// a = b + s c on arrays far larger than the caches, on the threads of the caller's ThreadScope,
// with the same static schedule as the core's loops (each thread touches its own pages first).
#pragma once
#include <chrono>
#include "parallel.hpp"

namespace cmg {

// Bytes per second of the best of `repeats` triads over n doubles (24 bytes an entry: b and c read,
// a written; the STREAM convention, write-allocate traffic not counted).
inline double triad_bytes_per_second(Index n, int repeats) {
  std::vector<double> a(n), b(n), c(n);
  parallel_for(n, [&](Index i) { a[i] = 0.0; b[i] = 1.0 + 1e-9 * (double)i; c[i] = 2.0; });
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    parallel_for(n, [&](Index i) { a[i] = b[i] + 1.5 * c[i]; });
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  volatile double sink = a[n / 2];
  (void)sink;
  return 24.0 * (double)n / best;
}

}  // namespace cmg
