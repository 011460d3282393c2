// One cycle of (truncated) monotone multigrid for a contact law L -- Algorithm 2 of the paper for
// Coulomb, truncated monotone multigrid for frictionless and Tresca, a linear cycle for
// law::Linear: nu1 nonlinear Gauss-Seidel sweeps, the law's linearization at the smoothed iterate
// (truncation, bounds, friction gradient and Hessian), the coarse correction of that problem,
// nu2 sweeps back, and the acceptance of the new iterate. The Step of run_loop
// (solver/loop_solver.hpp). Its options' extensions are parts chosen once when the step is made:
// the smoother chain (smoother_chain.hpp: the upwind contact visit), the coarse correction (plain
// or projected_coarse_correction.hpp, then tied_correction.hpp), and the acceptance (Anderson
// mixing of settled Coulomb cycles, settled_anderson.hpp; the fused norm pass; the refusal rule of
// the Petrov-Galerkin coupling, petrov_galerkin_coupling.hpp).
#pragma once
#include "mg/cycle.hpp"
#include "base/monitor.hpp"
#include "steps/fine_iterate.hpp"
#include "steps/iterate_checks.hpp"
#include "steps/petrov_galerkin_coupling.hpp"
#include "steps/projected_coarse_correction.hpp"
#include "steps/settled_anderson.hpp"
#include "steps/smoother_chain.hpp"
#include "steps/tied_correction.hpp"

namespace cmg {

template <int d>
bool same_blocks(const std::vector<std::pair<Index, Mat<d>>>& a, const std::vector<std::pair<Index, Mat<d>>>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].first != b[k].first || a[k].second != b[k].second) return false;
  return true;
}

// What the coarse problem was built for: the truncation mask and the Hessian blocks of the fine
// diagonal. The hierarchy is updated when the next linearization differs.
template <int d>
struct BuiltLinearization {
  std::vector<std::uint8_t> mask;
  std::vector<std::pair<Index, Mat<d>>> hessian;

  // Brings the coarse levels H to the linearization (m, h) of the fine matrix A where it differs
  // from the one they were built for; returns whether they changed.
  bool update(GalerkinHierarchy<d>& H, const BlockMatrix<d>& A, const std::vector<std::uint8_t>& m,
              const std::vector<std::pair<Index, Mat<d>>>& h) {
    if (m == mask && same_blocks<d>(h, hessian)) return false;
    H.update(A, mask.data(), m.data(), hessian, h);
    mask = m;
    hessian = h;
    return true;
  }
};

// The fine vectors of a cycle beyond the iterate's own: r, u_old and the Anderson history (six
// more once a Coulomb solve slides). A solver keeps one across its solves (solver/contact_solver.hpp):
// a fresh step per solve allocated them again, 8 fine vectors of pages first touched inside the
// solve (at level 9, 37,000 minor faults a solve, ~2,900 a cycle; the Anderson slots' in its
// "norm" phase). On a VM a first touch of memory the guest had handed back costs up to ~50 us a
// page (0.4-0.5 s of system time a cycle while the history filled;
// docs/dev/decisions/0011-memory-release.md).

struct CycleWorkspace {
  std::vector<double> r, old;
  SettledAnderson<> anderson;
  std::size_t memory_bytes() const { return sizeof(double) * (r.capacity() + old.capacity()) + anderson.memory_bytes(); }
};

template <int d, class L>
class MonotoneMultigridStep {
 public:
  MonotoneMultigridStep(const ContactProblem<d>& P, GalerkinHierarchy<d>& H, CoarseCycle<d>& C, BuiltLinearization<d>& built,
                        FineIterate<d>& it, const SolverOptions& opt, const SweepOrder& fine_order = SweepOrder(),
                        TiedCorrection<d>* tied = nullptr, CycleWorkspace* work = nullptr)
      : P_(P), H_(H), C_(C), built_(built), it_(it), opt_(opt), tied_(tied), ws_(work ? *work : own_),
        r_(ws_.r), old_(ws_.old), anderson_(ws_.anderson), pg_(H, opt.petrov_galerkin && L::coarse_freezes_bound),
        smoother_(P, fine_order, opt.upwind_contact_sweep && L::coarse_freezes_bound),
        projected_(P, opt.projected_coarse_correction), checks_(P, it, fine_order, opt.omega) {
    const Index n = P.num_nodes() * d;
    mask_ = P.base_mask();
    r_.assign(n, 0.0); old_.assign(n, 0.0);  // of the same size: no new pages
    anderson_.reset();  // a kept workspace: its slots stay, the history of the last solve goes
    // A kept workspace takes all its Anderson slots before the first cycle of its first solve (the
    // solver's later solves need them all the same); a step's own workspace (the command line's
    // single solves) allocates them as the history fills, so a solve that never mixes does not
    // hold them at its peak.
    if constexpr (L::coarse_freezes_bound)
      if (work) anderson_.reserve(n);
    lo_.assign(P.num_contact() * d, -kInf); hi_.assign(P.num_contact() * d, kInf);  // bounds live at contact nodes only
  }

