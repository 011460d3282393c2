// The multilevel coarse correction of (truncated monotone) multigrid as one V/W/F-cycle over the
// coarse levels of a GalerkinHierarchy: projected Gauss-Seidel on each level within bounds
// restricted monotonically from the fine level, an exact coarsest solve. It returns the fine
// correction w = P~ c and leaves the iterate alone (a Newton-type step may project or line-search
// it). Without bounds it is the coarse part of a plain linear cycle.
#pragma once
#include <algorithm>
#include "mg/bound_restriction.hpp"
#include "mg/bounded_coarsest.hpp"
#include "mg/cycle_recursion.hpp"
#include "mg/hierarchy.hpp"
#include "mg/line_smoother.hpp"
#include "base/solver_options.hpp"

namespace cmg {

template <int d>
class CoarseCycle {
 public:
  explicit CoarseCycle(const GalerkinHierarchy<d>& H) : H_(H), order_(H.num_coarse_levels()) {
    const int nc = H.num_coarse_levels();
    lv_.resize(nc);
    for (int l = 0; l < nc; ++l) {
      const Index n = H.prolongation(l).cols;
      Vectors& L = lv_[l];
      L.x.assign(n * d, 0); L.b.assign(n * d, 0); L.r.assign(n * d, 0);
      L.lo.assign(n * d, -kInf); L.hi.assign(n * d, kInf); L.bounded.assign(n, 0);
    }
  }

  // The rows smoothed on coarse level l (all by default; the changed region of an adaptive
  // hierarchy). The coarsest level is solved, not smoothed, on all its rows.
  void set_rows_to_smooth(int l, SweepOrder order) {
    order.check(H_.prolongation(l).cols);
    order_.at(l) = std::move(order);
    coloured_.clear();
    hashed_.clear();
  }
  // The orders of the coarse levels' sweeps for `o` (the coloured ones built on first use: the
  // coarse patterns are fixed once the hierarchy was first built).
  const std::vector<SweepOrder>& orders(Ordering o) {
    if (o == Ordering::Lexicographic) return order_;
    if (o == Ordering::Hashed) {
      if (!hashed_ready()) throw std::logic_error("the hashed coarse orders are not made (make_hashed)");
      return hashed_;
    }
    if (coloured_.empty()) {
      for (int l = 0; l < (int)order_.size(); ++l) coloured_.push_back(order_[l].coloured_by<d>(H_.matrix(l)));
      coarsest_all_ = SweepOrder().coloured_by<d>(H_.matrix(0));
    }
    return coloured_;
  }
  // The hashed colourings of the coarse levels (sweep_order.hpp hashed_visit): number(l, k) is the
  // node number of stored row k of level l that the priority hashes (the user's numbering, which
  // the distributed solver's global ids equal). The coarsest level's projected sweeps stay
  // lexicographic in this order, as the distributed solver's on its gathered coarsest level.
  template <class Number>
  void make_hashed(Number&& number) {
    hashed_.clear();
    for (int l = 0; l < (int)order_.size(); ++l) {
      const BlockMatrix<d>& A = H_.matrix(l);
      hashed_.push_back(order_[l].hashed_visit(A.rows, [&](Index k) { return number(l, k); }).template coloured_by<d>(A));
    }
  }
  bool hashed_ready() const { return !hashed_.empty() || order_.empty(); }
  std::size_t memory_bytes() const {
    std::size_t s = 0;
    for (auto& L : lv_) s += sizeof(double) * 5 * L.x.size();
    return s;
  }

  // w = P~ c (w: fine level, n_fine * d; add: w += P~ c), c the multilevel correction for the fine
  // residual r, the truncation mask and the fine correction bounds (ignored when !bounded).
  // lines: line Gauss-Seidel on the unbounded levels that have lines (a linear cycle; the monotone
  // cycle keeps its point sweeps).
  void correction(const SolverOptions& opt, const double* r_fine, const std::uint8_t* mask, const NodeBounds& bounds,
                  bool bounded, double* w, Index n_fine, bool add = false, bool lines = false) {
    correction_of(opt, [&](Index i) { return Vec<d>(CVecMap<d>(r_fine + d * i)); }, mask, bounds, bounded, w, n_fine, add, lines);
  }

  // The same with the fine residual's rows given by fine_row(i) (a Vec<d>), in fine row order:
  // the monotone step forms them as they are restricted (steps/monotone_mg_step.hpp).
  template <class Row>
  void correction_of(const SolverOptions& opt, Row&& fine_row, const std::uint8_t* mask, const NodeBounds& bounds, bool bounded,
                     double* w, Index n_fine, bool add = false, bool lines = false) {
    const int top = (int)lv_.size() - 1;
    if (top < 0) {  // a single level: the smoother alone
      if (!add) std::fill(w, w + n_fine * d, 0.0);
      return;
    }
    const Prolongation<d>& P = H_.prolongation(top);
    Vectors& C = lv_[top];
    restrict_of<d>(P, mask, fine_row, C.b.data(), C.r.data());  // C.r: scratch until level top smooths
    if (bounded) restrict_bounds<d>(P, mask, bounds, C.lo.data(), C.hi.data());
    set_bounded(C, bounded);
    zero(C.x);
    cur_ = &orders(opt.ordering);
    serial_rows_ = kSerialLevelRows;
    lines_ = lines;
    omega_ = opt.omega;
    omega_post_ = opt.post_omega();
    Ops ops{*this, opt};
    top_level_cycles(ops, opt.nu1, opt.nu2, top, opt.cycle);
    if (add) prolongate_add<d>(P, mask, C.x.data(), w);
    else prolongate<d>(P, mask, C.x.data(), w);
  }

