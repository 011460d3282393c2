// Algorithm 1 of the paper: u^k solves the Tresca problem with s_p = F_p |s_n(u^{k-1})|,
// warm-started from u^{k-1}, each by the loop of truncated monotone multigrid steps; the outer
// iteration stops when the normal stresses no longer change (relative fixed_point_tol).
#pragma once
#include "solver/loop_solver.hpp"
#include "steps/monotone_mg_step.hpp"

namespace cmg {

template <int d>
class FixedPointStep {
 public:
  FixedPointStep(ContactProblem<d>& P, MonotoneMultigridStep<d, law::Tresca>& tresca, FineIterate<d>& it)
      : P_(P), tresca_(tresca), it_(it), sn_prev_(P.num_contact()), sn_(P.num_contact()) {
    normal_stress(sn_prev_);
  }

  // One outer iteration k: returns false when its Tresca solve failed (R.status says why).
  bool iterate(int k, const SolverOptions& opt, const double* reference, Monitor& mon, SolveResult& R) {
    for (Index c = 0; c < P_.num_contact(); ++c) P_.set_bound(c, P_.coefficient(c) * std::abs(sn_prev_[c]));
    R.outer_iterations = k;
    if (!run_loop(tresca_, opt, reference, mon, R, k)) {
      R.status = "the Tresca solve of outer iteration " + std::to_string(k) + " did not converge: " + R.status;
      R.converged = false;
      return false;
    }
    normal_stress(sn_);
    double diff = 0, nrm = 0;
    for (Index c = 0; c < P_.num_contact(); ++c) { diff += (sn_[c] - sn_prev_[c]) * (sn_[c] - sn_prev_[c]); nrm += sn_[c] * sn_[c]; }
    change_ = std::sqrt(diff);
    norm_ = std::sqrt(nrm);
    sn_prev_ = sn_;
    return true;
  }
  bool fixed(double tol) const { return change_ <= tol * norm_; }
  double relative_change() const { return norm_ > 0 ? change_ / norm_ : change_; }

 private:
  // s_n = (A u - f)_n at the contact nodes, from the tracked A u
  void normal_stress(std::vector<double>& sn) const {
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index k = P_.contact_node(c) * d;
      sn[c] = it_.Au[k] - P_.load()[k];
    }
  }

  ContactProblem<d>& P_;
  MonotoneMultigridStep<d, law::Tresca>& tresca_;
  FineIterate<d>& it_;
  std::vector<double> sn_prev_, sn_;
  double change_ = 0, norm_ = 0;
};

// The outer loop of Algorithm 1.
template <int d>
void run_fixed_point(FixedPointStep<d>& step, const SolverOptions& opt, const double* reference, Monitor& mon, SolveResult& R) {
  for (int k = 1; k <= opt.fixed_point_max; ++k) {
    if (!step.iterate(k, opt, reference, mon, R)) return;
    R.outer_changes.push_back(step.relative_change());
    if (step.fixed(opt.fixed_point_tol)) {
      R.converged = true;
      R.status = "converged";
      return;
    }
    const int w = opt.fixed_point_stall_window;
    if (w > 0 && k > w && R.outer_changes[k - 1] >= R.outer_changes[k - 1 - w]) {
      R.converged = false;
      R.status = "no convergence of the fixed-point iteration: the relative change of s_n (" +
                 fmt3(R.outer_changes[k - 1]) + " at outer iteration " + std::to_string(k) + ") did not fall below " +
                 "the one of " + std::to_string(w) + " iterations before (" + fmt3(R.outer_changes[k - 1 - w]) + ")";
      return;
    }
  }
  R.converged = false;
  R.status = "no convergence of the fixed-point iteration in " + std::to_string(opt.fixed_point_max) + " outer iterations";
}

}  // namespace cmg