  // pre-smooth, linearize, coarse correction, post-smooth, accept
  double iterate(double* phases, bool& rebuilt) {
    PhaseClock pc(phases);
    std::vector<double>& u = it_.u;
    // on all threads: a plain vector copy was a serial pass over two fine vectors
    // (docs/dev/decisions/0003-coloured-gauss-seidel.md)
    parallel_for((Index)u.size(), [&](Index k) { old_[k] = u[k]; });
    smoother_.smooth(P_, u.data(), opt_.nu1, true, opt_.omega);
    pc.lap(Phase::PreSmooth);
    const bool bounded = linearize();
    pc.lap(Phase::Linearize);
    const bool state_changed = mask_ != built_.mask;
    rebuilt = update_coarse();
    pc.lap(Phase::CoarseUpdate);
    coarse_correction(bounded);
    pc.lap(Phase::CoarseCorrection);
    smoother_.smooth(P_, u.data(), opt_.nu2, false, opt_.post_omega());
    pc.lap(Phase::PostSmooth);
    const double step = accept(state_changed);
    pc.lap(Phase::Norm);
    return step;
  }

  // energy (with the Dirichlet offset and the friction term), the contact counts, the coupling's
  // state and the projected correction's step
  void record(CycleRecord& rec) const {
    checks_.record(rec);
    rec.petrov_galerkin = pg_.state();
    if (projected_.on()) rec.step_size = projected_.step_size();
  }

  double error_against(const double* ref) const { return checks_.error_against(ref); }

  // ||S(u) - u||_A for one forward nonlinear sweep S (u_old and r are free after a cycle)
  double sweep_change() { return checks_.sweep_change(old_, r_); }

 private:
  // The fine residual r = f - A u at the contact rows (the linearization reads them and adds the
  // friction gradient; every other row is formed as the coarse correction restricts it), then the
  // law's linearization at every contact node and the upwind order from it; returns whether any
  // bound is finite.
  bool linearize() {
    const BlockMatrix<d>& A = P_.matrix();
    for (Index c = 0; c < P_.num_contact(); ++c)
      A.residual_row(A.values.data(), it_.u.data(), P_.load().data(), P_.contact_node(c), kPrefetchValueRows,
                     r_.data() + d * P_.contact_node(c));
    hessian_.clear();
    coupling_.clear();
    bool bounded = false;
    if constexpr (L::has_contact) {
      const auto& base = P_.base_mask();
      for (Index c = 0; c < P_.num_contact(); ++c) {
        const Index i = P_.contact_node(c), k = i * d;
        Mat<d> Hc = Mat<d>::Zero();
        if (projected_.on()) projected_.set_bound(c, L::bound(P_.node(c), it_.u[k] >= P_.node(c).gap, r_[k]));  // r_ before the friction gradient
        if (linearize_node<L, d>(P_.node(c), it_.u.data() + k, r_.data() + k, mask_.data() + k, base.data() + k, lo_.data() + c * d,
                                 hi_.data() + c * d, &Hc, P_.matrix().block(P_.matrix().diag[i])))
          bounded = true;
        if (!Hc.isZero(0.0)) hessian_.emplace_back(i, Hc);
        if constexpr (L::coarse_freezes_bound)
          if (pg_.wanted() || smoother_.upwind().on()) {
            const Vec<d> w = bound_coupling<L, d>(P_.node(c), it_.u.data() + k, r_[k]);
            if (!w.isZero(0.0)) coupling_.emplace_back(i, w);
          }
      }
    }
    smoother_.upwind().order_from(P_, coupling_);
    return bounded;
  }

  // The coarse levels brought to this cycle's truncation and Hessian (where they changed), and the
  // top level to the sliding nodes' coupling where it is on: every cycle but the first, for the
  // sliding nodes of this one (waiting until the truncation settles left the settling cycles at the
  // frozen bound's slow rate: adaptive Hertz level 11, F = 2, 16 cycles settled only, 13 in every
  // cycle; docs/dev/decisions/0006-petrov-galerkin-coupling.md). Returns whether the levels changed.
  bool update_coarse() {
    const bool rebuilt = built_.update(H_, P_.matrix(), mask_, hessian_);
    pg_.bring(P_.matrix(), mask_.data(), coupling_, !first_);
    first_ = false;
    return rebuilt;
  }

