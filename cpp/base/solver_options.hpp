// Everything a solve can be asked: the method, the shape of its cycles, the smoothing, the stop
// rules and the run-time choices (threads, sweep order), in one struct validated in one place.
// Plain data: the cycles (mg/) and the steps (steps/) read the fields they need. The Python
// package mirrors it field for field (contactmg.solve.options.SolverOptions); the bindings turn a
// dict with these field names into it and refuse any other key.
#pragma once
#include <cmath>
#include <string>
#include "base/common.hpp"

namespace cmg {

// nmg: monotone multigrid cycles (Algorithm 2 for Coulomb friction); tnnmg: truncated nonsmooth
// Newton multigrid; fixed-point: Algorithm 1 (Coulomb only: Tresca solves by monotone multigrid).
enum class Method : int { Nmg = 0, Tnnmg = 1, FixedPoint = 2 };
enum class CycleType : int { V = 0, W = 1, F = 2 };
// The order of every Gauss-Seidel sweep: lexicographic, or by colours of the block graph (the rows
// of one colour at once, on all threads): coloured greedily in row order (Coloured) or in the hashed
// order of the node numbers (Hashed: the distributed solver's colours, base/hashed_priority.hpp).
enum class Ordering : int { Lexicographic = 0, Coloured = 1, Hashed = 2 };
// The linear correction of a TNNMG step (steps/tnnmg_step.hpp): the coarse cycle alone (the fine
// level smoothed only by the nonlinear sweeps), one truncated linear cycle on the fine level
// (mg/truncated_linear_cycle.hpp), or PCG preconditioned by that cycle (mg/pcg.hpp).
enum class LinearCorrection : int { Coarse = 0, Cycle = 1, Pcg = 2 };

inline Method parse_method(const std::string& s) {
  if (s == "nmg") return Method::Nmg;
  if (s == "tnnmg") return Method::Tnnmg;
  if (s == "fixed-point") return Method::FixedPoint;
  throw InputError("method: unknown method '" + s + "' (expected nmg, tnnmg or fixed-point)");
}
inline const char* method_name(Method m) {
  return m == Method::Tnnmg ? "tnnmg" : m == Method::FixedPoint ? "fixed-point" : "nmg";
}
inline CycleType parse_cycle(const std::string& s) {
  if (s == "V") return CycleType::V;
  if (s == "W") return CycleType::W;
  if (s == "F") return CycleType::F;
  throw InputError("cycle: unknown cycle type '" + s + "' (expected V, W or F)");
}
inline const char* cycle_name(CycleType t) { return t == CycleType::V ? "V" : t == CycleType::W ? "W" : "F"; }
inline Ordering parse_ordering(const std::string& s) {
  if (s == "lexicographic") return Ordering::Lexicographic;
  if (s == "coloured" || s == "colored") return Ordering::Coloured;
  if (s == "hashed") return Ordering::Hashed;
  throw InputError("ordering: unknown ordering '" + s + "' (expected lexicographic, coloured or hashed)");
}
inline const char* ordering_name(Ordering o) {
  return o == Ordering::Coloured ? "coloured" : o == Ordering::Hashed ? "hashed" : "lexicographic";
}
inline LinearCorrection parse_linear_correction(const std::string& s) {
  if (s == "coarse") return LinearCorrection::Coarse;
  if (s == "cycle") return LinearCorrection::Cycle;
  if (s == "pcg") return LinearCorrection::Pcg;
  throw InputError("linear: unknown linear correction '" + s + "' (expected coarse, cycle or pcg)");
}
inline const char* linear_correction_name(LinearCorrection c) {
  return c == LinearCorrection::Coarse ? "coarse" : c == LinearCorrection::Cycle ? "cycle" : "pcg";
}

// Projected Gauss-Seidel sweeps on the coarsest level when its exact solve violates the bounds.
// Each sweep lowers the energy, so any number keeps the cycle monotone; on the Hertz benchmark
// (triangles levels 3-7, quads 3-6, F = 0.4 and 5) 10, 50, 200 and 2000 gave the same cycle
// counts, and 2000 (run to a relative change of 1e-14) cost 84 % of a quad level-3 solve.
constexpr int kCoarsestMaxSweeps = 50;
// Newton steps of the exact box solve that follows them on a coarsest level with free motions
// (mg/box_qp.hpp): each finds more of the contact set, a handful is the rule.
constexpr int kCoarsestNewtonSteps = 30;
// The switch to TNNMG (switch_rate) looks at the contraction of the last kSwitchWindow cycles, from
// cycle kSwitchFrom on (the first cycles settle the contact set and contract unevenly).
constexpr int kSwitchFrom = 5, kSwitchWindow = 3;
// A correction this many times larger than the first one ends a solve as diverged.
constexpr double kDivergenceFactor = 1e8;

// The defaults are the Python package's (contactmg.solve.options.SolverOptions; a test checks
// every field against it), so a field a caller leaves out means the same in both.
struct SolverOptions {
  Method method = Method::Nmg;
  CycleType cycle = CycleType::F;
  int nu1 = 3, nu2 = 3;  // pre- and post-smoothing sweeps
  double tol = 0;        // stop when ||u^{k+1} - u^k||_A <= tol
  double rtol = 1e-10;   // ... or <= rtol * max(the first cycle's correction norm, ||u||_A)
  int max_cycles = 200;  // per solve (per Tresca solve inside the fixed point)
  // Over-relaxation of the unbounded block solves of every Gauss-Seidel sweep (fine level: nodes
  // without contact; coarse levels: rows without bounds); 1 = plain Gauss-Seidel. Nodal block
  // Gauss-Seidel on P1 elasticity levels off near 0.34 per F(3,3) cycle, the symmetric over-relaxed
  // sweep costs the same and contracts by 0.22 with 1.4 on the adaptive Hertz levels
  // (docs/dev/decisions/0005-over-relaxation.md). Any 0 < omega < 2 keeps each such step an energy
  // decrease (a node's quadratic falls by (omega - omega^2 / 2) times its exact minimum), so the
  // monotone cycles stay monotone; bounded rows and contact nodes keep their exact solves.
  double omega = 1.0;
  // Over-relaxation of the post-smoothing sweeps only (the backward ones after the coarse
  // correction, fine and coarse levels; the coarsest level's sweeps keep omega); 0 = omega.
  // Between two coarse corrections the smoother is nu2 backward sweeps then nu1 forward ones, and
  // splitting the relaxation contracts P1 elasticity's linear V(3,3) by 0.14 on the unit square
  // level 7 where the symmetric 1.3 gives 0.26, at the same cost
  // (docs/dev/decisions/0005-over-relaxation.md). Any 0 < omega_post < 2 keeps the cycles monotone.
  double omega_post = 0.0;
  double fixed_point_tol = 1e-9;  // Algorithm 1: relative change of s_n at which it stops
  int fixed_point_max = 100;      // Algorithm 1: outer iterations at most
  // Algorithm 1 stops as not converging when its relative change of s_n has not fallen below the
  // one of `fixed_point_stall_window` outer iterations before (0: never; it runs to fixed_point_max).
  // A contraction lowers the change every iteration; one that does not fall over several
  // iterations is the paper's "no conv." (large F, small h), found without running to the cap.
  int fixed_point_stall_window = 0;
  // TNNMG only: its linear correction, and whether that correction smooths by lines
  // (mg/line_smoother.hpp) on the levels whose matrix has lines (elsewhere lines are points).
  LinearCorrection linear = LinearCorrection::Pcg;
  bool lines = true;
  int threads = 0;  // threads of the sweeps, products and norms; 0: all cores (the result does not depend on it)
  // Gauss-Seidel order of every sweep (fine nonlinear, coarse projected). At construction it also
  // decides the storage: coloured stores every level but the coarsest by colours
  // (mg/renumbering.hpp), so that a coloured sweep streams memory.
  Ordering ordering = Ordering::Coloured;
  // Algorithm 2 (a law whose coarse problem freezes a bound): in every cycle but the first, level
  // L-1's matrix also carries the sliding nodes' Petrov-Galerkin coupling, with a fallback to the
  // symmetric one (steps/petrov_galerkin_coupling.hpp). Off by default: that coarse correction is
  // not an energy descent; it pays on 2D adaptive hierarchies
  // (docs/dev/decisions/0006-petrov-galerkin-coupling.md).
  bool petrov_galerkin = false;
  // Algorithm 2: one more visit of the contact nodes after every fine sweep, the sliding ones in
  // the upwind order of the Coulomb Jacobian (steps/upwind_contact_sweep.hpp;
  // docs/dev/decisions/0007-upwind-contact-sweep.md).
  bool upwind_contact_sweep = false;
  // The coarse correction without the gap bounds of the inactive contact nodes, projected onto the
  // gap at the fine level and taken with the exact line search of the frozen-bound energy. Where a
  // contact frame is not a signed permutation of the axes, the monotone restriction turns a node's
  // gap bound into bounds on every coarse component it touches, and a node closing on the obstacle
  // holds back the coarse motions around it (docs/dev/decisions/0008-projected-coarse-correction.md).
  // Every step still lowers the frozen energy.
  bool projected_coarse_correction = false;
  // Algorithm 2 only: when > 0, a solve whose corrections contract by less than this per cycle
  // (their geometric mean ratio over kSwitchWindow cycles, from cycle kSwitchFrom on) goes on with
  // TNNMG steps from its iterate, in the same loop and under the same stop. The monotone coarse
  // obstacles of coarse spaces made from a fine mesh alone hold back some coarse corrections
  // (docs/dev/decisions/0029-geometric-coarsening.md); TNNMG's linear correction has none.
  double switch_rate = 0;

