// Anderson acceleration of the cycle map x -> G(x) once the contact state has settled.
//
// Why: Algorithm 2's coarse problem freezes the Coulomb bound F |s_n| of the sliding nodes (it does not
// see that a coarse correction changes their normal force, hence their friction force). Once the contact
// state stops changing, the cycle is a fixed affine map near the solution, and what the coarse problem
// misses shows as a slow linear contraction: 0.7 per cycle at F = 5 on uniform Hertz level 9, 0.8 at F =
// 40 on adaptive level 9 (docs/dev/decisions/0010-settled-anderson.md). Anderson mixing of the last few
// cycles removes those few slow modes, as a Krylov method would on the affine map.
//
// What keeps it safe (no parameter a user sets; the depth is fixed here):
//  - it mixes cycles with a sliding node (the caller resets the history when nothing slides), of
//    one contact state as long as the cycle makes progress: the caller restarts the history when
//    the truncation changed, unless the plain cycle's step is no smaller (energy norm) than every
//    step of the solve before (monotone_mg_step.hpp says why);
//  - the mixed iterate is handed to `admit`, which must give it exactly the contact state of the
//    plain cycle's result (or refuse it): active normals on the gap, sticking tangentials at their
//    exact values, inactive nodes off the obstacle, sliding nodes sliding the same way;
//  - a step after which the fixed-point residual |G(x) - x| did not decrease restarts the history
//    (the plain cycle's result is taken that time).
// The stopping test and the confirming sweep of the loop are unchanged: a solution is still a
// fixed point of one nonlinear sweep, whatever produced the iterate.
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <deque>
#include <vector>
#include "base/parallel.hpp"

namespace cmg {

// The serial step's sums: over fixed chunks on all threads (parallel_sums), the same bits on any
// thread count. A distributed solve sums node values exactly over its ranks instead
// (bindings/bind_anderson.cpp).
struct ChunkSums {
  template <int M, class F>
  std::array<double, M> sums(Index n, int m, F&& f) const { return parallel_sums<M>(n, m, f); }
};

// Sums: how the step's dot products are summed (sums<M>(n, m, f): f(k, s) adds entry k's terms of
// the m sums to s[0..m)); every entry k is visited once, as the step also writes its slots there.
template <class Sums = ChunkSums>
class SettledAnderson {
 public:
  SettledAnderson() = default;
  explicit SettledAnderson(Sums sums) : sums_(std::move(sums)) {}

  static constexpr int kDepth = 3;  // cycles mixed (a fixed internal choice; 2-5 behave alike)

  void reset() {
    hist_.clear();
    last_ = -1;
    accelerated_ = false;
  }
  std::size_t memory_bytes() const {
    std::size_t s = 0;
    for (const Slot& q : slot_) s += sizeof(double) * (q.x.capacity() + q.g.capacity());
    return s;
  }
  bool last_accelerated() const { return accelerated_; }
  const Sums& sums() const { return sums_; }
  // Every slot sized for n entries now, their pages touched here and not in the cycles where the
  // history first fills (a kept workspace's first solve: a first touch costs up to ~50 us
  // a page on this project's VM). Every entry is written before it is read: no bit changes.
  void reserve(Index n) {
    slot_.resize(kDepth);
    for (Slot& q : slot_) { q.x.resize(n); q.g.resize(n); }
  }