  // u += P~ c, prolongated straight into the iterate (no fine vector for the correction); plain or
  // projected (where a bound is finite), then the tied correction of several bodies (their common
  // motions, no bounds). The fine residual of a row that is no contact row is formed as the
  // restriction reads it (BlockMatrix::residual_row): a residual pass wrote a fine vector that the
  // restriction read straight back (docs/dev/decisions/0013-fused-residual.md); the same sums, the
  // same bits.
  void coarse_correction(bool bounded) {
    std::vector<double>& u = it_.u;
    const BlockMatrix<d>& A = P_.matrix();
    const std::vector<double>& f = P_.load();
    const std::uint8_t* flags = P_.row_flags();
    const auto fine_residual = [&](Index i) {
      Vec<d> s;
      if (flags[i] & ContactProblem<d>::kContactRow) s = CVecMap<d>(r_.data() + d * i);
      else A.residual_row(A.values.data(), u.data(), f.data(), i, kPrefetchValueRows, s.data());
      return s;
    };
    if (projected_.on() && bounded) projected_.apply(P_, C_, opt_, fine_residual, mask_.data(), lo_, hi_, u, r_);
    else
      C_.correction_of(opt_, fine_residual, mask_.data(), NodeBounds{&P_.contact_nodes(), lo_.data(), hi_.data()}, bounded, u.data(),
                       P_.num_nodes(), true);
    if (tied_) tied_->apply(P_, opt_, u.data());
  }

  // The new iterate u = G(x) of x = u_old: mixed with the last cycles' (settled Coulomb cycles),
  // A u brought up to date with |u - u_old|_A measured in the same pass, and refused where the
  // Petrov-Galerkin coupling's rule says so (the iterate back to x). Returns the cycle's step.
  double accept(bool state_changed) {
    const double measured = mix(state_changed);
    const double step = measured >= 0 ? measured : update_and_measure();
    if (pg_.judge(step, best_step_)) return refuse();
    best_step_ = std::min(best_step_, step);
    return step;
  }

  // old_ = x (before the cycle), u = G(x): mix the cycles (settled_anderson.hpp). Returns the step
  // where the restart test has measured it already (A u then up to date), else -1.
  // A 3D sliding node's friction Hessian changes with its u_T in every cycle (a rebuild, but a
  // smooth change of the cycle map): only a change of the truncation may restart the history.
  // Without a sliding node no frozen bound enters the coarse problem: the plain cycle is left as it is.
  // A new truncation makes the old differences those of another affine map: the history restarts --
  // unless the plain cycle's step |G(x) - x|_A is no smaller than the smallest step of the solve so
  // far. Then the state changes because the cycle does not converge, and a restart at every change
  // would leave the slow modes unmixed for ever: adaptive Hertz level 11 at F = 8 wandered at 2e-3
  // for 200 cycles while a few nodes at the contact edge (nearly zero pressure and gap) switched
  // between free and sliding in every cycle; the cycle map there contracts by only 0.96 even with
  // the state fixed. The mixed iterate still takes the plain result's exact state (admit_mixed), and
  // a mixed step that does not help restarts.
  double mix(bool state_changed) {
    if constexpr (L::coarse_freezes_bound) {
      std::vector<double>& u = it_.u;
      // The restart test's A (G(x) - x) goes into r_ (free after the coarse correction): where the
      // mixed iterate is refused, u is G(x) bit for bit, and the update of A u adds r_ and takes the
      // test's |u - u_old|_A^2 (the same sums over the same chunks) instead of a second pass over
      // the matrix.
      return anderson_.settle(
          old_.data(), u.data(), (Index)u.size(), any_sliding(), state_changed, best_step_,
          [&] { return std::sqrt(std::max(change_norm_squared(old_, u, r_.data()), 0.0)); },
          [&](double* y, const double* plain) { return admit_mixed(y, plain); },
          [&] { parallel_for((Index)u.size(), [&](Index k) { it_.Au[k] += r_[k]; }); });
    }
    return -1;
  }

