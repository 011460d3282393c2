// One step of truncated nonsmooth Newton multigrid (TNNMG; Graeser & Kornhuber, Graeser, Sack &
// Sander) for a contact law L:
//   1. nu1 nonlinear Gauss-Seidel sweeps of the law (the fine smoother of Algorithm 2);
//   2. the law's linearization at the smoothed iterate u: truncation of active normals and
//      sticking tangentials, friction gradient (and in 3D Hessian) of the sliding nodes with the
//      bound s_p of u frozen, exactly as Algorithm 2 builds its coarse problem;
//   3. ONE linear cycle of the coarse levels for that truncated Newton system -- no coarse
//      obstacles; the correction w = P~ c;
//   4. w projected node-wise onto the admissible set (u_n + w_n <= g_p at inactive nodes);
//   5. the exact line search of the frozen-bound energy along w (frozen_line_search.hpp);
//   6. nu2 sweeps.
// What each part minimizes: the sweeps minimize the law's energy node by node (exactly, with the
// Coulomb bound lagged per node as in Algorithm 2); steps 2-5 decrease the frozen-bound energy
//   J_s(v) = 1/2 v^T A v - f^T v + sum_p s_p |v_T|,  v_n <= g,  s_p frozen at the smoothed u
// (for Coulomb s_p = F_p |s_n(u)| at nodes in contact, 0 elsewhere: a Tresca energy, convex, so
// the line search has one minimizer and never raises J_s). For frictionless and Tresca J_s is
// the energy itself and every step decreases it; for Coulomb the bound moves between steps, which
// is why Coulomb's functional is not minimized globally. The step records the decrease of J_s by
// steps 3-5, computed from the vectors (not from the 1D formula), and the step length.
#pragma once
#include "mg/cycle.hpp"
#include "solver/monitor.hpp"
#include "steps/fine_iterate.hpp"
#include "steps/frozen_line_search.hpp"
#include "steps/monotone_mg_step.hpp"
#include "steps/nonlinear_gauss_seidel.hpp"

namespace cmg {

template <int d, class L>
class TnnmgStep {
  using Smoother = NonlinearGaussSeidel<d, L>;

 public:
  TnnmgStep(const ContactProblem<d>& P, GalerkinHierarchy<d>& H, CoarseCycle<d>& C, BuiltLinearization<d>& built,
            FineIterate<d>& it, const CycleOptions& opt, const SweepOrder& fine_order = SweepOrder())
      : P_(P), H_(H), C_(C), built_(built), it_(it), opt_(opt), order_(fine_order), checks_(P, H, C, built, it, opt, fine_order) {
    const Index n = P.num_nodes() * d;
    mask_ = P.base_mask();
    r_.assign(n, 0.0); w_.assign(n, 0.0); Aw_.assign(n, 0.0); old_.assign(n, 0.0); tmp_.assign(n, 0.0);
    lo_.assign(n, -kInf); hi_.assign(n, kInf);
    s_.assign(P.num_contact(), 0.0);
  }

  double iterate(double* phases, bool& rebuilt) {
    PhaseClock pc(phases);
    std::vector<double>& u = it_.u;
    const BlockMatrix<d>& A = P_.matrix();
    const std::vector<double>& f = P_.load();
    old_ = u;
    for (int s = 0; s < opt_.nu1; ++s) Smoother::sweep(P_, u.data(), true, order_);
    pc.lap(Phase::PreSmooth);
    A.multiply(u.data(), tmp_.data());  // A u of the smoothed iterate
    for (std::size_t k = 0; k < r_.size(); ++k) r_[k] = f[k] - tmp_[k];
    linearize();
    pc.lap(Phase::Linearize);
    rebuilt = mask_ != built_.mask || !same_blocks<d>(hessian_, built_.hessian);
    if (rebuilt) {
      H_.update(A, built_.mask.data(), mask_.data(), built_.hessian, hessian_);
      built_.mask = mask_;
      built_.hessian = hessian_;
    }
    pc.lap(Phase::CoarseUpdate);
    C_.correction(opt_, r_.data(), mask_.data(), NodeBounds{}, false, w_.data(), P_.num_nodes());
    const double e_before = frozen_energy(u.data(), tmp_.data());
    step_ = line_search();
    for (std::size_t k = 0; k < u.size(); ++k) { u[k] += step_ * w_[k]; tmp_[k] += step_ * Aw_[k]; }
    decrease_ = e_before - frozen_energy(u.data(), tmp_.data());
    pc.lap(Phase::CoarseCorrection);
    for (int s = 0; s < opt_.nu2; ++s) Smoother::sweep(P_, u.data(), false, order_);
    pc.lap(Phase::PostSmooth);
    for (std::size_t k = 0; k < u.size(); ++k) old_[k] = u[k] - old_[k];
    A.multiply(old_.data(), tmp_.data());
    double e = 0;
    for (std::size_t k = 0; k < u.size(); ++k) { e += old_[k] * tmp_[k]; it_.Au[k] += tmp_[k]; }
    pc.lap(Phase::Norm);
    return std::sqrt(std::max(e, 0.0));
  }

