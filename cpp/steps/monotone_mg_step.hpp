// One cycle of (truncated) monotone multigrid for a contact law L -- Algorithm 2 of the paper for
// Coulomb, truncated monotone multigrid for frictionless and Tresca, a linear cycle for
// law::Linear: nu1 nonlinear Gauss-Seidel sweeps, the law's linearization at the smoothed iterate
// (truncation, bounds, friction gradient and Hessian), the coarse correction of that problem,
// nu2 sweeps back. The Step of run_loop (solver/loop_solver.hpp).
#pragma once
#include "mg/cycle.hpp"
#include "solver/monitor.hpp"
#include "steps/fine_iterate.hpp"
#include "steps/frozen_line_search.hpp"
#include "steps/nonlinear_gauss_seidel.hpp"
#include "steps/tied_correction.hpp"
#include "steps/settled_anderson.hpp"
#include "steps/petrov_galerkin_coupling.hpp"
#include "steps/upwind_contact_sweep.hpp"

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
  using Smoother = NonlinearGaussSeidel<d, L>;

 public:
  MonotoneMultigridStep(const ContactProblem<d>& P, GalerkinHierarchy<d>& H, CoarseCycle<d>& C, BuiltLinearization<d>& built,
                        FineIterate<d>& it, const SolverOptions& opt, const SweepOrder& fine_order = SweepOrder(),
                        TiedCorrection<d>* tied = nullptr, CycleWorkspace* work = nullptr)
      : P_(P), H_(H), C_(C), built_(built), it_(it), opt_(opt), order_(fine_order), tied_(tied), ws_(work ? *work : own_),
        r_(ws_.r), old_(ws_.old), anderson_(ws_.anderson), pg_(H, opt.petrov_galerkin && L::coarse_freezes_bound),
        upwind_(P, fine_order, opt.upwind_contact_sweep && L::coarse_freezes_bound),
        projected_(opt.projected_coarse_correction && L::has_contact) {
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
    if (projected_) {
      w_.assign(n, 0.0);
      bound_.assign(P.num_contact(), 0.0);
      hi_open_.assign(P.num_contact() * d, kInf);
    }
  }

  double iterate(double* phases, bool& rebuilt) {
    PhaseClock pc(phases);
    std::vector<double>& u = it_.u;
    const BlockMatrix<d>& A = P_.matrix();
    const std::vector<double>& f = P_.load();
    // on all threads: a plain vector copy was a serial pass over two fine vectors
    // (docs/dev/decisions/0003-coloured-gauss-seidel.md)
    parallel_for((Index)u.size(), [&](Index k) { old_[k] = u[k]; });
    for (int s = 0; s < opt_.nu1; ++s) {
      Smoother::sweep(P_, u.data(), true, order_);
      if (upwind_.on()) upwind_.visit(P_, u.data());
    }
    pc.lap(Phase::PreSmooth);
    // The fine residual r = f - A u: at the contact rows now (the linearization reads them and adds the
    // friction gradient), every other row where the coarse correction restricts it, formed as it is
    // restricted (BlockMatrix::residual_row): a residual pass wrote a fine vector that the restriction
    // read straight back (docs/dev/decisions/0013-fused-residual.md). The same sums: the same bits as a
    // residual pass.
    constexpr Index ahead = kPrefetchValueRows;
    for (Index c = 0; c < P_.num_contact(); ++c)
      A.residual_row(A.values.data(), u.data(), f.data(), P_.contact_node(c), ahead, r_.data() + d * P_.contact_node(c));
    const bool bounded = linearize();
    upwind_.order_from(P_, coupling_);
    pc.lap(Phase::Linearize);
    const bool state_changed = mask_ != built_.mask;
    rebuilt = built_.update(H_, A, mask_, hessian_);
    // every cycle but the first, for the sliding nodes of this one: waiting until the truncation settles
    // left the settling cycles at the frozen bound's slow rate (adaptive Hertz level 11, F = 2: 16
    // cycles settled only, 13 in every cycle; docs/dev/decisions/0006-petrov-galerkin-coupling.md)
    pg_.bring(A, mask_.data(), coupling_, !first_);
    first_ = false;
    pc.lap(Phase::CoarseUpdate);
    const std::uint8_t* flags = P_.row_flags();
    const auto fine_residual = [&](Index i) {
      Vec<d> s;
      if (flags[i] & ContactProblem<d>::kContactRow) s = CVecMap<d>(r_.data() + d * i);
      else A.residual_row(A.values.data(), u.data(), f.data(), i, ahead, s.data());
      return s;
    };
    // u += P~ c: prolongated straight into the iterate (no fine vector for the correction)
    if (projected_ && bounded) projected_correction(fine_residual);
    else
      C_.correction_of(opt_, fine_residual, mask_.data(), NodeBounds{&P_.contact_nodes(), lo_.data(), hi_.data()}, bounded, u.data(),
                       P_.num_nodes(), true);
    if (tied_) tied_->apply(P_, opt_, u.data());  // two bodies: the common motions, no bounds
    pc.lap(Phase::CoarseCorrection);
    for (int s = 0; s < opt_.nu2; ++s) {
      Smoother::sweep(P_, u.data(), false, order_, opt_.omega_post);
      if (upwind_.on()) upwind_.visit(P_, u.data());
    }
    pc.lap(Phase::PostSmooth);
    double measured = -1;  // the step, when the restart test has measured it already
    if constexpr (L::coarse_freezes_bound) {
      // old_ = x (before the cycle), u = G(x): mix the cycles (settled_anderson.hpp).
      // A 3D sliding node's friction Hessian changes with its u_T in every cycle (a rebuild, but
      // a smooth change of the cycle map): only a change of the truncation may restart the history.
      // Without a sliding node no frozen bound enters the coarse problem: the plain cycle is left as it is.
      // A new truncation makes the old differences those of another affine map: the history
      // restarts -- unless the plain cycle's step |G(x) - x|_A is no smaller than the smallest step
      // of the solve so far. Then the state changes because the cycle does not converge, and a
      // restart at every change would leave the slow modes unmixed for ever: adaptive Hertz level
      // 11 at F = 8 wandered at 2e-3 for 200 cycles while a few nodes at the contact edge (nearly
      // zero pressure and gap) switched between free and sliding in every cycle; the cycle map
      // there contracts by only 0.96 even with the state fixed. The mixed iterate still takes the
      // plain result's exact state (admit_mixed), and a mixed step that does not help restarts.
      if (!any_sliding()) anderson_.reset();
      else {
        // The restart test's A (G(x) - x) goes into r_ (free after the coarse correction): where the
        // mixed iterate is refused, u is G(x) bit for bit, and the update of A u below adds r_ and
        // takes the test's |u - u_old|_A^2 (the same sums over the same chunks) instead of a
        // second pass over the matrix.
        double e_change = 0;
        if (state_changed) e_change = change_norm_squared(old_, u, r_.data());
        const bool restart = state_changed && std::sqrt(std::max(e_change, 0.0)) < best_step_;
        const bool mixed =
            anderson_.step(old_.data(), u.data(), (Index)u.size(), [&](double* y, const double* plain) { return admit_mixed(y, plain); }, restart);
        if (state_changed && !mixed) {
          parallel_for((Index)u.size(), [&](Index k) { it_.Au[k] += r_[k]; });
          measured = std::sqrt(std::max(e_change, 0.0));
        }
      }
    }
    // Au += A (u - u_old) and e = |u - u_old|_A^2 in one pass (were four: difference, product,
    // update, dot); sums over fixed chunks of rows, so the same on any thread count
    const double step = measured >= 0 ? measured : std::sqrt(std::max(parallel_sum(A.rows, [&](Index i) {
      A.prefetch_ahead(i, u.data(), old_.data());  // two gathers a block (base/block_matrix.hpp says why)
      prefetch_row_values<d>(A.values.data(), A.indptr.data(), i, ahead, A.rows);
      Vec<d> y = Vec<d>::Zero();
      accumulate_block_differences<d>(A.values.data(), A.indices.data(), A.indptr[i], A.indptr[i + 1], u.data(), old_.data(), y.data());
      VecMap<d>(it_.Au.data() + d * i) += y;
      return (CVecMap<d>(u.data() + d * i) - CVecMap<d>(old_.data() + d * i)).dot(y);
    }), 0.0));
    // judged in every cycle with the coupling, a cycle with a state change too (it was not: a coupled
    // cycle that grew by 1e10 while the state changed went on and read as divergence)
    if (pg_.judge(step, best_step_)) {
      // the coupling's step was no smaller than every step before: refused, the iterate back to
      // x (feasible, as every iterate), A u with it; the cycle map changes: the history starts again
      anderson_.reset();
      parallel_for((Index)u.size(), [&](Index k) { u[k] = old_[k]; });
      A.multiply(u.data(), it_.Au.data());
      // the iterate did not move: the cycle reports the smallest step before it, not the refused
      // one (a refused step that grew by 1e10 read as divergence and ended a solve the fallback saves)
      pc.lap(Phase::Norm);
      return best_step_;
    } else {
      best_step_ = std::min(best_step_, step);
    }
    pc.lap(Phase::Norm);
    return step;
  }

  // energy (with the Dirichlet offset and the friction term) and the contact counts
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
    rec.petrov_galerkin = pg_.state();
    if (projected_) rec.step_size = step_size_;
  }

  // ||u - u*||_A with u* canonical (taken to the contact frames first)
  double error_against(const double* ref) {
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

  // ||S(u) - u||_A for one forward nonlinear sweep S; u is left as it was. NaN for linear problems.
  double sweep_change() {
    if constexpr (!L::has_contact) return std::numeric_limits<double>::quiet_NaN();
    std::vector<double>& u = it_.u;
    old_ = u;
    Smoother::sweep(P_, u.data(), true, order_);
    for (std::size_t k = 0; k < u.size(); ++k) std::swap(u[k], old_[k]);
    for (std::size_t k = 0; k < u.size(); ++k) old_[k] -= u[k];
    std::vector<double>& tmp = r_;  // the residual is not needed after a cycle: no new fine vector
    P_.matrix().multiply(old_.data(), tmp.data());
    double e = 0;
    for (std::size_t k = 0; k < u.size(); ++k) e += old_[k] * tmp[k];
    return std::sqrt(std::max(e, 0.0));
  }

 private:
  // The law's linearization at every contact node; returns whether any bound is finite.
  bool linearize() {
    hessian_.clear();
    coupling_.clear();
    if constexpr (!L::has_contact) return false;
    bool bounded = false;
    const auto& base = P_.base_mask();
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index i = P_.contact_node(c), k = i * d;
      Mat<d> Hc = Mat<d>::Zero();
      if (projected_) bound_[c] = L::bound(P_.node(c), it_.u[k] >= P_.node(c).gap, r_[k]);  // r_ before the friction gradient
      if (linearize_node<L, d>(P_.node(c), it_.u.data() + k, r_.data() + k, mask_.data() + k, base.data() + k, lo_.data() + c * d,
                               hi_.data() + c * d, &Hc, P_.matrix().block(P_.matrix().diag[i])))
        bounded = true;
      if (!Hc.isZero(0.0)) hessian_.emplace_back(i, Hc);
      if constexpr (L::coarse_freezes_bound)
        if (pg_.wanted() || upwind_.on()) {
          const Vec<d> w = bound_coupling<L, d>(P_.node(c), it_.u.data() + k, r_[k]);
          if (!w.isZero(0.0)) coupling_.emplace_back(i, w);
        }
    }
    return bounded;
  }

  // The coarse correction w with every bound but the inactive nodes' gap bounds (the sliding signs
  // stay), projected node-wise onto u_n + w_n <= g, then u += a w with a the exact minimizer of the
  // frozen-bound energy along w (frozen_line_search.hpp, TNNMG's): a descent step whatever w is, so
  // the cycle stays monotone, and a node closing on the obstacle no longer throttles the coarse
  // motions around it. The slope w^T (f - A u) is taken as w^T f - (A w)^T u (A symmetric): one
  // product with A, into r_ (free after the restriction).
  template <class Row>
  void projected_correction(Row&& fine_residual) {
    std::vector<double>& u = it_.u;
    const BlockMatrix<d>& A = P_.matrix();
    const std::vector<double>& f = P_.load();
    bool bounded = false;
    for (std::size_t k = 0; k < hi_.size(); ++k) {
      hi_open_[k] = k % d == 0 ? kInf : hi_[k];
      bounded = bounded || hi_open_[k] < kInf || lo_[k] > -kInf;
    }
    C_.correction_of(opt_, fine_residual, mask_.data(), NodeBounds{&P_.contact_nodes(), lo_.data(), hi_open_.data()}, bounded,
                     w_.data(), P_.num_nodes(), false);
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index k = P_.contact_node(c) * d;
      const double room = P_.node(c).gap - u[k];
      if (w_[k] > room) w_[k] = std::max(0.0, room);
    }
    A.multiply(w_.data(), r_.data());
    const Index n = (Index)u.size();
    const double quad = parallel_sum(n, [&](Index k) { return w_[k] * r_[k]; });
    const double slope = parallel_sum(n, [&](Index k) { return w_[k] * f[k] - r_[k] * u[k]; });
    search_.clear(quad, slope);
    for (Index c = 0; c < P_.num_contact(); ++c) {
      const Index k = P_.contact_node(c) * d;
      const ContactNode p = P_.node(c);
      const Vec<d> v = slip_increment<d>(p, u.data() + k);  // a load step's friction acts on the increment
      search_.add_friction(bound_[c], v.data(), w_.data() + k, p.free);
      search_.add_normal_limit(p.gap - u[k], w_[k]);
    }
    const double a = step_size_ = search_.minimize();
    parallel_for(n, [&](Index k) { u[k] += a * w_[k]; });
  }

  // |y - x|_A^2 with A (y - x) into z (one product with A; taken only where the truncation
  // changed). The same sums over the same chunks as the norm pass of iterate().
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
  const SweepOrder& order_;  // of the fine nonlinear sweeps
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
  UpwindContactSweep<d, L> upwind_;
  std::vector<std::pair<Index, Vec<d>>> coupling_;  // sliding node -> w (bound_coupling), when wanted
  bool first_ = true;
  // the projected coarse correction (SolverOptions::projected_coarse_correction): its direction, the
  // frozen bounds, the upper bounds without the gaps, the line search and its last step
  const bool projected_;
  std::vector<double> w_, bound_, hi_open_;
  FrozenLineSearch<d> search_;
  double step_size_ = std::numeric_limits<double>::quiet_NaN();
  double best_step_ = kInf;  // the smallest |u^{k+1} - u^k|_A of this solve
};

}  // namespace cmg
