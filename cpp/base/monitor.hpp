// The monitor of a solve: the clock (with the time spent on diagnostics kept out), the phase
// timings, the Ctrl-C check and the optional per-cycle progress callback.
#pragma once
#include <chrono>
#include <functional>
#include "base/solve_result.hpp"

namespace cmg {

class Monitor {
 public:
  using clock = std::chrono::steady_clock;

  std::function<bool()> interrupted;                 // true: stop (Ctrl-C); checked once per cycle
  std::function<void(const CycleRecord&)> progress;  // called after every cycle

  void start() {
    t0_ = clock::now();
    untimed_ = 0;
    std::fill(std::begin(phase_), std::end(phase_), 0.0);
  }
  double elapsed() const { return std::chrono::duration<double>(clock::now() - t0_).count() - untimed_; }
  void check_interrupt() const {
    if (interrupted && interrupted()) throw Interrupted();
  }
  // Runs f outside the timings (error recording, the progress callback).
  template <class F>
  void untimed(F&& f) {
    const auto t = clock::now();
    f();
    untimed_ += std::chrono::duration<double>(clock::now() - t).count();
  }
  void report(const CycleRecord& r) {
    if (progress) untimed([&] { progress(r); });
  }
  double* phases() { return phase_; }
  std::vector<double> phase_seconds() const { return std::vector<double>(std::begin(phase_), std::end(phase_)); }

 private:
  clock::time_point t0_ = clock::now();
  double untimed_ = 0;
  double phase_[(int)Phase::Count] = {};
};

// Laps of one cycle: lap(p) adds the time since the previous lap to phase p.
struct PhaseClock {
  using clock = std::chrono::steady_clock;
  double* acc;
  clock::time_point t = clock::now();
  explicit PhaseClock(double* a) : acc(a) {}
  void lap(Phase p) {
    const auto now = clock::now();
    acc[(int)p] += std::chrono::duration<double>(now - t).count();
    t = now;
  }
};

}  // namespace cmg