  double post_omega() const { return omega_post > 0 ? omega_post : omega; }

  // Throws InputError naming the first field with a bad value.
  void validate() const {
    if (nu1 < 0 || nu2 < 0 || nu1 + nu2 < 1 || nu1 > 100 || nu2 > 100)
      throw InputError("nu1, nu2: smoothing steps must lie in 0..100 with nu1 + nu2 >= 1 (got " + std::to_string(nu1) +
                       ", " + std::to_string(nu2) + ")");
    if (!(tol >= 0) || !std::isfinite(tol)) throw InputError("tol must be a finite number >= 0");
    if (!(rtol >= 0) || !std::isfinite(rtol)) throw InputError("rtol must be a finite number >= 0");
    if (!(tol > 0 || rtol > 0)) throw InputError("tol, rtol: one of them must be > 0");
    if (max_cycles < 1) throw InputError("max_cycles must be at least 1");
    if (!(omega > 0 && omega < 2)) throw InputError("omega: the over-relaxation must lie in (0, 2)");
    if (!(omega_post == 0 || (omega_post > 0 && omega_post < 2)))
      throw InputError("omega_post: the over-relaxation must lie in (0, 2) (0: the same as omega)");
    if (!(fixed_point_tol >= 0) || !std::isfinite(fixed_point_tol))
      throw InputError("fixed_point_tol must be a finite number >= 0");
    if (fixed_point_max < 1) throw InputError("fixed_point_max must be at least 1");
    if (fixed_point_stall_window < 0) throw InputError("fixed_point_stall_window must be >= 0 (0: off)");
    if (threads < 0) throw InputError("threads must be >= 0 (0: all cores)");
    if (!(switch_rate >= 0 && switch_rate < 1)) throw InputError("switch_rate must lie in [0, 1) (0: off)");
    const char* cycle_choice = petrov_galerkin ? "petrov_galerkin"
                               : upwind_contact_sweep ? "upwind_contact_sweep"
                               : projected_coarse_correction ? "projected_coarse_correction"
                                                             : nullptr;
    if (switch_rate > 0 && method != Method::Nmg)
      throw InputError(std::string("switch_rate: the switch to TNNMG is taken from method nmg, not ") + method_name(method));
    if (cycle_choice && method != Method::Nmg)
      throw InputError(std::string(cycle_choice) + " is a choice of the monotone multigrid cycle (method nmg), not " +
                       method_name(method));
  }
};

// Every field of SolverOptions by name, once: the bindings read and write the options dict from
// this list (bindings/options.cpp), and the Python package's SolverOptions is checked against it.
#define CMG_SOLVER_OPTION_FIELDS(X)                                                                              \
  X(method) X(cycle) X(nu1) X(nu2) X(tol) X(rtol) X(max_cycles) X(omega) X(omega_post) X(fixed_point_tol)        \
  X(fixed_point_max) X(fixed_point_stall_window) X(linear) X(lines) X(threads) X(ordering) X(petrov_galerkin)     \
  X(upwind_contact_sweep) X(projected_coarse_correction) X(switch_rate)

}  // namespace cmg
