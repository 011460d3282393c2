// The solver options as a Python dict and back (bindings/options.cpp).
#pragma once
#include "bindings/common.hpp"
#include "base/solver_options.hpp"

namespace cmg::bindings {

// `base` with the keys of `options` (a dict, or None) set; a key of value None keeps base's value.
// An unknown key or a bad value raises InputError (ValueError) naming it; the result is validated.
SolverOptions options_from_dict(py::handle options, SolverOptions base);
// The options as a dict of SolverOptions field names.
py::dict options_to_dict(const SolverOptions& o);

}  // namespace cmg::bindings
