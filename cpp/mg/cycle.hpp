// The multilevel coarse correction of (truncated monotone) multigrid as one V/W/F-cycle over the
// coarse levels of a GalerkinHierarchy: projected Gauss-Seidel on each level within bounds
// restricted monotonically from the fine level, an exact coarsest solve. It returns the fine
// correction w = P~ c and leaves the iterate alone (a Newton-type step may project or line-search
// it). Without bounds it is the coarse part of a plain linear cycle.
#pragma once
#include <algorithm>
#include "mg/bound_restriction.hpp"
#include "mg/hierarchy.hpp"
#include "mg/line_smoother.hpp"

namespace cmg {

enum class CycleType : int { V = 0, W = 1, F = 2 };

// The linear correction of a TNNMG step (steps/tnnmg_step.hpp): the coarse cycle alone (the fine
// level smoothed only by the nonlinear sweeps), one truncated linear cycle on the fine level
// (mg/truncated_linear_cycle.hpp), or PCG preconditioned by that cycle (mg/pcg.hpp).
enum class LinearCorrection : int { Coarse = 0, Cycle = 1, Pcg = 2 };

inline LinearCorrection parse_linear_correction(const std::string& s) {
  if (s == "coarse") return LinearCorrection::Coarse;
  if (s == "cycle") return LinearCorrection::Cycle;
  if (s == "pcg") return LinearCorrection::Pcg;
  throw InputError("unknown linear correction '" + s + "' (expected coarse, cycle or pcg)");
}
inline const char* linear_correction_name(LinearCorrection c) {
  return c == LinearCorrection::Coarse ? "coarse" : c == LinearCorrection::Cycle ? "cycle" : "pcg";
}

struct CycleOptions {
  CycleType cycle = CycleType::V;
  int nu1 = 3, nu2 = 3;
  // Projected Gauss-Seidel sweeps on the coarsest level when its exact solve violates the bounds.
  // Each sweep lowers the energy, so any number keeps the cycle monotone; on the Hertz benchmark
  // (triangles levels 3-7, quads 3-6, F = 0.4 and 5) 10, 50, 200 and 2000 gave the same cycle
  // counts, and 2000 (run to a relative change of 1e-14) cost 84 % of a quad level-3 solve.
  int coarsest_max_sweeps = 50;
  // Gauss-Seidel order of every sweep (fine nonlinear, coarse projected): lexicographic, or by
  // colours of the block graph (rows of a colour on all threads).
  // Lexicographic by default: on the shared 2-core machine of issue 15 the coloured sweep was
  // slower on one thread (neighbours of one colour are scattered: worse cache use) and the second
  // thread gained nothing under load (docs/scaling.md, benchmarks/parallel_bandwidth.py).
  Ordering ordering = Ordering::Lexicographic;
  // TNNMG only: its linear correction, and whether that correction smooths by lines
  // (mg/line_smoother.hpp) on the levels whose matrix has lines (elsewhere lines are points).
  LinearCorrection linear = LinearCorrection::Pcg;
  bool lines = true;
  // Over-relaxation of the unbounded block solves of every Gauss-Seidel sweep (fine level: nodes
  // without contact; coarse levels: rows without bounds); 1 = plain Gauss-Seidel. Why: the rate of
  // nodal block Gauss-Seidel on P1 elasticity levels off near 0.34 per F(3,3) cycle (Q1: 0.14), and
  // a symmetric over-relaxed sweep (SSOR) costs the same and contracts by 0.22 with 1.4 on the
  // adaptive Hertz levels (README, issue 11, third part). Any 0 < omega < 2 keeps each such step an
  // energy decrease (a node's quadratic falls by (omega - omega^2 / 2) times its exact minimum), so
  // the monotone cycles stay monotone; bounded rows and contact nodes keep their exact solves.
  double omega = 1.0;
  // Over-relaxation of the post-smoothing sweeps only (the backward ones after the coarse
  // correction, fine and coarse levels; the coarsest level's sweeps keep omega); 0 = omega.
  // Why (issue 11, fifth part): between two coarse corrections the smoother is nu2 backward sweeps
  // then nu1 forward ones, and splitting the relaxation -- omega = 1 before, 1.8 after (or the
  // reverse: the same spectrum) -- contracts P1 elasticity's linear V(3,3) by 0.14 on the unit square
  // level 7 where the symmetric 1.3 gives 0.26, at the same cost (benchmarks/p1_smoother_modes.py).
  // Each step keeps its energy decrease for any 0 < omega_post < 2, so the cycles stay monotone.
  double omega_post = 0.0;
  // Algorithm 2 (a law whose coarse problem freezes a bound): in every cycle but the first, level
  // L-1's matrix also carries the sliding nodes' Petrov-Galerkin coupling, with a fallback to the
  // symmetric one (steps/petrov_galerkin_coupling.hpp; issue 11, seventh and tenth parts). Off here:
  // that coarse correction is not an energy descent; the Python problem turns it on where it pays
  // (2D adaptive hierarchies).
  bool petrov_galerkin = false;
  // Algorithm 2: one more visit of the contact nodes after every fine sweep, the sliding ones
  // in the upwind order of the Coulomb Jacobian (steps/upwind_contact_sweep.hpp; issue 11, eleventh
  // part). Off here; the Python problem turns it on for Coulomb friction on 2D adaptive
  // hierarchies.
  bool upwind_contact_sweep = false;
  // Algorithm 2 and the truncated monotone cycle: the coarse correction without the gap bounds of
  // the inactive contact nodes, projected onto the gap at the fine level and taken with the exact
  // line search of the frozen-bound energy (steps/monotone_mg_step.hpp). Where a contact frame is
  // not a signed permutation of the axes, the monotone restriction turns a node's gap bound into
  // bounds on every coarse component it touches, and a node closing on the obstacle holds back the
  // coarse motions around it (the cork: 16 / 22 / 29 cycles on levels 2-4 without friction, 11 /
  // 12 / 12 with this). Every step still lowers the frozen energy. Off here; the Python problem turns
  // it on where a contact frame is rotated.
  bool projected_coarse_correction = false;
  double post_omega() const { return omega_post > 0 ? omega_post : omega; }
};

inline void check_omega(double omega) {
  if (!(omega > 0 && omega < 2)) throw InputError("the over-relaxation omega must lie in (0, 2)");
}

inline CycleType parse_cycle(const std::string& s) {
  if (s == "V") return CycleType::V;
  if (s == "W") return CycleType::W;
  if (s == "F") return CycleType::F;
  throw InputError("unknown cycle type '" + s + "' (expected V, W or F)");
}

inline void check_smoothing_steps(int nu1, int nu2) {
  if (nu1 < 0 || nu2 < 0 || nu1 + nu2 < 1 || nu1 > 100 || nu2 > 100)
    throw InputError("smoothing steps nu1, nu2 must lie in 0..100 with nu1 + nu2 >= 1");
}

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
  }
  // The orders of the coarse levels' sweeps for `o` (the coloured ones built on first use: the
  // coarse patterns are fixed once the hierarchy was first built).
  const std::vector<SweepOrder>& orders(Ordering o) {
    if (o == Ordering::Lexicographic) return order_;
    if (coloured_.empty()) {
      for (int l = 0; l < (int)order_.size(); ++l) coloured_.push_back(order_[l].coloured_by<d>(H_.matrix(l)));
      coarsest_all_ = SweepOrder().coloured_by<d>(H_.matrix(0));
    }
    return coloured_;
  }
  std::size_t memory_bytes() const {
    std::size_t s = 0;
    for (auto& L : lv_) s += sizeof(double) * 5 * L.x.size();
    return s;
  }

  // w = P~ c (w: fine level, n_fine * d; add: w += P~ c), c the multilevel correction for the fine
  // residual r, the truncation mask and the fine correction bounds (ignored when !bounded).
  // lines: line Gauss-Seidel on the unbounded levels that have lines (a linear cycle; the monotone
  // cycle keeps its point sweeps).
  void correction(const CycleOptions& opt, const double* r_fine, const std::uint8_t* mask, const NodeBounds& bounds,
                  bool bounded, double* w, Index n_fine, bool add = false, bool lines = false) {
    correction_of(opt, [&](Index i) { return Vec<d>(CVecMap<d>(r_fine + d * i)); }, mask, bounds, bounded, w, n_fine, add, lines);
  }

  // The same with the fine residual's rows given by fine_row(i) (a Vec<d>), in fine row order:
  // the monotone step forms them as they are restricted (steps/monotone_mg_step.hpp).
  template <class Row>
  void correction_of(const CycleOptions& opt, Row&& fine_row, const std::uint8_t* mask, const NodeBounds& bounds, bool bounded,
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
    serial_rows_ = parallel_grains().level_rows;
    lines_ = lines;
    omega_ = opt.omega;
    omega_post_ = opt.post_omega();
    cycle(opt, top, opt.cycle);
    // A W- or F-cycle visits the coarse level twice from the fine level too, as from every other
    // level (the fine level has no smoothing between the visits, so the second visit is one more
    // cycle on level `top` from the correction already made: its residual b - A c is the
    // restricted fine residual after w = P~ c, Galerkin). One visit left the error of a single
    // coarse cycle in every fine correction: on Kuhn tetrahedra the linear rate then saturates
    // at 0.52 (V) or 0.40 (W below the fine level only) instead of the two-grid 0.31
    // (benchmarks/tet_twogrid.py).
    if (opt.cycle != CycleType::V) cycle(opt, top, opt.cycle == CycleType::F ? CycleType::V : CycleType::W);
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

  // (on all threads: the serial loops of a cycle hold back the second thread, issue 15)
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

  void cycle(const CycleOptions& opt, int l, CycleType type) {
    // A level below parallel_grains().level_rows rows, and every coarser one, runs on the calling thread: its
    // loops are too short to pay for waking the second thread (a W/F-cycle visits the small
    // levels most often). Every loop gives the same bits on any thread count, so this is a
    // matter of time only.
    if (!serial_ && H_.matrix(l).rows < serial_rows_ && team_size() > 1) {
      const ThreadScope one(1);
      serial_ = true;
      cycle(opt, l, type);
      serial_ = false;
      return;
    }
    Vectors& L = lv_[l];
    if (l == 0) { solve_coarsest(opt); return; }
    const BlockMatrix<d>& A = H_.matrix(l);
    const SweepOrder& order = (*cur_)[l];
    for (int s = 0; s < opt.nu1; ++s) sweep(l, true, order);
    const int visits = type == CycleType::V ? 1 : 2;
    Vectors& C = lv_[l - 1];
    const Prolongation<d>& P = H_.prolongation(l - 1);
    for (int v = 0; v < visits; ++v) {
      // b - A x restricted as it is formed (one pass over A; was a residual pass, then the restriction)
      if (fused_residual_restriction()) restrict_level_residual<d>(A, P, L.x.data(), L.b.data(), C.b.data(), C.r.data());
      else {
        A.residual(L.x.data(), L.b.data(), L.r.data());
        restrict_residual<d>(P, nullptr, L.r.data(), C.b.data(), C.r.data());
      }
      // the coarser level gets the slack that remains on this one
      if (L.any_bounds) restrict_slack<d>(P, L.lo.data(), L.hi.data(), L.x.data(), C.lo.data(), C.hi.data(), L.bounded.data());
      set_bounded(C, L.any_bounds);
      zero(C.x);
      cycle(opt, l - 1, (type == CycleType::F && v == 1) ? CycleType::V : type);
      prolongate_add<d>(P, nullptr, C.x.data(), L.x.data());
    }
    for (int s = 0; s < opt.nu2; ++s) sweep(l, false, order, omega_post_);
  }

  void solve_coarsest(const CycleOptions& opt) {
    Vectors& L = lv_[0];
    const BlockMatrix<d>& A = H_.matrix(0);
    const Index n = (Index)L.x.size();
    Eigen::Map<Eigen::VectorXd> x(L.x.data(), n);
    Eigen::Map<const Eigen::VectorXd> b(L.b.data(), n);
    H_.solve_coarsest(L.b.data(), L.x.data());
    if (!L.any_bounds) return;
    bool inside = true;
    for (Index k = 0; k < n; ++k) inside = inside && x[k] >= L.lo[k] && x[k] <= L.hi[k];
    if (inside) return;
    // Start projected Gauss-Seidel from the clamped solution only if that beats x = 0 in energy,
    // so that the coarse correction never raises the energy.
    for (Index k = 0; k < n; ++k) x[k] = std::max(L.lo[k], std::min(x[k], L.hi[k]));
    A.multiply(L.x.data(), L.r.data());
    double e = 0;
    for (Index k = 0; k < n; ++k) e += 0.5 * x[k] * L.r[k] - b[k] * x[k];
    if (!(e < 0)) x.setZero();
    double scale = 0;
    const SweepOrder lexicographic;
    const SweepOrder& all = opt.ordering == Ordering::Coloured ? coarsest_all_ : lexicographic;
    for (int s = 0; s < opt.coarsest_max_sweeps; ++s) {
      L.r = L.x;
      sweep(0, s % 2 == 0, all);
      double change = 0;
      scale = 0;
      for (Index k = 0; k < n; ++k) {
        change = std::max(change, std::abs(L.x[k] - L.r[k]));
        scale = std::max(scale, std::abs(L.x[k]));
      }
      if (change <= 1e-14 * scale) break;
    }
  }

  Index serial_rows_ = 0;  // parallel_grains().level_rows of this correction (see cycle())
  bool serial_ = false;
  const GalerkinHierarchy<d>& H_;
  std::vector<SweepOrder> order_, coloured_;
  SweepOrder coarsest_all_;                      // every row of the coarsest level, coloured
  const std::vector<SweepOrder>* cur_ = nullptr;  // the orders of the cycle under way
  bool lines_ = false;                            // line sweeps in the cycle under way
  double omega_ = 1.0;                            // over-relaxation of the cycle under way
  double omega_post_ = 1.0;                       // the same of its post-smoothing sweeps
  std::vector<Vectors> lv_;
};

}  // namespace cmg
