// One step of truncated nonsmooth Newton multigrid (TNNMG; Graeser & Kornhuber, Graeser, Sack &
// Sander) for a contact law L:
//   1. nu1 nonlinear Gauss-Seidel sweeps of the law (the fine smoother of Algorithm 2);
//   2. the law's linearization at the smoothed iterate u: truncation of active normals and
//      sticking tangentials, friction gradient (and in 3D Hessian) of the sliding nodes with the
//      bound s_p of u frozen, exactly as Algorithm 2 builds its coarse problem;
//   3. the linear correction w of that truncated Newton system -- no coarse obstacles -- as chosen
//      by SolverOptions::linear: PCG preconditioned by the truncated linear cycle on the fine level
//      (the default: line sweeps where the matrix has lines, mg/truncated_linear_cycle.hpp and
//      mg/pcg.hpp), one such cycle, or one cycle of the coarse levels alone (w = P~ c: the fine
//      level then smoothed only by the nonlinear sweeps, as first built);
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
#include "mg/pcg.hpp"
#include "mg/truncated_linear_cycle.hpp"
#include "base/monitor.hpp"
#include "steps/fine_iterate.hpp"
#include "steps/frozen_line_search.hpp"
#include "steps/iterate_checks.hpp"
#include "steps/monotone_mg_step.hpp"
#include "steps/nonlinear_gauss_seidel.hpp"

namespace cmg {

// The PCG of the linear correction stops when its energy decrease per iteration has fallen to
// kLinearReduction^2 of the first (the correction's energy error down by about kLinearReduction:
// a tenth, what one V-cycle gives on the Hertz benchmark, so a good cycle costs two applications
// and a poor one -- nu -> 1/2, stretched elements -- as many as it needs, up to kMaxLinearIterations).
constexpr double kLinearReduction = 0.1;
constexpr int kMaxLinearIterations = 20;

template <int d, class L>
class TnnmgStep {
  using Smoother = NonlinearGaussSeidel<d, L>;

 public:
  TnnmgStep(const ContactProblem<d>& P, GalerkinHierarchy<d>& H, CoarseCycle<d>& C, BuiltLinearization<d>& built,
            FineIterate<d>& it, const SolverOptions& opt, TruncatedLinearCycle<d>& fine_cycle,
            const SweepOrder& fine_order = SweepOrder())
      : P_(P), H_(H), C_(C), built_(built), it_(it), opt_(opt), lin_(fine_cycle), order_(fine_order),
        checks_(P, it, fine_order, opt.omega) {
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
    for (int s = 0; s < opt_.nu1; ++s) Smoother::sweep(P_, u.data(), true, order_, opt_.omega);
    pc.lap(Phase::PreSmooth);
    A.multiply(u.data(), tmp_.data());  // A u of the smoothed iterate
    for (std::size_t k = 0; k < r_.size(); ++k) r_[k] = f[k] - tmp_[k];
    linearize();
    pc.lap(Phase::Linearize);
    rebuilt = built_.update(H_, A, mask_, hessian_);
    pc.lap(Phase::CoarseUpdate);
    linear_correction();
    step_ = line_search();
    decrease_ = frozen_decrease(u.data(), tmp_.data(), step_);
    for (std::size_t k = 0; k < u.size(); ++k) { u[k] += step_ * w_[k]; tmp_[k] += step_ * Aw_[k]; }
    pc.lap(Phase::CoarseCorrection);
    for (int s = 0; s < opt_.nu2; ++s) Smoother::sweep(P_, u.data(), false, order_, opt_.omega);
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
    rec.linear_iterations = linear_iterations_;
  }
  double error_against(const double* ref) const { return checks_.error_against(ref); }
  // old_ and tmp_ are free after a cycle
  double sweep_change() { return checks_.sweep_change(old_, tmp_); }

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
                           hi_.data() + k, &Hc, P_.matrix().block(P_.matrix().diag[i]));
      if (!Hc.isZero(0.0)) hessian_.emplace_back(i, Hc);
    }
  }

  // w_ for the truncated Newton system K w = M r (r_ with the friction gradient): see the top
  void linear_correction() {
    const Index n = (Index)w_.size();
    if (opt_.linear == LinearCorrection::Coarse) {
      C_.correction(opt_, r_.data(), mask_.data(), NodeBounds{}, false, w_.data(), P_.num_nodes(), false, opt_.lines);
      linear_iterations_ = 1;
      return;
    }
    lin_.set_linearization(mask_.data(), hessian_, opt_.lines);
    parallel_for(n, [&](Index k) { Aw_[k] = mask_[k] * r_[k]; });  // Aw_: the masked right-hand side here
    if (opt_.linear == LinearCorrection::Cycle) {
      lin_.apply(C_, opt_, Aw_.data(), w_.data());
      linear_iterations_ = 1;
      return;
    }
    const PcgReport rep = pcg(
        n, [&](const double* x, double* y) { lin_.multiply(x, y); },
        [&](const double* res, double* z) { lin_.apply(C_, opt_, res, z); }, Aw_.data(), w_.data(), kMaxLinearIterations,
        kLinearReduction);
    linear_iterations_ = rep.iterations;
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

  // J_s(u) - J_s(u + t w) with the frozen bounds, from the vectors u, A u, w, A w as the sum of its
  // parts -t w^T (A u - f) - t^2/2 w^T A w - sum_p s_p (|u_T + t w_T| - |u_T|): no cancellation of two
  // whole energies, whose round-off (1e-14 of the energy) exceeded the decrease once PCG had made the
  // steps small (the Dirichlet offset cancels)
  double frozen_decrease(const double* u, const double* Au, double t) const {
    const std::vector<double>& f = P_.load();
    double lin = 0, quad = 0;
    for (std::size_t k = 0; k < f.size(); ++k) { lin += w_[k] * (Au[k] - f[k]); quad += w_[k] * Aw_[k]; }
    double fr = 0;
    if constexpr (L::has_contact)
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index k = P_.contact_node(c) * d;
        if (s_[c] == 0) continue;
        Vec<d> v = CVecMap<d>(u + k) + t * CVecMap<d>(w_.data() + k);
        fr += s_[c] * (free_tangential_norm<d>(v.data(), P_.node(c).free) - free_tangential_norm<d>(u + k, P_.node(c).free));
      }
    return -(t * lin + 0.5 * t * t * quad + fr);
  }

  const ContactProblem<d>& P_;
  GalerkinHierarchy<d>& H_;
  CoarseCycle<d>& C_;
  BuiltLinearization<d>& built_;
  FineIterate<d>& it_;
  SolverOptions opt_;
  TruncatedLinearCycle<d>& lin_;
  const SweepOrder& order_;  // of the fine nonlinear sweeps
  IterateChecks<d, L> checks_;  // the record's energy and counts, the error, the sweep check
  FrozenLineSearch<d> ls_;
  std::vector<std::uint8_t> mask_;
  std::vector<double> r_, w_, Aw_, old_, tmp_, lo_, hi_, s_;
  std::vector<std::pair<Index, Mat<d>>> hessian_;
  double step_ = 0, decrease_ = 0;
  int linear_iterations_ = 0;
};

}  // namespace cmg
