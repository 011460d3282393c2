// The compiled core of contactmg: the module, its parts by subject (bind_fem.cpp, bind_solver.cpp,
// bind_local_levels.cpp: one rank's part of a distributed cycle; bind_distributed.cpp: exact sums;
// bind_distributed_levels.cpp: the coarse levels of a distributed cycle; bind_anderson.cpp: its
// Anderson mixing; bind_loop.cpp: the solver's loop around a step given as callables) and
// the submodule `testing` of the entry points only tests and benchmarks call (bind_testing.cpp).
#include <cstdlib>  // defines __GLIBC__ where it is glibc
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include "bindings/common.hpp"
#include "bindings/options.hpp"
#include "base/parallel.hpp"

PYBIND11_MODULE(_core, m) {
  using namespace cmg;
  using namespace cmg::bindings;
  m.doc() = "contactmg compiled core";
#ifdef __GLIBC__
  // Allocations of 1 MiB and more get pages of their own and go back to the system when freed.
  // glibc's default threshold grows to 32 MiB after the first large free, and then the level-sized
  // temporaries of setup and of a solve's results stayed in the heap: 28 MiB of the peak at level 9
  // (docs/dev/decisions/0011-memory-release.md).
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  bind_fem(m);
  bind_solver(m);
  bind_local_levels(m);
  bind_distributed(m);
  bind_distributed_levels(m);
  bind_anderson(m);
  bind_loop(m);
  m.def("openmp", [] { return have_openmp(); }, "whether the core was built with OpenMP threads");
  m.def("max_threads", [] { return max_threads(); }, "the cores the threads of a solve may use (threads=0)");
  m.def("solver_option_defaults", [] { return bindings::options_to_dict(SolverOptions()); },
        "every field of the core's SolverOptions with its default (the options a solve takes)");
  py::module_ testing = m.def_submodule("testing", "entry points for tests and benchmarks: the core's pieces on their own");
  bind_testing(testing);
}
