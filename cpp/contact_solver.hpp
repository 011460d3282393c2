// The solver of a contact problem as the bindings see it: the composition of the pieces --
// ContactProblem (fine level in the contact frames), GalerkinHierarchy and CoarseCycle (mg/), the
// monotone multigrid and fixed-point steps (steps/), the loop with its stop rules and the monitor
// (solver/) -- for the law chosen at run time (laws/law.hpp turns it into a type once per call).
#pragma once
#include <memory>
#include "laws/law.hpp"
#include "steps/fixed_point_step.hpp"
#include <memory>
#include "steps/tnnmg_step.hpp"

namespace cmg {

template <int d>
class ContactSolver {
 public:
  struct Transfer {  // interpolation weights of one refinement step
    Index n_fine, n_coarse;
    std::vector<Index> ptr, parent;
    std::vector<double> weight;
  };

  ContactSolver(BlockMatrix<d> A, const double* f, const std::uint8_t* fixed, const double* fixed_values,
                const std::vector<Index>& contact_nodes, const double* normals, const double* gaps, const double* coefficients,
                Law law, const std::vector<Transfer>& transfers, CycleOptions cyc, const std::uint8_t* frame_fixed = nullptr,
                const double* frame_values = nullptr)
      : law_(law),
        P_(std::move(A), f, fixed, fixed_values, contact_nodes, normals, gaps, coefficients, frame_fixed, frame_values),
        H_(prolongations(transfers)),
        C_(H_),
        cyc_(cyc) {
    built_.mask = P_.base_mask();
    H_.rebuild(P_.matrix(), built_.mask.data());
  }

  Index num_nodes() const { return P_.num_nodes(); }
  Index num_contact() const { return P_.num_contact(); }
  const ContactProblem<d>& problem() const { return P_; }
  const GalerkinHierarchy<d>& hierarchy() const { return H_; }
  CoarseCycle<d>& coarse_cycle() { return C_; }
  const BlockMatrix<d>& fine_matrix() const { return P_.matrix(); }
  const CycleOptions& cycle_options() const { return cyc_; }
  Monitor& monitor() { return mon_; }
  std::size_t memory_bytes() const {
    return P_.memory_bytes() + H_.memory_bytes() + C_.memory_bytes() + sizeof(double) * 8 * P_.num_nodes() * d +
           sizeof(Index) * fine_coloured_.rows().size() + (fine_cycle_ ? fine_cycle_->memory_bytes() : 0) +
           (tied_ ? tied_->memory_bytes() : 0);
  }
  // Load paths: friction on the slip increment from the canonical displacement u_prev (nullptr: none).
  void set_slip_origin(const double* u_prev) { P_.set_slip_origin(u_prev); }
  bool has_slip_origin() const { return P_.has_slip_origin(); }
  Index num_fine_colours() { return fine_order(Ordering::Coloured).num_colours(); }
  // A second, bounds-free coarse correction with every contact dof frozen after each coarse
  // correction of the nmg and fixed-point methods (steps/tied_correction.hpp; two bodies).
  void enable_tied_correction() {
    std::vector<BlockMatrix<d>> P;
    for (int l = 0; l < H_.num_coarse_levels(); ++l) P.push_back(H_.prolongation(l));
    tied_ = std::make_unique<TiedCorrection<d>>(P_, std::move(P));
  }
  bool tied_correction() const { return (bool)tied_; }
  // Full Galerkin rebuild for the current linearization (diagnostics: compare with the incremental one).
  void rebuild_coarse() { H_.rebuild(P_.matrix(), built_.mask.data(), built_.hessian); }

  // The method of the solver's law from u0 (canonical; nullptr = 0): monotone multigrid cycles.
  SolveResult solve(const double* u0, const SolveOptions& opt, const CycleOptions& cyc) {
    return with_law(law_, [&](auto L) {
      using Law = decltype(L);
      start(u0);
      P_.set_bounds_to_coefficients();
      SolveResult R;
      MonotoneMultigridStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_order(cyc.ordering), tied_.get());
      run_loop(step, opt, mon_, R, 0);
      finish<Law>(R);
      return R;
    });
  }
  SolveResult solve(const double* u0, const SolveOptions& opt) { return solve(u0, opt, cyc_); }