  void record(CycleRecord& rec) const {
    checks_.record(rec);
    rec.step_size = step_;
    rec.frozen_decrease = decrease_;
  }
  double error_against(const double* ref) { return checks_.error_against(ref); }
  double sweep_change() { return checks_.sweep_change(); }

 private:
  // mask, bounds, friction gradient into r_, Hessian blocks, and the frozen bounds s_
  void linearize() {
    hessian_.clear();
    if constexpr (!L::has_contact) return;
    const auto& base = P_.base_mask();
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index i = P_.contact_node(c), k = i * d;
      const ContactNode p = P_.node(c);
      s_[c] = L::bound(p, it_.u[k] >= p.gap, r_[k]);
      Mat<d> Hc = Mat<d>::Zero();
      linearize_node<L, d>(p, it_.u.data() + k, r_.data() + k, mask_.data() + k, base.data() + k, lo_.data() + k,
                           hi_.data() + k, &Hc);
      if (!Hc.isZero(0.0)) hessian_.emplace_back(i, Hc);
    }
  }

  // Projects w onto {u_n + w_n <= g} node-wise, then the exact step length along it (w_, Aw_ set).
  double line_search() {
    const std::vector<double>& u = it_.u;
    if constexpr (L::has_contact)
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index k = P_.contact_node(c) * d;
        const double room = P_.node(c).gap - u[k];
        if (w_[k] > room) w_[k] = std::max(0.0, room);
      }
    P_.matrix().multiply(w_.data(), Aw_.data());
    // slope = w^T (f - A u) with the unmodified residual: r_ holds the friction gradient too
    const std::vector<double>& f = P_.load();
    double quad = 0, slope = 0;
    for (std::size_t k = 0; k < u.size(); ++k) { quad += w_[k] * Aw_[k]; slope += w_[k] * (f[k] - tmp_[k]); }
    ls_.clear(quad, slope);
    if constexpr (L::has_contact)
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index k = P_.contact_node(c) * d;
        const ContactNode p = P_.node(c);
        ls_.add_friction(s_[c], u.data() + k, w_.data() + k, p.free);
        ls_.add_normal_limit(p.gap - u[k], w_[k]);
      }
    return ls_.minimize();
  }

  // J_s(v) with the frozen bounds, from v and A v (Dirichlet offset left out: it cancels)
  double frozen_energy(const double* v, const double* Av) const {
    const std::vector<double>& f = P_.load();
    double e = 0;
    for (std::size_t k = 0; k < f.size(); ++k) e += 0.5 * v[k] * Av[k] - f[k] * v[k];
    if constexpr (L::has_contact)
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index k = P_.contact_node(c) * d;
        e += s_[c] * free_tangential_norm<d>(v + k, P_.node(c).free);
      }
    return e;
  }

  const ContactProblem<d>& P_;
  GalerkinHierarchy<d>& H_;
  CoarseCycle<d>& C_;
  BuiltLinearization<d>& built_;
  FineIterate<d>& it_;
  CycleOptions opt_;
  // energy record, error and the sweep check are the monotone step's (same iterate, same law)
  const SweepOrder& order_;  // of the fine nonlinear sweeps
  MonotoneMultigridStep<d, L> checks_;
  FrozenLineSearch<d> ls_;
  std::vector<std::uint8_t> mask_;
  std::vector<double> r_, w_, Aw_, old_, tmp_, lo_, hi_, s_;
  std::vector<std::pair<Index, Mat<d>>> hessian_;
  double step_ = 0, decrease_ = 0;
};

}  // namespace cmg
