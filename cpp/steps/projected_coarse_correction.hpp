// The projected coarse correction of Algorithm 2 (SolverOptions::projected_coarse_correction;
// docs/dev/decisions/0008-projected-coarse-correction.md): the coarse correction w with every bound
// but the inactive nodes' gap bounds (the sliding signs stay), projected node-wise onto
// u_n + w_n <= g, then u += a w with a the exact minimizer of the frozen-bound energy along w
// (frozen_line_search.hpp, TNNMG's): a descent step whatever w is, so the cycle stays monotone, and
// a node closing on the obstacle no longer throttles the coarse motions around it.
#pragma once
#include <limits>
#include <vector>
#include "mg/cycle.hpp"
#include "steps/frozen_line_search.hpp"

namespace cmg {

template <int d, class L>
class ProjectedCoarseCorrection {
 public:
  ProjectedCoarseCorrection(const ContactProblem<d>& P, bool on) : on_(on && L::has_contact) {
    if (!on_) return;
    w_.assign(P.num_nodes() * d, 0.0);
    bound_.assign(P.num_contact(), 0.0);
    hi_open_.assign(P.num_contact() * d, kInf);
  }

  bool on() const { return on_; }
  // the friction bound s_p of contact node c at the smoothed iterate, frozen for the line search
  void set_bound(Index c, double s) { bound_[c] = s; }
  // the last step length (NaN before the first)
  double step_size() const { return step_size_; }

  // u += a w for the fine residual `fine_residual`, the truncation `mask` and the bounds lo, hi of
  // the linearization (nc * d); `scratch` a fine vector free after the restriction (A w goes there).
  // The slope w^T (f - A u) is taken as w^T f - (A w)^T u (A symmetric): one product with A.
  template <class Row>
  void apply(const ContactProblem<d>& P, CoarseCycle<d>& C, const SolverOptions& opt, Row&& fine_residual,
             const std::uint8_t* mask, const std::vector<double>& lo, const std::vector<double>& hi, std::vector<double>& u,
             std::vector<double>& scratch) {
    const BlockMatrix<d>& A = P.matrix();
    const std::vector<double>& f = P.load();
    bool bounded = false;
    for (std::size_t k = 0; k < hi.size(); ++k) {
      hi_open_[k] = k % d == 0 ? kInf : hi[k];
      bounded = bounded || hi_open_[k] < kInf || lo[k] > -kInf;
    }
    C.correction_of(opt, fine_residual, mask, NodeBounds{&P.contact_nodes(), lo.data(), hi_open_.data()}, bounded,
                    w_.data(), P.num_nodes(), false);
    for (Index c = 0; c < P.num_contact(); ++c) {
      const Index k = P.contact_node(c) * d;
      const double room = P.node(c).gap - u[k];
      if (w_[k] > room) w_[k] = std::max(0.0, room);
    }
    A.multiply(w_.data(), scratch.data());
    const Index n = (Index)u.size();
    const double quad = parallel_sum(n, [&](Index k) { return w_[k] * scratch[k]; });
    const double slope = parallel_sum(n, [&](Index k) { return w_[k] * f[k] - scratch[k] * u[k]; });
    search_.clear(quad, slope);
    for (Index c = 0; c < P.num_contact(); ++c) {
      const Index k = P.contact_node(c) * d;
      const ContactNode p = P.node(c);
      const Vec<d> v = slip_increment<d>(p, u.data() + k);  // a load step's friction acts on the increment
      search_.add_friction(bound_[c], v.data(), w_.data() + k, p.free);
      search_.add_normal_limit(p.gap - u[k], w_[k]);
    }
    const double a = step_size_ = search_.minimize();
    parallel_for(n, [&](Index k) { u[k] += a * w_[k]; });
  }

 private:
  const bool on_;
  std::vector<double> w_, bound_, hi_open_;  // the direction, the frozen bounds, the upper bounds without the gaps
  FrozenLineSearch<d> search_;
  double step_size_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace cmg