 private:
  struct Vectors {
    std::vector<double> x, b, r, lo, hi;
    std::vector<std::uint8_t> bounded;
    bool any_bounds = false;
  };

  // (on all threads on the large levels, like every pass of the cycle)
  static void zero(std::vector<double>& x) {
    parallel_for((Index)x.size(), [&](Index k) { x[k] = 0.0; }, 8 * kParallelGrain);
  }

  // (on all threads: the serial loops of a cycle hold back the second thread,
  // docs/dev/decisions/0003-coloured-gauss-seidel.md)
  static void set_bounded(Vectors& L, bool bounded) {
    const Index n = (Index)L.bounded.size();
    L.any_bounds = parallel_sum(n, [&](Index i) {
      bool b = false;
      if (bounded)
        for (int c = 0; c < d; ++c) b = b || L.lo[i * d + c] > -kInf || L.hi[i * d + c] < kInf;
      L.bounded[i] = b;
      return b ? 1.0 : 0.0;
    }) > 0;
  }

  void sweep(int l, bool forward, const SweepOrder& order) { sweep(l, forward, order, omega_); }
  void sweep(int l, bool forward, const SweepOrder& order, double omega) {
    Vectors& L = lv_[l];
    const auto& M = H_.level(l);
    if (L.any_bounds)
      projected_gs_sweep<d>(M.A, M.Dinv, L.bounded, M.inert, L.lo.data(), L.hi.data(), L.b.data(), L.x.data(), forward, order,
                            omega);
    else if (lines_ && M.lines.has_lines() && order.all() && !order.coloured())
      M.factored_lines().sweep(M.A, M.active.data(), L.b.data(), L.x.data(), forward);
    else
      block_gs_sweep<d>(M.A, M.Dinv, L.b.data(), L.x.data(), forward, order, omega);
  }

  // The level operations of the cycle's recursion (mg/cycle_recursion.hpp) on the Galerkin levels.
  struct Ops {
    CoarseCycle& c;
    const SolverOptions& opt;

    // A level below kSerialLevelRows rows, and every coarser one, runs on the calling thread: its
    // loops are too short to pay for waking the second thread (a W/F-cycle visits the small
    // levels most often). Every loop gives the same bits on any thread count, so this is a
    // matter of time only.
    template <class Body>
    void enter(int l, Body&& body) {
      if (!c.serial_ && c.H_.matrix(l).rows < c.serial_rows_ && team_size() > 1) {
        const ThreadScope one(1);
        c.serial_ = true;
        body();
        c.serial_ = false;
        return;
      }
      body();
    }
    void pre_smooth(int l) { c.sweep(l, true, (*c.cur_)[l]); }
    void post_smooth(int l) { c.sweep(l, false, (*c.cur_)[l], c.omega_post_); }
    void restrict_down(int l) {
      Vectors &L = c.lv_[l], &C = c.lv_[l - 1];
      const Prolongation<d>& P = c.H_.prolongation(l - 1);
      // b - A x restricted as it is formed (one pass over A; was a residual pass, then the restriction)
      restrict_level_residual<d>(c.H_.matrix(l), P, L.x.data(), L.b.data(), C.b.data(), C.r.data());
      // the coarser level gets the slack that remains on this one
      if (L.any_bounds) restrict_slack<d>(P, L.lo.data(), L.hi.data(), L.x.data(), C.lo.data(), C.hi.data(), L.bounded.data());
      set_bounded(C, L.any_bounds);
      zero(C.x);
    }
    void prolong_up(int l) { prolongate_add<d>(c.H_.prolongation(l - 1), nullptr, c.lv_[l - 1].x.data(), c.lv_[l].x.data()); }
    void solve_coarsest() { c.solve_coarsest(opt); }
  };

  void solve_coarsest(const SolverOptions& opt) {
    Vectors& L = lv_[0];
    H_.solve_coarsest(L.b.data(), L.x.data());
    if (!L.any_bounds) return;
    const SweepOrder lexicographic;
    // (hashed: lexicographic, the gathered coarsest level's order in the distributed solver)
    const SweepOrder& all = opt.ordering == Ordering::Coloured ? coarsest_all_ : lexicographic;
    bound_coarsest_solution<d>(H_.matrix(0), L.b.data(), L.lo.data(), L.hi.data(), L.x.data(), L.r.data(),
                               H_.coarsest_shifted(), [&](bool forward) { sweep(0, forward, all); });
  }

  Index serial_rows_ = 0;  // kSerialLevelRows in a correction (see Ops::enter)
  bool serial_ = false;
  const GalerkinHierarchy<d>& H_;
  std::vector<SweepOrder> order_, coloured_, hashed_;
  SweepOrder coarsest_all_;                      // every row of the coarsest level, coloured
  const std::vector<SweepOrder>* cur_ = nullptr;  // the orders of the cycle under way
  bool lines_ = false;                            // line sweeps in the cycle under way
  double omega_ = 1.0;                            // over-relaxation of the cycle under way
  double omega_post_ = 1.0;                       // the same of its post-smoothing sweeps
  std::vector<Vectors> lv_;
};

}  // namespace cmg
