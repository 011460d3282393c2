// What a solve returns: SolveResult with its per-cycle history.
#pragma once
#include <limits>
#include <string>
#include "base/common.hpp"

namespace cmg {

struct CycleRecord {
  int cycle = 0, outer = 0;
  double correction_norm = 0, energy = 0, seconds = 0;
  double solution_norm = 0;  // ||u||_A of the iterate after the cycle: the scale of a relative stop
  double error = std::numeric_limits<double>::quiet_NaN();  // ||u - u*||_A when a reference is given
  Index active = 0, stick = 0, slip = 0;
  bool rebuilt = false;
  // TNNMG only (NaN otherwise): the line search's step length and the decrease of the frozen-bound
  // energy by the correction and line search
  double step_size = std::numeric_limits<double>::quiet_NaN();
  double frozen_decrease = std::numeric_limits<double>::quiet_NaN();
  int linear_iterations = 0;  // TNNMG: preconditioner applications (linear cycles) of the correction
  // Algorithm 2 with SolverOptions::petrov_galerkin: 1 where the top coarse level carried the
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
  // the first cycle's correction norm (the relative stop's scale; a loop that goes on with another
  // step keeps it), -1 before the first cycle
  double first_correction = -1;
  int switched_at = 0;  // the last Algorithm 2 cycle before TNNMG took over (switch_rate), 0: none
};

}  // namespace cmg
