// The loop around an iteration step: cycles until the correction norm ||u^{k+1} - u^k||_A meets
// the tolerance (absolute tol, or rtol times the larger of the first correction and ||u||_A), confirmed by one more
// smoothing sweep; divergence and non-finite iterates end it with a message.
//
// A Step provides: double iterate(double* phases, bool& rebuilt) (one cycle, returns the energy
// norm of its correction), void record(CycleRecord&) (energy and contact counts),
// double error_against(const double* canonical_reference), double sweep_change() (||S(u) - u||_A
// for one nonlinear sweep S, NaN where there is nothing to check).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include "base/monitor.hpp"
#include "base/solver_options.hpp"

namespace cmg {

// A stop on the correction norm is confirmed only if one more smoothing sweep moves the iterate by
// at most this many times the tolerance (a sweep changes a converged iterate by about its error,
// which is below the last correction; a limit cycle moves it by orders of magnitude more).
constexpr double kSweepCheckFactor = 100;

inline std::string fmt3(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// The status run_loop leaves when the contraction asks for another step (switch_rate).
inline const char* kSwitchStatus = "switch";

// Whether the last kSwitchWindow corrections of R contract by less than `rate` per cycle.
inline bool contracts_slowly(const SolveResult& R, double rate) {
  const std::size_t n = R.history.size();
  if (rate <= 0 || n < (std::size_t)std::max(kSwitchFrom, kSwitchWindow + 1)) return false;
  const double now = R.history[n - 1].correction_norm, before = R.history[n - 1 - kSwitchWindow].correction_norm;
  return before > 0 && now > std::pow(rate, kSwitchWindow) * before;
}

// Returns whether it converged; R gets the history, the cycle count and the status. With
// switch_rate > 0 (and `may_switch`) it returns early with status kSwitchStatus when the
// corrections contract slowly; a run_loop that `goes_on` after it keeps the relative stop's scale
// and counts its cycles against the same max_cycles (a new loop, as each Tresca solve of
// Algorithm 1, starts both afresh).
// reference: the canonical u* (storage order) whose error ||u - u*||_A each cycle records, or nullptr.
// Whether the line search of the last kSwitchWindow steps was blocked: each moved by less than
// kBlockedStep of its direction (a TNNMG direction that runs into a bound at once).
constexpr double kBlockedStep = 1e-3;
inline bool steps_blocked(const SolveResult& R) {
  const std::size_t n = R.history.size();
  if (n < (std::size_t)kSwitchWindow) return false;
  for (std::size_t k = n - kSwitchWindow; k < n; ++k)
    if (!(R.history[k].step_size < kBlockedStep)) return false;
  return true;
}

template <class Step>
bool run_loop(Step& step, const SolverOptions& opt, const double* reference, Monitor& mon, SolveResult& R, int outer,
              bool may_switch = false, bool goes_on = false, bool back_when_blocked = false) {
  if (!goes_on) R.first_correction = -1;
  double& first = R.first_correction;
  R.status = "no convergence in " + std::to_string(opt.max_cycles) + " cycles";
  for (int it = goes_on ? R.cycles + 1 : 1; it <= opt.max_cycles; ++it) {
    mon.check_interrupt();
    CycleRecord rec;
    rec.correction_norm = step.iterate(mon.phases(), rec.rebuilt);
    rec.cycle = ++R.cycles;
    rec.outer = outer;
    step.record(rec);
    rec.seconds = mon.elapsed();
    if (reference) mon.untimed([&] { rec.error = step.error_against(reference); });
    R.history.push_back(rec);
    mon.report(rec);
    const double cn = rec.correction_norm;
    if (first < 0) first = cn;
    // rtol is relative to the larger of the first correction and the iterate's own energy norm:
    // both scale with the model's units, and the second does not vanish for a warm start that is
    // already nearly the solution (a load step that changes little)
    const double scale = std::max(first, rec.solution_norm);
    if (!std::isfinite(cn) || (cn > kDivergenceFactor * first && first > 0)) {
      R.status = std::isfinite(cn)
                     ? "diverged: correction norm " + fmt3(cn) + " at cycle " + std::to_string(it) + ", " + fmt3(cn / first) +
                           " times the first"
                     : "diverged: the iterate is no longer finite at cycle " + std::to_string(it) +
                           " (overflow: are the load and the material of sensible magnitude?)";
      R.converged = false;
      return false;
    }
    if (cn <= opt.tol || cn <= opt.rtol * scale) {
      // The stopping test cannot tell a solution from an iterate that the cycle maps back onto
      // itself while the smoother keeps moving it (a limit cycle of the nonlinear Gauss-Seidel,
      // seen for Coulomb at large F). A solution is a fixed point of one sweep: check that.
      PhaseClock pc(mon.phases());
      const double sc = step.sweep_change();
      if (!std::isnan(sc)) {
        R.sweep_check = sc;
        pc.lap(Phase::Check);
      }
      const double allowed = kSweepCheckFactor * std::max(opt.tol, opt.rtol * scale);
      if (R.sweep_check > allowed) {
        R.converged = false;
        R.status = "stalled: the cycle returns to an iterate (correction " + fmt3(cn) +
                   ") that one more smoothing sweep still moves by " + fmt3(R.sweep_check) +
                   " (energy norm): a limit cycle of the nonlinear smoother, not a solution";
        return false;
      }
      R.converged = true;
      R.status = "converged";
      return true;
    }
    if ((may_switch && contracts_slowly(R, opt.switch_rate)) || (back_when_blocked && steps_blocked(R))) {
      R.status = kSwitchStatus;
      return false;
    }
  }
  R.converged = false;
  return false;
}

}  // namespace cmg