  // The rule around step() for Algorithm 2's settled cycles, the serial step's and the ranks' alike
  // (steps/monotone_mg_step.hpp says why): without a sliding node nothing is mixed and the history
  // goes; a new truncation (state_changed) restarts the history unless the plain cycle's step
  // change_norm() = |G(x) - x|_A is no smaller than best_step, the smallest step of the solve so
  // far. Where the state changed and the mixed iterate was refused, gx is G(x) bit for bit, and
  // keep_change() may take what change_norm() computed (A (G(x) - x)) into A u. Returns that step
  // there, else -1 (the caller measures it).
  template <class ChangeNorm, class Admit, class KeepChange>
  double settle(const double* x, double* gx, Index n, bool any_sliding, bool state_changed, double best_step,
                ChangeNorm&& change_norm, Admit&& admit, KeepChange&& keep_change) {
    if (!any_sliding) {
      reset();
      return -1;
    }
    const double change = state_changed ? change_norm() : 0.0;
    const bool restart = state_changed && change < best_step;
    const bool mixed = step(x, gx, n, admit, restart);
    if (state_changed && !mixed) {
      keep_change();
      return change;
    }
    return -1;
  }

  // x: the iterate before the cycle; gx: the cycle's result G(x), overwritten with the mixed
  // iterate when `admit(candidate, plain)` accepts it (it may adjust the candidate; plain is G(x)).
  // Returns whether it did. restart: forget the history first (the caller's contact state changed).
  //
  // Storage (docs/dev/decisions/0011-memory-release.md): kDepth slots of two fine vectors, no more. A
  // slot holds either a pair of the history (dx = x - x', dg = g - g', g = G(x) - x) or the last iterate
  // (x', G(x')): the new pair is formed in place over the last iterate, and the next last iterate takes
  // the slot of the oldest pair, which the next step would drop (the textbook layout held the history,
  // x', g', g and a candidate: 10 fine vectors, 80 bytes a dof in 2D). Passes: one forms the new pair
  // with every dot product of the least-squares problem (the Gram entries of older pairs are kept: the
  // pairs do not change), one forms the candidate in gx and keeps G(x) as the next last iterate (19
  // vector reads and writes a step against some 40 in the textbook layout). Every value is the one of the textbook layout bit
  // for bit: g' = G(x') - x' is formed again from the same operands, and the sums run over the same
  // chunks in the same order (parallel_sums).
  // x and gx hold n entries; admit(double* candidate, const double* plain).
  template <class Admit>
  bool step(const double* x, double* gx, Index n, Admit&& admit, bool restart = false) {
    if (restart) {  // this cycle's pair spans two states: the history starts with the next one
      reset();
      return false;
    }
    double gnorm;
    if (last_ >= 0) {
      Slot& q = slot_[last_];
      const int h = (int)hist_.size();  // older pairs, oldest first
      const double* dg_old[kDepth] = {};
      for (int i = 0; i < h; ++i) dg_old[i] = slot_[hist_[i]].g.data();
      // sums: 0 |g|^2; 1..h+1 dg_i . g (oldest first, the new pair last); h+2..2h+2 dg_new . dg_j
      const auto s = sums_.template sums<2 * kDepth + 2>(n, 2 * h + 3, [&](Index k, double* acc) {
        const double g = gx[k] - x[k], g_last = q.g[k] - q.x[k];
        const double dx = x[k] - q.x[k], dg = g - g_last;
        q.x[k] = dx;
        q.g[k] = dg;
        acc[0] += g * g;
        for (int i = 0; i < h; ++i) acc[1 + i] += dg_old[i][k] * g;
        acc[1 + h] += dg * g;
        for (int j = 0; j < h; ++j) acc[2 + h + j] += dg * dg_old[j][k];
        acc[2 + 2 * h] += dg * dg;
      });
      gnorm = s[0];
      if (accelerated_ && !(gnorm < last_gnorm_)) {  // the mixed step did not help: start over
        reset();
        keep_last(x, gx, n, nullptr);
      } else {
        const int nw = last_;
        for (int j = 0; j < h; ++j) gram_[nw][hist_[j]] = gram_[hist_[j]][nw] = s[2 + h + j];
        gram_[nw][nw] = s[2 + 2 * h];
        for (int i = 0; i <= h; ++i) rhs_[i] = s[1 + i];
        hist_.push_back(nw);
        last_ = -1;
      }
    } else {
      gnorm = 0;
      keep_last(x, gx, n, &gnorm);
    }
    last_gnorm_ = gnorm;
    accelerated_ = false;
    if (last_ >= 0) return false;  // no history, or it was just restarted: x, G(x) kept
    if (gnorm == 0) { keep_last(x, gx, n, nullptr); return false; }
    // gamma = argmin |g - dG gamma| (normal equations of a <= kDepth column least-squares problem,
    // solved by a rank-revealing decomposition: nearly dependent columns get no weight)
    const int m = (int)hist_.size();
    Eigen::MatrixXd M(m, m);
    Eigen::VectorXd rhs(m);
    for (int i = 0; i < m; ++i) {
      rhs[i] = rhs_[i];
      for (int j = 0; j < m; ++j) M(i, j) = gram_[hist_[i]][hist_[j]];
    }
    const Eigen::VectorXd gamma = M.completeOrthogonalDecomposition().solve(rhs);
    if (!gamma.allFinite()) { keep_last(x, gx, n, nullptr); return false; }
    // the candidate gx - sum_i gamma_i (dx_i + dg_i) in place; G(x) and x into the next last slot
    // (the oldest pair's when the history is full: read before written, entry by entry)
    const double* dx[kDepth] = {};
    const double* dg[kDepth] = {};
    for (int i = 0; i < m; ++i) { dx[i] = slot_[hist_[i]].x.data(); dg[i] = slot_[hist_[i]].g.data(); }
    const int to = next_last_slot(n);  // may take the oldest pair's slot (and may grow slot_: pointers above stay)
    Slot& q = slot_[to];
    parallel_for(n, [&](Index k) {
      double s = 0;
      for (int i = 0; i < m; ++i) s += gamma[i] * (dx[i][k] + dg[i][k]);
      q.x[k] = x[k];
      q.g[k] = gx[k];
      gx[k] -= s;
    });
    last_ = to;
    if (!admit(gx, static_cast<const double*>(q.g.data()))) {
      std::copy(q.g.begin(), q.g.end(), gx);
      return false;
    }
    accelerated_ = true;
    return true;
  }

