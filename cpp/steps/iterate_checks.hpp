// What the loop (solver/loop_solver.hpp) asks of a step about its iterate, the same for every step
// of a law: the energy (with the Dirichlet offset and the friction term) and the contact counts of
// a cycle's record, the error ||u - u*||_A against a reference, and the change ||S(u) - u||_A of one
// more forward nonlinear sweep S (the confirmation of a stop). One object, so that a step is the
// cycle alone and TNNMG need not carry a monotone step for these.
#pragma once
#include <cmath>
#include <limits>
#include <vector>
#include "base/solve_result.hpp"
#include "steps/fine_iterate.hpp"
#include "steps/nonlinear_gauss_seidel.hpp"

namespace cmg {

template <int d, class L>
class IterateChecks {
  using Smoother = NonlinearGaussSeidel<d, L>;

 public:
  // omega: the over-relaxation of the sweep that confirms a stop (the pre-smoothing's)
  IterateChecks(const ContactProblem<d>& P, FineIterate<d>& it, const SweepOrder& order, double omega)
      : P_(P), it_(it), order_(order), omega_(omega) {}

  // energy, contact counts and ||u||_A of the iterate into rec
  void record(CycleRecord& rec) const {
    const std::vector<double>& u = it_.u, &Au = it_.Au, &f = P_.load();
    // over fixed chunks on all threads (was serial: three fine vectors read once a cycle)
    double e = P_.energy_offset() + parallel_sum((Index)u.size(), [&](Index k) { return 0.5 * u[k] * Au[k] - f[k] * u[k]; });
    if constexpr (L::has_contact)
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index k = P_.contact_node(c) * d;
        const ContactNode p = P_.node(c);
        e += friction_energy<L, d>(p, u.data() + k, f[k] - Au[k]);
        const NodeState s = node_state<d>(p, u.data() + k);
        if (s != NodeState::Free) { ++rec.active; (s == NodeState::Stick ? rec.stick : rec.slip)++; }
      }
    rec.energy = e;
    rec.solution_norm = std::sqrt(std::max(parallel_sum((Index)u.size(), [&](Index k) { return u[k] * Au[k]; }), 0.0));
  }

  // ||u - u*||_A with u* canonical (taken to the contact frames first)
  double error_against(const double* ref) const {
    const std::vector<double>& u = it_.u;
    const auto& fixed = P_.fixed();
    std::vector<double> w(ref, ref + u.size()), tmp(u.size());  // diagnostics: scratch of its own
    P_.basis().to_local(w.data());
    for (std::size_t k = 0; k < u.size(); ++k) w[k] = fixed[k] ? 0.0 : u[k] - w[k];
    P_.matrix().multiply(w.data(), tmp.data());
    double e = 0;
    for (std::size_t k = 0; k < u.size(); ++k) e += w[k] * tmp[k];
    return std::sqrt(std::max(e, 0.0));
  }

  // ||S(u) - u||_A for one forward sweep S; u is left as it was. `a` and `b`: the caller's fine
  // vectors that hold nothing the next cycle needs (no new fine vector at a stop). NaN for linear
  // problems.
  double sweep_change(std::vector<double>& a, std::vector<double>& b) {
    if constexpr (!L::has_contact) return std::numeric_limits<double>::quiet_NaN();
    std::vector<double>& u = it_.u;
    a = u;
    Smoother::sweep(P_, u.data(), true, order_, omega_);
    for (std::size_t k = 0; k < u.size(); ++k) std::swap(u[k], a[k]);
    for (std::size_t k = 0; k < u.size(); ++k) a[k] -= u[k];
    P_.matrix().multiply(a.data(), b.data());
    double e = 0;
    for (std::size_t k = 0; k < u.size(); ++k) e += a[k] * b[k];
    return std::sqrt(std::max(e, 0.0));
  }

 private:
  const ContactProblem<d>& P_;
  FineIterate<d>& it_;
  const SweepOrder& order_;  // of the fine nonlinear sweeps
  const double omega_;
};

}  // namespace cmg
