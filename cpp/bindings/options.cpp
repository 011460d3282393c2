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

// One reader and one writer per field type: the field list (CMG_SOLVER_OPTION_FIELDS) does the rest.
void read(py::handle v, const char* n, int& x) { x = int_option(v, n); }
void read(py::handle v, const char* n, double& x) { x = real_option(v, n); }
void read(py::handle v, const char* n, bool& x) { x = bool_option(v, n); }
void read(py::handle v, const char* n, Method& x) { x = parse_method(str_option(v, n)); }
void read(py::handle v, const char* n, CycleType& x) { x = parse_cycle(str_option(v, n)); }
void read(py::handle v, const char* n, Ordering& x) { x = parse_ordering(str_option(v, n)); }
void read(py::handle v, const char* n, LinearCorrection& x) { x = parse_linear_correction(str_option(v, n)); }
py::object value(int x) { return py::int_(x); }
py::object value(double x) { return py::float_(x); }
py::object value(bool x) { return py::bool_(x); }
py::object value(Method x) { return py::str(method_name(x)); }
py::object value(CycleType x) { return py::str(cycle_name(x)); }
py::object value(Ordering x) { return py::str(ordering_name(x)); }
py::object value(LinearCorrection x) { return py::str(linear_correction_name(x)); }

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
      bool known = false;
#define CMG_READ(name)                                \
  if (k == #name) {                                   \
    known = true;                                     \
    if (!v.is_none()) read(v, #name, o.name);         \
  }
      CMG_SOLVER_OPTION_FIELDS(CMG_READ)
#undef CMG_READ
      if (!known) throw InputError("unknown option '" + k + "'");
    }
  }
  o.validate();
  return o;
}

// The options a solve used, as a dict of SolverOptions field names.
py::dict options_to_dict(const SolverOptions& o) {
  py::dict out;
#define CMG_WRITE(name) out[#name] = value(o.name);
  CMG_SOLVER_OPTION_FIELDS(CMG_WRITE)
#undef CMG_WRITE
  return out;
}

}  // namespace cmg::bindings
