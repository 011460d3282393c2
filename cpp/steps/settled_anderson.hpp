// Anderson acceleration of the cycle map x -> G(x) once the contact state has settled.
//
// Why: Algorithm 2's coarse problem freezes the Coulomb bound F |s_n| of the sliding nodes (it does
// not see that a coarse correction changes their normal force, hence their friction force). Once
// the contact state stops changing, the cycle is a fixed affine map near the solution, and what
// the coarse problem misses shows as a slow linear contraction: 0.7 per cycle at F = 5 on uniform
// Hertz level 9, 0.8 at F = 40 on adaptive level 9 (issue 14). Anderson mixing of the last few
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
#include <deque>
#include <vector>
#include "parallel.hpp"

namespace cmg {

class SettledAnderson {
 public:
  static constexpr int kDepth = 3;  // cycles mixed (a fixed internal choice; 2-5 behave alike)

  void reset() {
    dx_.clear();
    dg_.clear();
    have_last_ = false;
    accelerated_ = false;
  }
  std::size_t memory_bytes() const {
    return sizeof(double) * (last_x_.capacity() + last_g_.capacity() + g_.capacity() + cand_.capacity() +
                             (dx_.size() + dg_.size()) * last_x_.size());
  }
  bool last_accelerated() const { return accelerated_; }

  // x: the iterate before the cycle; gx: the cycle's result G(x), overwritten with the mixed
  // iterate when `admit(candidate)` accepts it (it may adjust the candidate). Returns whether it did.
  // restart: forget the history first (the caller's contact state changed).
  template <class Admit>
  bool step(const std::vector<double>& x, std::vector<double>& gx, Admit&& admit, bool restart = false) {
    if (restart) {  // this cycle's pair spans two states: the history starts with the next one
      reset();
      return false;
    }
    const Index n = (Index)x.size();
    g_.resize(n);
    parallel_for(n, [&](Index k) { g_[k] = gx[k] - x[k]; });
    const double gnorm = parallel_sum(n, [&](Index k) { return g_[k] * g_[k]; });
    if (have_last_ && accelerated_ && !(gnorm < last_gnorm_)) {  // the mixed step did not help: start over
      reset();
    }
    if (have_last_) {
      std::vector<double> dx, dg;
      if ((int)dx_.size() == kDepth) {  // the oldest pair's storage takes the newest
        dx.swap(dx_.front()); dg.swap(dg_.front());
        dx_.pop_front(); dg_.pop_front();
      }
      dx.resize(n); dg.resize(n);
      parallel_for(n, [&](Index k) { dx[k] = x[k] - last_x_[k]; dg[k] = g_[k] - last_g_[k]; });
      dx_.push_back(std::move(dx));
      dg_.push_back(std::move(dg));
    }
    last_x_ = x;
    last_g_ = g_;
    last_gnorm_ = gnorm;
    have_last_ = true;
    accelerated_ = false;
    if (dx_.empty() || gnorm == 0) return false;
    // gamma = argmin |g - dG gamma| (normal equations of a <= kDepth column least-squares problem,
    // solved by a rank-revealing decomposition: nearly dependent columns get no weight)
    const int m = (int)dg_.size();
    Eigen::MatrixXd M(m, m);
    Eigen::VectorXd rhs(m);
    for (int i = 0; i < m; ++i) {
      rhs[i] = parallel_sum(n, [&](Index k) { return dg_[i][k] * g_[k]; });
      for (int j = 0; j <= i; ++j) M(i, j) = M(j, i) = parallel_sum(n, [&](Index k) { return dg_[i][k] * dg_[j][k]; });
    }
    const Eigen::VectorXd gamma = M.completeOrthogonalDecomposition().solve(rhs);
    if (!gamma.allFinite()) return false;
    cand_.assign(gx.begin(), gx.end());
    parallel_for(n, [&](Index k) {
      double s = 0;
      for (int i = 0; i < m; ++i) s += gamma[i] * (dx_[i][k] + dg_[i][k]);
      cand_[k] -= s;
    });
    if (!admit(cand_)) return false;
    gx.swap(cand_);
    accelerated_ = true;
    return true;
  }

 private:
  std::deque<std::vector<double>> dx_, dg_;
  std::vector<double> last_x_, last_g_, g_, cand_;
  double last_gnorm_ = 0;
  bool have_last_ = false, accelerated_ = false;
};

}  // namespace cmg
