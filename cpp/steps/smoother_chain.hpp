// The fine smoothing of a monotone multigrid cycle: nu sweeps of the law's nonlinear Gauss-Seidel,
// each followed, where it is on, by one more visit of the contact nodes in their upwind order
// (upwind_contact_sweep.hpp). Chosen once per step, so the cycle reads "smooth".
#pragma once
#include "steps/nonlinear_gauss_seidel.hpp"
#include "steps/upwind_contact_sweep.hpp"

namespace cmg {

template <int d, class L>
class SmootherChain {
  using Smoother = NonlinearGaussSeidel<d, L>;

 public:
  SmootherChain(const ContactProblem<d>& P, const SweepOrder& order, bool upwind) : order_(order), upwind_(P, order, upwind) {}

  // `sweeps` sweeps in the direction `forward`, over-relaxed by omega
  void smooth(const ContactProblem<d>& P, double* u, int sweeps, bool forward, double omega) {
    for (int s = 0; s < sweeps; ++s) {
      Smoother::sweep(P, u, forward, order_, omega);
      if (upwind_.on()) upwind_.visit(P, u, omega);
    }
  }

  UpwindContactSweep<d, L>& upwind() { return upwind_; }
  const SweepOrder& order() const { return order_; }

 private:
  const SweepOrder& order_;  // of the fine nonlinear sweeps
  UpwindContactSweep<d, L> upwind_;
};

}  // namespace cmg
