// What a solve is asked (SolveOptions) and what it returns (SolveResult with its per-cycle history).
#pragma once
#include <limits>
#include <string>
#include "common.hpp"

namespace cmg {

struct SolveOptions {
  double tol = 1e-11;    // stop when ||u^{k+1} - u^k||_A <= tol
  double rtol = 0;       // ... or <= rtol * (the first cycle's correction norm)
  int max_cycles = 200;  // per solve (per Tresca solve inside the fixed point)
  double fixed_point_tol = 1e-9;
  int fixed_point_max = 100;
  // Algorithm 1 stops as not converging when its relative change of s_n has not fallen below the
  // one of `fixed_point_stall_window` outer iterations before (0: never; it runs to fixed_point_max).
  // A contraction lowers the change every iteration; one that does not fall over several
  // iterations is the paper's "no conv." (large F, small h), found without running to the cap.
  int fixed_point_stall_window = 0;
  double divergence_factor = 1e8;  // a correction this much larger than the first one: diverged
  const double* reference = nullptr;  // canonical u*: record ||u - u*||_A per cycle (costs a matvec)
};

struct CycleRecord {
  int cycle = 0, outer = 0;
  double correction_norm = 0, energy = 0, seconds = 0;
  double error = std::numeric_limits<double>::quiet_NaN();  // ||u - u*||_A when a reference is given
  Index active = 0, stick = 0, slip = 0;
  bool rebuilt = false;
  // TNNMG only (NaN otherwise): the line search's step length and the decrease of the frozen-bound
  // energy by the correction and line search
  double step_size = std::numeric_limits<double>::quiet_NaN();
  double frozen_decrease = std::numeric_limits<double>::quiet_NaN();
  int linear_iterations = 0;  // TNNMG: preconditioner applications (linear cycles) of the correction
  // Algorithm 2 with CycleOptions::petrov_galerkin: 1 where the top coarse level carried the
  // sliding nodes' coupling, 2 where it did and the fallback then switched it off, else 0
  int petrov_galerkin = 0;
};

// Where a solve spends its time (SolveResult::phase_seconds): a handful of clock reads per cycle.
enum class Phase : int { PreSmooth, Linearize, CoarseUpdate, CoarseCorrection, PostSmooth, Norm, Check, Count };
inline const char* phase_name(int p) {
  static const char* names[] = {"presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check"};
  return names[p];
}

struct SolveResult {
  std::vector<double> u;               // displacement, canonical frame, n * d
  std::vector<double> contact_force;   // (A u - f) at contact nodes in their frames, nc * d
  std::vector<double> friction_bound;  // the bound s of each contact node at the end
  std::vector<std::int8_t> state;      // contact nodes: 0 free, 1 stick, 2 slip
  std::vector<CycleRecord> history;
  std::vector<double> outer_changes;   // Algorithm 1: |s_n(u^k) - s_n(u^{k-1})| / |s_n(u^k)| per outer iteration
  bool converged = false;
  std::string status;
  int cycles = 0, outer_iterations = 0, rebuilds = 0;
  double seconds = 0, rebuild_seconds = 0;
  double sweep_check = std::numeric_limits<double>::quiet_NaN();  // ||S(u) - u||_A at the stop
  std::vector<double> phase_seconds;  // indexed by Phase
};

}  // namespace cmg