 private:
  struct Slot {
    std::vector<double> x, g;
  };

  // The slot for the next last iterate: a free one, or the oldest pair's when the history is
  // full (the next step drops that pair anyway).
  int next_last_slot(Index n) {
    int to = -1;
    if ((int)hist_.size() == kDepth) {
      to = hist_.front();
      hist_.pop_front();
    } else {
      for (int c = 0; c < kDepth && to < 0; ++c)
        if (std::find(hist_.begin(), hist_.end(), c) == hist_.end()) to = c;
    }
    if ((int)slot_.size() <= to) slot_.resize(to + 1);
    slot_[to].x.resize(n);
    slot_[to].g.resize(n);
    return to;
  }

  // x and G(x) kept as the last iterate (and |G(x) - x|^2 into *gnorm when asked)
  void keep_last(const double* x, const double* gx, Index n, double* gnorm) {
    const int to = next_last_slot(n);
    Slot& q = slot_[to];
    if (gnorm) {
      *gnorm = sums_.template sums<1>(n, 1, [&](Index k, double* acc) {
        q.x[k] = x[k];
        q.g[k] = gx[k];
        const double g = gx[k] - x[k];
        acc[0] += g * g;
      })[0];
    } else {
      parallel_for(n, [&](Index k) { q.x[k] = x[k]; q.g[k] = gx[k]; });
    }
    last_ = to;
  }

  Sums sums_;
  std::vector<Slot> slot_;     // at most kDepth
  std::deque<int> hist_;       // slots holding pairs (dx, dg), oldest first
  int last_ = -1;              // slot holding (x', G(x')), or -1
  double gram_[kDepth][kDepth] = {};  // dg_a . dg_b by slots
  double rhs_[kDepth] = {};
  double last_gnorm_ = 0;
  bool accelerated_ = false;
};

}  // namespace cmg
