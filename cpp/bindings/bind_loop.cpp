// The one loop (solver/loop_solver.hpp) around a step given as Python callables, and the one
// multigrid recursion (mg/cycle_recursion.hpp) over levels given as a Python object: the
// distributed solve's cycle takes the serial solver's stop, sweep check, divergence test, messages
// and recursion from here, not from copies of them.
#include <limits>
#include <utility>
#include "bindings/options.hpp"
#include "mg/cycle_recursion.hpp"
#include "solver/loop_solver.hpp"

namespace cmg::bindings {

namespace {

// A Step of run_loop whose cycle, record and sweep check are Python callables: iterate() -> the
// correction's energy norm; record() -> a dict with energy, solution_norm, active, stick, slip and
// rebuilt; sweep_change() -> ||S(u) - u||_A. On MPI ranks each returns the same value on every rank
// (exact sums), so every rank's loop takes the same decisions.
struct CallableStep {
  py::function iterate_, record_, sweep_change_;

  double iterate(double*, bool& rebuilt) {
    const double cn = iterate_().cast<double>();
    rebuilt = false;
    return cn;
  }
  void record(CycleRecord& r) {
    const py::dict o = record_();
    r.energy = o["energy"].cast<double>();
    r.solution_norm = o["solution_norm"].cast<double>();
    r.active = o["active"].cast<Index>();
    r.stick = o["stick"].cast<Index>();
    r.slip = o["slip"].cast<Index>();
    r.rebuilt = o.contains("rebuilt") && o["rebuilt"].cast<bool>();
  }
  double error_against(const double*) { return std::numeric_limits<double>::quiet_NaN(); }
  double sweep_change() { return sweep_change_().cast<double>(); }
};

// The level operations of mg/cycle_recursion.hpp as the methods of a Python object.
struct PythonLevels {
  py::object levels;

  template <class Body>
  void enter(int, Body&& body) { body(); }
  void pre_smooth(int l) { levels.attr("pre_smooth")(l); }
  void post_smooth(int l) { levels.attr("post_smooth")(l); }
  void restrict_down(int l) { levels.attr("restrict_down")(l); }
  void prolong_up(int l) { levels.attr("prolong_up")(l); }
  void solve_coarsest() { levels.attr("solve_coarsest")(); }
};

}  // namespace

void bind_loop(py::module_& m) {
  m.def("multigrid_cycle", [](py::object levels, int nu1, int nu2, int top, const std::string& cycle) {
           if (nu1 < 0 || nu2 < 0 || nu1 + nu2 < 1) throw InputError("nu1, nu2 must be >= 0 with nu1 + nu2 >= 1");
           if (top < 0) throw InputError("top must be a level (>= 0)");
           PythonLevels L{std::move(levels)};
           top_level_cycles(L, nu1, nu2, top, parse_cycle(cycle));
         }, py::arg("levels"), py::arg("nu1"), py::arg("nu2"), py::arg("top"), py::arg("cycle"),
         "The coarse correction's multigrid recursion from level `top` (mg/cycle_recursion.hpp: the serial "
         "cycle's), over `levels`: an object with pre_smooth(l), post_smooth(l), restrict_down(l), prolong_up(l) "
         "and solve_coarsest()");
  m.def("run_loop", [](py::function iterate, py::function record, py::function sweep_change, py::object options,
                       py::object progress) {
           if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw InputError("progress must be callable or None");
           const SolverOptions opt = options_from_dict(options, SolverOptions());
           CallableStep step{std::move(iterate), std::move(record), std::move(sweep_change)};
           Monitor mon;
           if (!progress.is_none()) mon.progress = [&progress](const CycleRecord& r) { progress(record_to_dict(r)); };
           mon.interrupted = [] { return PyErr_CheckSignals() != 0; };
           mon.start();
           SolveResult R;
           try {
             run_loop(step, opt, nullptr, mon, R, 0);
           } catch (const Interrupted&) {
             throw py::error_already_set();
           }
           py::dict out;
           out["converged"] = R.converged;
           out["status"] = R.status;
           out["cycles"] = R.cycles;
           out["sweep_check"] = R.sweep_check;
           out["seconds"] = mon.elapsed();
           out["history"] = history_to_dict(R.history);
           return out;
         }, py::arg("iterate"), py::arg("record"), py::arg("sweep_change"), py::arg("options") = py::dict(),
         py::arg("progress") = py::none(),
         "The solver's loop (tol / rtol stop confirmed by one more sweep, divergence, max_cycles: the fields of "
         "`options`) around a step given as callables: iterate() -> correction norm, record() -> dict (energy, "
         "solution_norm, active, stick, slip), sweep_change() -> float. Returns converged, status, cycles, "
         "sweep_check, seconds and the history (one array per field)");
}

}  // namespace cmg::bindings
