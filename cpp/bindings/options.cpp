// The options dict of the solver's constructor and solve(): the field names of SolverOptions
// (base/solver_options.hpp), each value checked for its type here and for its range by
// SolverOptions::validate().
#include <algorithm>
#include <limits>
#include "bindings/options.hpp"

namespace cmg::bindings {

namespace {

bool is_integer(py::handle v) { return !PyBool_Check(v.ptr()) && PyIndex_Check(v.ptr()); }
bool is_real(py::handle v) {
  if (PyBool_Check(v.ptr())) return false;
  return PyFloat_Check(v.ptr()) || PyIndex_Check(v.ptr()) || py::isinstance(v, py::module_::import("numbers").attr("Real"));
}

int int_option(py::handle v, const char* name) {
  if (!is_integer(v)) throw InputError(std::string(name) + " must be an integer, got " + py::repr(v).cast<std::string>());
  const long long x = v.cast<long long>();
  if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max())
    throw InputError(std::string(name) + " is out of range: " + std::to_string(x));
  return (int)x;
}
double real_option(py::handle v, const char* name) {
  if (!is_real(v)) throw InputError(std::string(name) + " must be a number, got " + py::repr(v).cast<std::string>());
  return py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
}
bool bool_option(py::handle v, const char* name) {
  if (!PyBool_Check(v.ptr()) && !py::isinstance(v, py::module_::import("numpy").attr("bool_")))
    throw InputError(std::string(name) + " must be True or False, got " + py::repr(v).cast<std::string>());
  return py::bool_(py::reinterpret_borrow<py::object>(v)).cast<bool>();
}
std::string str_option(py::handle v, const char* name) {
  if (!py::isinstance<py::str>(v)) throw InputError(std::string(name) + " must be a string, got " + py::repr(v).cast<std::string>());
  return v.cast<std::string>();
}

}  // namespace

// `base` with the keys of `options` (a dict, or None) set; a key of value None keeps base's value.
// An unknown key or a bad value raises InputError naming it; the result is validated.
SolverOptions options_from_dict(py::handle options, SolverOptions o) {
  if (!options.is_none()) {
    if (!py::isinstance<py::dict>(options)) throw InputError("options must be a dict (SolverOptions field -> value)");
    for (auto item : py::reinterpret_borrow<py::dict>(options)) {
      if (!py::isinstance<py::str>(item.first)) throw InputError("an option name must be a string");
      const std::string k = item.first.cast<std::string>();
      const py::handle v = item.second;
      const char* n = k.c_str();
      if (v.is_none()) {
        static const char* known[] = {"method", "cycle", "nu1", "nu2", "tol", "rtol", "max_cycles", "omega", "omega_post",
                                      "fixed_point_tol", "fixed_point_max", "fixed_point_stall_window", "linear", "lines",
                                      "threads", "ordering", "petrov_galerkin", "upwind_contact_sweep",
                                      "projected_coarse_correction", "switch_rate"};
        if (std::find_if(std::begin(known), std::end(known), [&](const char* q) { return k == q; }) == std::end(known))
          throw InputError("unknown option '" + k + "'");
        continue;
      }
      if (k == "method") o.method = parse_method(str_option(v, n));
      else if (k == "cycle") o.cycle = parse_cycle(str_option(v, n));
      else if (k == "nu1") o.nu1 = int_option(v, n);
      else if (k == "nu2") o.nu2 = int_option(v, n);
      else if (k == "tol") o.tol = real_option(v, n);
      else if (k == "rtol") o.rtol = real_option(v, n);
      else if (k == "max_cycles") o.max_cycles = int_option(v, n);
      else if (k == "omega") o.omega = real_option(v, n);
      else if (k == "omega_post") o.omega_post = real_option(v, n);
      else if (k == "fixed_point_tol") o.fixed_point_tol = real_option(v, n);
      else if (k == "fixed_point_max") o.fixed_point_max = int_option(v, n);
      else if (k == "fixed_point_stall_window") o.fixed_point_stall_window = int_option(v, n);
      else if (k == "linear") o.linear = parse_linear_correction(str_option(v, n));
      else if (k == "lines") o.lines = bool_option(v, n);
      else if (k == "threads") o.threads = int_option(v, n);
      else if (k == "ordering") o.ordering = parse_ordering(str_option(v, n));
      else if (k == "petrov_galerkin") o.petrov_galerkin = bool_option(v, n);
      else if (k == "upwind_contact_sweep") o.upwind_contact_sweep = bool_option(v, n);
      else if (k == "projected_coarse_correction") o.projected_coarse_correction = bool_option(v, n);
      else if (k == "switch_rate") o.switch_rate = real_option(v, n);
      else throw InputError("unknown option '" + k + "'");
    }
  }
  o.validate();
  return o;
}

// The options a solve used, as a dict of SolverOptions field names.
py::dict options_to_dict(const SolverOptions& o) {
  py::dict out;
  out["method"] = method_name(o.method); out["cycle"] = cycle_name(o.cycle); out["nu1"] = o.nu1; out["nu2"] = o.nu2;
  out["tol"] = o.tol; out["rtol"] = o.rtol; out["max_cycles"] = o.max_cycles; out["omega"] = o.omega;
  out["omega_post"] = o.omega_post; out["fixed_point_tol"] = o.fixed_point_tol; out["fixed_point_max"] = o.fixed_point_max;
  out["fixed_point_stall_window"] = o.fixed_point_stall_window; out["linear"] = linear_correction_name(o.linear);
  out["lines"] = o.lines; out["threads"] = o.threads; out["ordering"] = ordering_name(o.ordering);
  out["petrov_galerkin"] = o.petrov_galerkin; out["upwind_contact_sweep"] = o.upwind_contact_sweep;
  out["projected_coarse_correction"] = o.projected_coarse_correction;
  out["switch_rate"] = o.switch_rate;
  return out;
}

}  // namespace cmg::bindings