  // Truncated nonsmooth Newton multigrid steps (steps/tnnmg_step.hpp) from u0, same stop rules.
  SolveResult solve_tnnmg(const double* u0, const SolveOptions& opt, const CycleOptions& cyc) {
    // its line search measures the friction term on u_T, not on the slip increment of a load step
    if (P_.has_slip_origin())
      throw InputError("method tnnmg does not take a slip origin (load paths): use nmg or fixed-point");
    return with_law(law_, [&](auto L) {
      using Law = decltype(L);
      start(u0);
      P_.set_bounds_to_coefficients();
      SolveResult R;
      TnnmgStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_cycle(), fine_order(cyc.ordering));
      run_loop(step, opt, mon_, R, 0);
      finish<Law>(R);
      return R;
    });
  }

  // The linear correction of TNNMG on the linearization the coarse levels are built for (a fresh
  // solver: the Dirichlet mask alone, i.e. linear elasticity in the contact frames): PCG with the
  // truncated linear cycle for K w = M r (r in the frames). Returns w; `energies` the energy
  // 1/2 w^T K w - r^T M w after each iteration (0 first). For tests and diagnostics.
  std::vector<double> linear_solve(const double* r, const CycleOptions& cyc, int max_iterations, double reduction,
                                   std::vector<double>& energies) {
    TruncatedLinearCycle<d>& lin = fine_cycle();
    lin.set_linearization(built_.mask.data(), built_.hessian, cyc.lines);
    const Index n = P_.num_nodes() * d;
    std::vector<double> rm(n), w(n);
    for (Index k = 0; k < n; ++k) rm[k] = built_.mask[k] * r[k];
    PcgReport rep = pcg(
        n, [&](const double* x, double* y) { lin.multiply(x, y); },
        [&](const double* res, double* z) { lin.apply(C_, cyc, res, z); }, rm.data(), w.data(), max_iterations, reduction, true);
    energies = rep.energy;
    return w;
  }
  const LineSet& fine_lines(bool lines) {
    fine_cycle().set_linearization(built_.mask.data(), built_.hessian, lines);
    return fine_cycle().lines();
  }

  // Algorithm 1 (Coulomb only).
  SolveResult solve_fixed_point(const double* u0, const SolveOptions& opt, const CycleOptions& cyc) {
    if (law_ != Law::Coulomb) throw InputError("the fixed-point iteration needs a Coulomb friction law");
    start(u0);
    SolveResult R;
    MonotoneMultigridStep<d, law::Tresca> tresca(P_, H_, C_, built_, it_, cyc, fine_order(cyc.ordering), tied_.get());
    FixedPointStep<d> step(P_, tresca, it_);
    run_fixed_point(step, opt, mon_, R);
    finish<law::Coulomb>(R);
    return R;
  }

  // `sweeps` nonlinear Gauss-Seidel sweeps of the solver's law from u0 (canonical), alternating
  // direction starting forward; returns the canonical iterate. A solution is a fixed point of this
  // map (the nodal rules keep every local solution), so it serves as an independent check.
  std::vector<double> smooth(const double* u0, int sweeps, Ordering ordering = Ordering::Lexicographic) {
    return with_law(law_, [&](auto L) {
      start(u0);
      P_.set_bounds_to_coefficients();
      const SweepOrder& order = fine_order(ordering);
      for (int k = 0; k < sweeps; ++k) NonlinearGaussSeidel<d, decltype(L)>::sweep(P_, it_.u.data(), k % 2 == 0, order);
      std::vector<double> u = it_.u;
      P_.basis().to_canonical(u.data());
      return u;
    });
  }

 private:
  std::vector<BlockMatrix<d>> prolongations(const std::vector<Transfer>& T) const {
    std::vector<BlockMatrix<d>> P;
    for (std::size_t l = 0; l < T.size(); ++l) {
      const bool fine = l + 1 == T.size();
      if (l > 0 && T[l].n_coarse != T[l - 1].n_fine) throw InputError("prolongations do not chain: level sizes differ");
      if (fine && T[l].n_fine != P_.num_nodes()) throw InputError("the finest prolongation does not match the matrix size");
      if ((Index)T[l].ptr.size() != T[l].n_fine + 1) throw InputError("prolongation pointer array has the wrong length");
      P.push_back(make_prolongation<d>(T[l].n_fine, T[l].n_coarse, T[l].ptr.data(), T[l].parent.data(), T[l].weight.data()));
      if (fine) P_.basis().transform_prolongation(P.back());
    }
    return P;
  }

  // The truncated linear cycle of TNNMG's linear correction on the fine level (made on first use).
  TruncatedLinearCycle<d>& fine_cycle() {
    if (!fine_cycle_) fine_cycle_ = std::make_unique<TruncatedLinearCycle<d>>(P_.matrix(), P_.basis());
    return *fine_cycle_;
  }

  // The order of the fine nonlinear sweeps (the colouring made once, on first use).
  const SweepOrder& fine_order(Ordering o) {
    if (o == Ordering::Lexicographic) return lexicographic_;
    if (!fine_coloured_.coloured()) fine_coloured_ = SweepOrder().coloured_by<d>(P_.matrix());
    return fine_coloured_;
  }

  void start(const double* u0) {
    rebuilds0_ = H_.rebuilds();
    rebuild_seconds0_ = H_.rebuild_seconds();
    mon_.start();
    it_.start(P_, u0);
  }

  template <class L>
  void finish(SolveResult& R) {
    const Index nc = num_contact();
    R.seconds = mon_.elapsed();
    R.rebuilds = H_.rebuilds() - rebuilds0_;
    R.rebuild_seconds = H_.rebuild_seconds() - rebuild_seconds0_;
    R.phase_seconds = mon_.phase_seconds();
    R.u = it_.u;
    R.contact_force.assign(nc * d, 0.0);
    R.friction_bound.assign(nc, 0.0);
    R.state.assign(nc, 0);
    const std::vector<double>& f = P_.load();
    for (Index c = 0; c < nc; ++c) {
      const Index k = P_.contact_node(c) * d;
      const ContactNode p = P_.node(c);
      for (int a = 0; a < d; ++a) R.contact_force[c * d + a] = it_.Au[k + a] - f[k + a];
      R.state[c] = (std::int8_t)node_state<d>(p, it_.u.data() + k);
      R.friction_bound[c] = L::bound(p, R.state[c] != 0, f[k] - it_.Au[k]);
    }
    P_.basis().to_canonical(R.u.data());
  }

  Law law_;
  ContactProblem<d> P_;
  GalerkinHierarchy<d> H_;
  CoarseCycle<d> C_;
  CycleOptions cyc_;
  BuiltLinearization<d> built_;
  FineIterate<d> it_;
  Monitor mon_;
  SweepOrder lexicographic_, fine_coloured_;
  std::unique_ptr<TruncatedLinearCycle<d>> fine_cycle_;
  std::unique_ptr<TiedCorrection<d>> tied_;
  int rebuilds0_ = 0;
  double rebuild_seconds0_ = 0;
};

}  // namespace cmg
