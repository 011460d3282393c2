// The solver of a contact problem as the bindings see it: the composition of the pieces --
// ContactProblem (fine level in the contact frames), GalerkinHierarchy and CoarseCycle (mg/), the
// monotone multigrid and fixed-point steps (steps/), the loop with its stop rules and the monitor
// (solver/) -- for the law chosen at run time (laws/law.hpp turns it into a type once per call).
#pragma once
#include <memory>
#include "laws/law.hpp"
#include "solver/fixed_point_solver.hpp"
#include "mg/renumbering.hpp"
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

  // options: the solver's own options, the ones a solve starts from. Their ordering also decides
  // the storage: coloured (hashed) stores every level but the coarsest by its colours (hashed
  // colours; mg/renumbering.hpp); what goes in and out stays in the caller's numbering.
  ContactSolver(BlockMatrix<d> A, const double* f, const std::uint8_t* fixed, const double* fixed_values,
                const std::vector<Index>& contact_nodes, const double* normals, const double* gaps, const double* coefficients,
                Law law, std::vector<Transfer> transfers, const SolverOptions& options, const std::uint8_t* frame_fixed = nullptr,
                const double* frame_values = nullptr)
      : ContactSolver(Stored(std::move(A), f, fixed, fixed_values, contact_nodes, std::move(transfers),
                             validated(options).ordering),
                      normals, gaps, coefficients, law, options, frame_fixed, frame_values) {}

  Index num_nodes() const { return P_.num_nodes(); }
  Index num_contact() const { return P_.num_contact(); }
  const ContactProblem<d>& problem() const { return P_; }
  const GalerkinHierarchy<d>& hierarchy() const { return H_; }
  CoarseCycle<d>& coarse_cycle() { return C_; }
  const BlockMatrix<d>& fine_matrix() const { return P_.matrix(); }  // in storage order
  // A u - f of the last iterate (n * d: canonical axes, the caller's numbering), from the kept A u:
  // the final check of a solve reads its free rows (a fixed row holds no equation here: its
  // component is eliminated). No product with A, and no matrix kept elsewhere for it.
  std::vector<double> residual() const {
    const std::vector<double>& f = P_.load();
    std::vector<double> r(it_.Au.size());
    for (std::size_t k = 0; k < r.size(); ++k) r[k] = it_.Au[k] - f[k];
    std::vector<double> out = order_.back().to_storage_inverse(r.data(), num_nodes(), d);
    const BasisTransform<d>& T = P_.basis();
    for (Index c = 0; c < T.num_blocks(); ++c) {
      VecMap<d> ri(out.data() + order_.back().to_user(T.node(c)) * d);
      ri = T.block(c) * Vec<d>(ri);
    }
    return out;
  }
  // The largest entry of the fine matrix: the stiffness scale of the final check.
  double stiffness_scale() const {
    double m = 0;
    for (double v : P_.matrix().values) m = std::max(m, std::abs(v));
    return m;
  }

  // The fine matrix (in the frames, Dirichlet eliminated) and coarse matrix l in the user's numbering.
  BlockMatrix<d> fine_matrix_in_user_order() const { return in_user_order(P_.matrix(), (int)order_.size() - 1); }
  BlockMatrix<d> coarse_matrix_in_user_order(int l) const { return in_user_order(H_.matrix(l), l); }
  // The rows smoothed on coarse level l (all by default), in the user's numbering of that level.
  void set_rows_to_smooth(int l, std::vector<Index> rows) {
    const Index n = H_.prolongation(l).cols;
    for (Index i : rows)
      if (i < 0 || i >= n) throw InputError("a row to smooth (" + std::to_string(i) + ") is outside 0.." + std::to_string(n - 1));
    if (!order_[l].identity()) {
      const std::vector<Index> where = order_[l].new_of_old();
      for (Index& i : rows) i = where[i];
    }
    C_.set_rows_to_smooth(l, SweepOrder(std::move(rows)));
  }
  const SolverOptions& options() const { return options_; }
  bool renumbered() const { return !order_.back().identity(); }
  Monitor& monitor() { return mon_; }
  std::size_t memory_bytes() const {
    // the problem (matrix, load, masks), coarse levels and prolongations, coarse vectors, the fine
    // iterate u, A u and the step's r, u_old (4 fine vectors and one mask), the orders
    std::size_t s = P_.memory_bytes() + H_.memory_bytes() + C_.memory_bytes() + (sizeof(double) * 4 + 1) * P_.num_nodes() * d +
                    fine_coloured_.memory_bytes() + fine_hashed_.memory_bytes() + lexicographic_.memory_bytes();
    for (const Renumbering& R : order_) s += R.memory_bytes();
    if (fine_cycle_) s += fine_cycle_->memory_bytes();
    if (tied_) s += tied_->memory_bytes();
    s += work_.anderson.memory_bytes();  // r, u_old counted above
    return s;
  }
  // Load paths: friction on the slip increment from the canonical displacement u_prev (nullptr: none).
  void set_slip_origin(const double* u_prev) {
    if (!u_prev || order_.back().identity()) { P_.set_slip_origin(u_prev); return; }
    P_.set_slip_origin(order_.back().to_storage(u_prev, num_nodes(), d).data());
  }
  bool has_slip_origin() const { return P_.has_slip_origin(); }
  // A load step: a new load / new Dirichlet values (canonical, the caller's numbering, n * d) for
  // the same matrix, fixed components and contact data. A later solve is the one of a solver built
  // with these data, bit for bit.
  void set_load(const double* f) { P_.set_load(order_.back().to_storage(f, num_nodes(), d).data()); }
  void set_fixed_values(const double* values) {
    P_.set_fixed_values(order_.back().to_storage(values, num_nodes(), d).data());
  }
  // Whether the cycles' workspace stays from one solve to the next (default). A solver made for one
  // solve turns it off: kept, it is 8 fine vectors alive while the result is written (+8 B/dof on
  // the peak of a level-9 solve in 2D) and 64 B/dof held after it.
  bool keep_workspace(bool on) {
    const bool old = keep_work_;
    keep_work_ = on;
    if (!on) work_ = CycleWorkspace();
    return old;
  }
  Index num_fine_colours() { return fine_order(Ordering::Coloured).num_colours(); }
  // The colour of every node of level `level` (coarsest 0, the fine level last) in the coloured
  // or hashed sweeps, in the user's numbering (-1: a row not smoothed). For tests.
  std::vector<Index> level_colours(int level, Ordering o) {
    if (o == Ordering::Lexicographic) throw InputError("level colours: lexicographic sweeps have no colours");
    if (level < 0 || level >= (int)order_.size()) throw InputError("level colours: no level " + std::to_string(level));
    const bool fine = level + 1 == (int)order_.size();
    const SweepOrder& S = fine ? fine_order(o) : (prepare_orders(o), C_.orders(o)[level]);
    const Index n = fine ? num_nodes() : H_.matrix(level).rows;
    std::vector<Index> colour(n, -1);
    const std::vector<Index>& ptr = S.colour_ptr();
    for (Index c = 0; c < S.num_colours(); ++c)
      for (Index q = ptr[c]; q < ptr[c + 1]; ++q) colour[order_[level].to_user(S.contiguous() ? q : S.rows()[q])] = c;
    return colour;
  }
  // A second, bounds-free coarse correction with every contact dof frozen after each coarse
  // correction of the nmg and fixed-point methods (steps/tied_correction.hpp; two bodies).
  void enable_tied_correction() {
    std::vector<Prolongation<d>> P;
    for (int l = 0; l < H_.num_coarse_levels(); ++l) P.push_back(H_.prolongation(l));
    tied_ = std::make_unique<TiedCorrection<d>>(P_, std::move(P));
  }
  bool tied_correction() const { return (bool)tied_; }
  // Full Galerkin rebuild for the current linearization (diagnostics: compare with the incremental one).
  void rebuild_coarse() { H_.rebuild(P_.matrix(), built_.mask.data(), built_.hessian); }

  // A solve by opt.method from u0 (canonical, the caller's numbering; nullptr = 0). reference: a
  // canonical u* whose error each cycle records (nullptr: none).
  SolveResult solve(const double* u0, const SolverOptions& opt, const double* reference = nullptr) {
    opt.validate();
    const double* ref = stored_reference(reference);
    SolveResult R = opt.method == Method::FixedPoint ? solve_fixed_point(u0, opt, ref)
                    : opt.method == Method::Tnnmg    ? solve_tnnmg(u0, opt, ref)
                                                     : solve_nmg(u0, opt, ref);
    std::vector<double>().swap(reference_);
    return R;
  }

  // The linear correction of TNNMG on the linearization the coarse levels are built for (a fresh
  // solver: the Dirichlet mask alone, i.e. linear elasticity in the contact frames): PCG with the
  // truncated linear cycle for K w = M r (r in the frames). Returns w; `energies` the energy
  // 1/2 w^T K w - r^T M w after each iteration (0 first). For tests and diagnostics.
  std::vector<double> linear_solve(const double* r, const SolverOptions& cyc, int max_iterations, double reduction,
                                   std::vector<double>& energies) {
    TruncatedLinearCycle<d>& lin = fine_cycle();
    prepare_orders(cyc.ordering);
    lin.set_linearization(built_.mask.data(), built_.hessian, cyc.lines);
    const Index n = P_.num_nodes() * d;
    const std::vector<double> rs = order_.back().to_storage(r, num_nodes(), d);  // r: user numbering
    std::vector<double> rm(n), w(n);
    for (Index k = 0; k < n; ++k) rm[k] = built_.mask[k] * rs[k];
    PcgReport rep = pcg(
        n, [&](const double* x, double* y) { lin.multiply(x, y); },
        [&](const double* res, double* z) { lin.apply(C_, cyc, res, z); }, rm.data(), w.data(), max_iterations, reduction, true);
    energies = rep.energy;
    return order_.back().to_storage_inverse(w.data(), num_nodes(), d);
  }
  // the lines of the fine / a coarse line smoother, node ids in the user's numbering
  LineSet fine_lines(bool lines) {
    fine_cycle().set_linearization(built_.mask.data(), built_.hessian, lines);
    return in_user_numbering(fine_cycle().lines(), (int)order_.size() - 1);
  }
  LineSet coarse_lines(int level) const { return in_user_numbering(H_.level(level).lines.lines(), level); }
  LineSet in_user_numbering(LineSet L, int level) const {
    for (Index& i : L.nodes) i = order_[level].to_user(i);
    return L;
  }

  // `sweeps` nonlinear Gauss-Seidel sweeps of the solver's law from u0 (canonical), alternating
  // direction starting forward; returns the canonical iterate. A solution is a fixed point of this
  // map (the nodal rules keep every local solution), so it serves as an independent check.
  // omega: the over-relaxation of the rows without contact (1: the plain nonlinear sweep of the
  // independent check); per_row: every row through the per-row path, also on a level stored by
  // colours (the range kernel's reference).
  std::vector<double> smooth(const double* u0, int sweeps, Ordering ordering = Ordering::Lexicographic, double omega = 1.0,
                             bool per_row = false) {
    return with_law(law_, [&](auto L) {
      start(u0, false);  // the fine level alone: the coarse levels stay as they are
      P_.set_bounds_to_coefficients();
      if (!(omega > 0 && omega < 2)) throw InputError("the over-relaxation omega must lie in (0, 2)");
      const SweepOrder& order = fine_order(ordering);
      for (int k = 0; k < sweeps; ++k)
        NonlinearGaussSeidel<d, decltype(L)>::sweep(P_, it_.u.data(), k % 2 == 0, order, omega, per_row);
      std::vector<double> u = it_.u;
      P_.basis().to_canonical(u.data());
      order_.back().to_user_in_place(u, d);
      return u;
    });
  }

 private:
  static const SolverOptions& validated(const SolverOptions& o) {
    o.validate();
    return o;
  }

  // Monotone multigrid cycles of the solver's law.
  SolveResult solve_nmg(const double* u0, const SolverOptions& cyc, const double* reference) {
    return with_law(law_, [&](auto L) {
      using Law = decltype(L);
      start(u0);
      P_.set_bounds_to_coefficients();
      SolveResult R;
      // TNNMG takes no slip origin (load paths) and has nothing to add without contact
      const bool may_switch = cyc.switch_rate > 0 && Law::has_contact && !P_.has_slip_origin();
      {
        MonotoneMultigridStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_order(cyc.ordering), tied_.get(), workspace());
        run_loop(step, cyc, reference, mon_, R, 0, may_switch);
      }
      if (R.status == kSwitchStatus) {  // the same iterate, the same stop: TNNMG steps from here
        R.switched_at = R.cycles;
        {
          TnnmgStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_cycle(), fine_order(cyc.ordering));
          run_loop(step, cyc, reference, mon_, R, 0, false, true, true);
        }
        // A TNNMG phase can stall short of the solution: its projected Newton direction need not be a
        // descent direction, and a step along a nearly free motion of a body held by contact has no
        // energy norm to measure (a frictionless roller guided at its top, two bodies); or its line
        // search is blocked at once, step after step (a body closing a gap to its obstacle). Algorithm
        // 2's cycles are monotone from any iterate: they finish the solve, under the same stop.
        if (!R.converged && (R.status == kSwitchStatus || R.status.rfind("stalled", 0) == 0)) {
          MonotoneMultigridStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_order(cyc.ordering), tied_.get(), workspace());
          run_loop(step, cyc, reference, mon_, R, 0, false, true);
        }
      }
      finish<Law>(R);
      return R;
    });
  }

  // Truncated nonsmooth Newton multigrid steps (steps/tnnmg_step.hpp), same stop rules.
  SolveResult solve_tnnmg(const double* u0, const SolverOptions& cyc, const double* reference) {
    // its line search measures the friction term on u_T, not on the slip increment of a load step
    if (P_.has_slip_origin())
      throw InputError("method tnnmg does not take a slip origin (load paths): use nmg or fixed-point");
    return with_law(law_, [&](auto L) {
      using Law = decltype(L);
      start(u0);
      P_.set_bounds_to_coefficients();
      SolveResult R;
      TnnmgStep<d, Law> step(P_, H_, C_, built_, it_, cyc, fine_cycle(), fine_order(cyc.ordering));
      run_loop(step, cyc, reference, mon_, R, 0);
      finish<Law>(R);
      return R;
    });
  }

  // Algorithm 1 (Coulomb only).
  SolveResult solve_fixed_point(const double* u0, const SolverOptions& cyc, const double* reference) {
    if (law_ != Law::Coulomb) throw InputError("the fixed-point iteration needs a Coulomb friction law");
    start(u0);
    SolveResult R;
    MonotoneMultigridStep<d, law::Tresca> tresca(P_, H_, C_, built_, it_, cyc, fine_order(cyc.ordering), tied_.get(), workspace());
    FixedPointStep<d> step(P_, tresca, it_);
    run_fixed_point(step, cyc, reference, mon_, R);
    finish<law::Coulomb>(R);
    return R;
  }

  CycleWorkspace* workspace() {
    if (keep_work_) return &work_;
    work_ = CycleWorkspace();  // not kept: what an earlier solve kept goes, the step allocates its own
    return nullptr;
  }
  // The fine data and the prolongations in storage order (the renumbering of every level).
  struct Stored {
    BlockMatrix<d> A;
    std::vector<double> f, fixed_values;
    std::vector<std::uint8_t> fixed;
    std::vector<Index> contact_nodes;
    std::vector<Prolongation<d>> P;  // canonical weights; the fine basis transform comes later
    std::vector<Renumbering> order;  // per level, coarsest first; the fine one last

    Stored(BlockMatrix<d> A_in, const double* f_in, const std::uint8_t* fixed_in, const double* values_in,
           const std::vector<Index>& nodes, std::vector<Transfer> T, Ordering storage)
        : A(std::move(A_in)) {
      const bool renumber = storage != Ordering::Lexicographic, hashed = storage == Ordering::Hashed;
      const Index n = A.rows;
      for (std::size_t l = 0; l < T.size(); ++l) {
        const bool fine = l + 1 == T.size();
        if (l > 0 && T[l].n_coarse != T[l - 1].n_fine) throw InputError("prolongations do not chain: level sizes differ");
        if (fine && T[l].n_fine != n) throw InputError("the finest prolongation does not match the matrix size");
        if ((Index)T[l].ptr.size() != T[l].n_fine + 1) throw InputError("prolongation pointer array has the wrong length");
        P.push_back(make_prolongation<d>(T[l].n_fine, T[l].n_coarse, T[l].ptr.data(), T[l].parent.data(), T[l].weight.data()));
        // the interpolation weights are in P now: freed at once, not at the end of the build (their
        // 64-bit copies were 24 bytes a dof at level 9 in 2D during the renumbering and the
        // Galerkin products, the peak of the build; docs/dev/decisions/0011-memory-release.md)
        std::vector<Index>().swap(T[l].ptr);
        std::vector<Index>().swap(T[l].parent);
        std::vector<double>().swap(T[l].weight);
      }
      order.resize(P.size() + 1);
      if (renumber) {
        // each colour stored in the level's locality order (mg/renumbering.hpp); rank: the locality
        // position of each stored row of the level just renumbered
        std::vector<Index> locality = reverse_cuthill_mckee<d>(A), rank;
        order.back() = Renumbering::by_colours<d>(A, locality, hashed);
        rank = stored_rank(locality, order.back());
        order.back().permute_matrix(A);
        if (!P.empty()) order.back().permute_rows(P.back());
        // each coarse level (not the coarsest: it is factorized) by the colours of its Galerkin pattern
        // (on the uniform hierarchies of the distributed solver the coarse mesh's cell adjacency,
        // the graph its hashed colouring runs on: coarse nodes i, j share a coarse cell exactly when
        // a fine node below i is coupled to one below j)
        BlockMatrix<d> pattern;
        for (int l = (int)P.size() - 1; l >= 1; --l) {
          pattern = galerkin_pattern<d>(l + 1 == (int)P.size() ? A : pattern, P[l], TransposedPattern<d>(P[l]));
          locality = induced_locality_order(P[l], rank);  // P[l]'s rows: stored, its columns: the user's
          order[l] = Renumbering::by_colours<d>(pattern, locality, hashed);
          rank = stored_rank(locality, order[l]);
          order[l].permute_matrix(pattern);
          order[l].permute_columns(P[l]);
          order[l].permute_rows(P[l - 1]);
        }
      }
      const Renumbering& R = order.back();
      f = R.to_storage(f_in, n, d);
      fixed = R.to_storage(fixed_in, n, d);
      fixed_values = R.to_storage(values_in, n, d);
      contact_nodes = nodes;
      if (!R.identity()) {
        const std::vector<Index> where = R.new_of_old();
        for (Index& i : contact_nodes) {
          if (i < 0 || i >= n) throw InputError("contact node " + std::to_string(i) + " is not a mesh node");
          i = where[i];
        }
      }
    }
  };

  // rank[k]: the position of stored row k in the locality order `visit` (of the user's numbers)
  static std::vector<Index> stored_rank(const std::vector<Index>& visit, const Renumbering& R) {
    const std::vector<Index> user = rank_of(visit);
    std::vector<Index> rank(user.size());
    for (std::size_t k = 0; k < rank.size(); ++k) rank[k] = user[R.to_user((Index)k)];
    return rank;
  }

  ContactSolver(Stored S, const double* normals, const double* gaps, const double* coefficients, Law law, SolverOptions cyc,
                const std::uint8_t* frame_fixed, const double* frame_values)
      : law_(law),
        P_(std::move(S.A), S.f.data(), S.fixed.data(), S.fixed_values.data(), S.contact_nodes, normals, gaps, coefficients,
           frame_fixed, frame_values),
        H_(transformed(std::move(S.P))),
        C_(H_),
        options_(cyc),
        order_(std::move(S.order)) {
    // the lexicographic order of a renumbered level is the user's order (fine: made on first use)
    for (int l = 1; l + 1 < (int)order_.size(); ++l)
      if (!order_[l].identity()) C_.set_rows_to_smooth(l, SweepOrder(order_[l].new_of_old()));
    // the storage-order copies are in P_ now: freed before the first Galerkin products
    std::vector<double>().swap(S.f);
    std::vector<double>().swap(S.fixed_values);
    std::vector<std::uint8_t>().swap(S.fixed);
    built_.mask = P_.base_mask();
    H_.rebuild(P_.matrix(), built_.mask.data());
  }

  std::vector<Prolongation<d>> transformed(std::vector<Prolongation<d>> P) const {
    if (!P.empty()) P_.basis().transform_prolongation(P.back());
    return P;
  }

  // The truncated linear cycle of TNNMG's linear correction on the fine level (made on first use).
  TruncatedLinearCycle<d>& fine_cycle() {
    if (!fine_cycle_) fine_cycle_ = std::make_unique<TruncatedLinearCycle<d>>(P_.matrix(), P_.basis());
    return *fine_cycle_;
  }

  // The order of the fine nonlinear sweeps (the colouring made once, on first use). Hashed: the
  // coarse levels' hashed colourings are made here too (by the user's numbers of their rows).
  const SweepOrder& fine_order(Ordering o) {
    const Renumbering& fine = order_.back();
    if (o == Ordering::Lexicographic) {
      if (!fine.identity() && lexicographic_.all()) lexicographic_ = SweepOrder(fine.new_of_old());
      return lexicographic_;
    }
    if (o == Ordering::Hashed) {
      prepare_orders(o);
      if (!fine_hashed_.coloured())
        fine_hashed_ = SweepOrder().hashed_visit(num_nodes(), [&](Index k) { return fine.to_user(k); }).template coloured_by<d>(P_.matrix());
      return fine_hashed_;
    }
    if (!fine_coloured_.coloured())
      fine_coloured_ = (fine.identity() ? SweepOrder() : SweepOrder(fine.new_of_old())).coloured_by<d>(P_.matrix());
    return fine_coloured_;
  }

  // The coarse levels' orders for a cycle in order o: the hashed ones need the user's numbers.
  void prepare_orders(Ordering o) {
    if (o == Ordering::Hashed && !C_.hashed_ready())
      C_.make_hashed([&](int l, Index k) { return order_[l].to_user(k); });
  }

  // The reference displacement (the caller's numbering) in storage order.
  const double* stored_reference(const double* reference) {
    if (!reference || order_.back().identity()) return reference;
    reference_ = order_.back().to_storage(reference, num_nodes(), d);
    return reference_.data();
  }

  BlockMatrix<d> in_user_order(const BlockMatrix<d>& A, int level) const {
    BlockMatrix<d> B = A;
    order_[level].inverse().permute_matrix(B);
    return B;
  }

  // A solve starts from the coarse levels as the solver built them (the Galerkin products of the
  // base mask): rebuilt in full when a solve before left them for another linearization or changed
  // them incrementally. Without this a second solve began from the last one's truncation and
  // round-off (incremental updates round otherwise than a rebuild, the coarsest solver's low-rank
  // state) and gave other bits than the first; now solve() is a function of the problem and its
  // options. Cost: one full rebuild of the coarse levels in each later solve, counted in its
  // rebuilds and rebuild seconds (the first cycle's update from the base is a solve's own anyway).
  void restore_coarse() {
    if (built_.mask == P_.base_mask() && built_.hessian.empty() && H_.incremental_updates() == 0 && !H_.has_top_overlay()) return;
    built_.mask = P_.base_mask();
    built_.hessian.clear();
    H_.rebuild(P_.matrix(), built_.mask.data());
  }

  void start(const double* u0, bool coarse = true) {
    std::vector<double> u_stored;
    if (u0 && !order_.back().identity()) {
      u_stored = order_.back().to_storage(u0, num_nodes(), d);
      u0 = u_stored.data();
    }
    rebuilds0_ = H_.rebuilds();
    rebuild_seconds0_ = H_.rebuild_seconds();
    mon_.start();
    if (coarse) restore_coarse();
    it_.start(P_, u0);
  }

  template <class L>
  void finish(SolveResult& R) {
    const Index nc = num_contact();
    R.seconds = mon_.elapsed();
    R.rebuilds = H_.rebuilds() - rebuilds0_;
    R.rebuild_seconds = H_.rebuild_seconds() - rebuild_seconds0_;
    R.phase_seconds = mon_.phase_seconds();
    // u in the user's numbering, written once (no second copy to permute in place: the end of a
    // solve was the peak of a level-9 run, docs/dev/decisions/0011-memory-release.md)
    R.u = order_.back().to_storage_inverse(it_.u.data(), num_nodes(), d);
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
    const BasisTransform<d>& T = P_.basis();
    for (Index c = 0; c < T.num_blocks(); ++c) {
      VecMap<d> ui(R.u.data() + order_.back().to_user(T.node(c)) * d);
      ui = T.block(c) * Vec<d>(ui);
    }
  }

  Law law_;
  ContactProblem<d> P_;
  GalerkinHierarchy<d> H_;
  CoarseCycle<d> C_;
  SolverOptions options_;
  BuiltLinearization<d> built_;
  FineIterate<d> it_;
  CycleWorkspace work_;  // r, u_old, the Anderson slots: kept across solves (monotone_mg_step.hpp says why)
  bool keep_work_ = true;  // off for a solver made for one solve: then the step's vectors go before the result is written
  Monitor mon_;
  std::vector<Renumbering> order_;  // storage order of each level (coarsest first, fine last)
  SweepOrder lexicographic_, fine_coloured_, fine_hashed_;
  std::unique_ptr<TruncatedLinearCycle<d>> fine_cycle_;
  std::unique_ptr<TiedCorrection<d>> tied_;
  std::vector<double> reference_;  // a solve's reference displacement in storage order
  int rebuilds0_ = 0;
  double rebuild_seconds0_ = 0;
};

}  // namespace cmg