  // Au += A (u - u_old) and |u - u_old|_A in one pass (were four: difference, product, update,
  // dot); sums over fixed chunks of rows, so the same on any thread count
  double update_and_measure() {
    const BlockMatrix<d>& A = P_.matrix();
    const std::vector<double>& u = it_.u;
    constexpr Index ahead = kPrefetchValueRows;
    return std::sqrt(std::max(parallel_sum(A.rows, [&](Index i) {
      A.prefetch_ahead(i, u.data(), old_.data());  // two gathers a block (base/block_matrix.hpp says why)
      prefetch_row_values<d>(A.values.data(), A.indptr.data(), i, ahead, A.rows);
      Vec<d> y = Vec<d>::Zero();
      accumulate_block_differences<d>(A.values.data(), A.indices.data(), A.indptr[i], A.indptr[i + 1], u.data(), old_.data(), y.data());
      VecMap<d>(it_.Au.data() + d * i) += y;
      return (CVecMap<d>(u.data() + d * i) - CVecMap<d>(old_.data() + d * i)).dot(y);
    }), 0.0));
  }

  // The coupling's step was no smaller than every step before (judged in every cycle with the
  // coupling, a cycle with a state change too: a coupled cycle that grew by 1e10 while the state
  // changed went on and read as divergence): refused, the iterate back to x (feasible, as every
  // iterate), A u with it; the cycle map changes: the history starts again. The iterate did not
  // move: the cycle reports the smallest step before it, not the refused one (a refused step that
  // grew by 1e10 read as divergence and ended a solve the fallback saves).
  double refuse() {
    std::vector<double>& u = it_.u;
    anderson_.reset();
    parallel_for((Index)u.size(), [&](Index k) { u[k] = old_[k]; });
    P_.matrix().multiply(u.data(), it_.Au.data());
    return best_step_;
  }

  // |y - x|_A^2 with A (y - x) into z (one product with A; taken only where the truncation
  // changed). The same sums over the same chunks as update_and_measure.
  double change_norm_squared(const std::vector<double>& x, const std::vector<double>& y, double* z) const {
    const BlockMatrix<d>& A = P_.matrix();
    constexpr Index ahead = kPrefetchValueRows;
    return parallel_sum(A.rows, [&](Index i) {
      A.prefetch_ahead(i, y.data(), x.data());
      prefetch_row_values<d>(A.values.data(), A.indptr.data(), i, ahead, A.rows);
      Vec<d> w = Vec<d>::Zero();
      accumulate_block_differences<d>(A.values.data(), A.indices.data(), A.indptr[i], A.indptr[i + 1], y.data(), x.data(), w.data());
      VecMap<d>(z + d * i) = w;
      return (CVecMap<d>(y.data() + d * i) - CVecMap<d>(x.data() + d * i)).dot(w);
    });
  }

  bool any_sliding() const {
    for (Index c = 0; c < P_.num_contact(); ++c)
      if (node_state<d>(P_.node(c), it_.u.data() + P_.contact_node(c) * d) == NodeState::Slip) return true;
    return false;
  }

  // The mixed iterate y of the Anderson step takes the contact state of the plain cycle's result
  // u exactly (on the gap exactly g, sticking tangentials at their exact value), or is refused:
  // an inactive node it puts onto or past the obstacle, a sliding node it stops or turns.
  bool admit_mixed(double* y, const double* u) const {
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index k = P_.contact_node(c) * d;
      if (!admit_mixed_node<d>(P_.node(c), y + k, u + k)) return false;
    }
    return true;
  }

  const ContactProblem<d>& P_;
  GalerkinHierarchy<d>& H_;
  CoarseCycle<d>& C_;
  BuiltLinearization<d>& built_;
  FineIterate<d>& it_;
  SolverOptions opt_;
  TiedCorrection<d>* tied_;   // or nullptr
  CycleWorkspace own_;  // used when the caller keeps none (then freed with the step)
  CycleWorkspace& ws_;
  std::vector<std::uint8_t> mask_;
  // the iterate's own (u, A u) aside, a cycle needs only r and u_old
  // (docs/dev/decisions/0011-memory-release.md)
  std::vector<double>& r_;
  std::vector<double>& old_;
  std::vector<double> lo_, hi_;  // nc * d
  std::vector<std::pair<Index, Mat<d>>> hessian_;
  SettledAnderson<>& anderson_;
  PetrovGalerkinCoupling<d> pg_;  // declared after H_: clears its overlay of H_ first
  SmootherChain<d, L> smoother_;
  ProjectedCoarseCorrection<d, L> projected_;
  IterateChecks<d, L> checks_;
  std::vector<std::pair<Index, Vec<d>>> coupling_;  // sliding node -> w (bound_coupling), when wanted
  bool first_ = true;
  double best_step_ = kInf;  // the smallest |u^{k+1} - u^k|_A of this solve
};

}  // namespace cmg
