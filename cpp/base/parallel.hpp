// Shared-memory threads (OpenMP when the build found it, else one thread): the thread count of a
// solve, and loops over independent items. Results never depend on the count: parallel loops only
// write disjoint entries, and sums are formed over fixed chunks added in a fixed order.
#pragma once
#include <algorithm>
#include <array>
#include <vector>
#include "base/common.hpp"
#ifdef CONTACTMG_OPENMP
#include <omp.h>
#endif

namespace cmg {

inline bool have_openmp() {
#ifdef CONTACTMG_OPENMP
  return true;
#else
  return false;
#endif
}

inline int max_threads() {
#ifdef CONTACTMG_OPENMP
  return omp_get_num_procs();
#else
  return 1;
#endif
}

// The most threads a parallel loop started now may have, and the calling thread's number in it
// (for per-thread scratch space; never for what a result depends on).
inline int team_size() {
#ifdef CONTACTMG_OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
inline int thread_id() {
#ifdef CONTACTMG_OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

// The thread count of the loops below while it lives (0: all cores); the old count after.
class ThreadScope {
 public:
  explicit ThreadScope(int threads) {
    if (threads < 0) throw InputError("threads must be >= 0 (0: all cores)");
#ifdef CONTACTMG_OPENMP
    old_ = omp_get_max_threads();
    omp_set_num_threads(threads == 0 ? omp_get_num_procs() : threads);
#endif
  }
  ~ThreadScope() {
#ifdef CONTACTMG_OPENMP
    omp_set_num_threads(old_);
#endif
  }
  ThreadScope(const ThreadScope&) = delete;
  ThreadScope& operator=(const ThreadScope&) = delete;

 private:
  int old_ = 1;
};

// Below this many items a loop runs on one thread: starting the team costs more than it saves.
constexpr Index kParallelGrain = 4096;

// Sizes below which the multigrid levels keep their work on the calling thread: a coloured sweep
// whose colours average fewer than kSerialColourRows rows (mg/sweep_order.hpp), a coarse level of
// fewer than kSerialLevelRows block rows and every coarser one (mg/cycle.hpp). Results do not
// depend on them (bit for bit): waking the second thread costs more than it saves below them.
constexpr Index kSerialColourRows = 1024;
constexpr Index kSerialLevelRows = 8192;

// f(i) for i in [0, n), items independent of each other; one thread below `grain` items.
template <class F>
inline void parallel_for(Index n, F&& f, Index grain = kParallelGrain) {
#ifdef CONTACTMG_OPENMP
#pragma omp parallel for schedule(static) if (n >= grain)
  for (Index i = 0; i < n; ++i) f(i);
#else
  for (Index i = 0; i < n; ++i) f(i);
#endif
}

// sum_i f(i) over [0, n): partial sums over chunks of a fixed length (not per thread), added in
// chunk order, so the value is the same bit for bit on any thread count.
template <class F>
inline double parallel_sum(Index n, F&& f) {
  constexpr Index chunk = 8192;
  const Index nchunks = (n + chunk - 1) / chunk;
  if (nchunks <= 1) {
    double s = 0;
    for (Index i = 0; i < n; ++i) s += f(i);
    return s;
  }
  std::vector<double> part(nchunks, 0.0);
  parallel_for(nchunks, [&](Index c) {
    const Index b = c * chunk, e = std::min(n, b + chunk);
    double s = 0;
    for (Index i = b; i < e; ++i) s += f(i);
    part[c] = s;
  }, 2);
  double s = 0;
  for (double p : part) s += p;
  return s;
}

// m <= M sums over [0, n) in one pass: f(i, s) adds item i's term of sum j to s[j]. Each sum runs
// over the chunks of parallel_sum in the same order, so it equals that sum bit for bit; one pass
// instead of m reads the shared operands once.
template <int M, class F>
inline std::array<double, M> parallel_sums(Index n, int m, F&& f) {
  constexpr Index chunk = 8192;
  const Index nchunks = (n + chunk - 1) / chunk;
  std::array<double, M> s{};
  if (nchunks <= 1) {
    for (Index i = 0; i < n; ++i) f(i, s.data());
    return s;
  }
  std::vector<std::array<double, M>> part(nchunks);
  parallel_for(nchunks, [&](Index c) {
    const Index b = c * chunk, e = std::min(n, b + chunk);
    std::array<double, M> p{};
    for (Index i = b; i < e; ++i) f(i, p.data());
    part[c] = p;
  }, 2);
  for (const auto& p : part)
    for (int j = 0; j < m; ++j) s[j] += p[j];
  return s;
}

}  // namespace cmg
