// What every binding file shares: the numpy array types, the shape check, the conversions of
// vectors to numpy arrays and the one converter of the solver's cycle records (the progress
// callback's dict and the result's history columns list the same fields).
#pragma once
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <string>
#include <vector>
#include "base/exact_sum.hpp"
#include "mg/line_smoother.hpp"
#include "base/solve_result.hpp"

namespace cmg::bindings {

namespace py = pybind11;
using DArr = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IArr = py::array_t<Index, py::array::c_style | py::array::forcecast>;
using BArr = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

template <class A>
void require_shape(const A& a, const char* name, std::initializer_list<py::ssize_t> shape) {
  std::vector<py::ssize_t> s(shape);
  bool ok = a.ndim() == (py::ssize_t)s.size();
  for (std::size_t k = 0; ok && k < s.size(); ++k) ok = s[k] < 0 || a.shape(k) == s[k];
  if (!ok) {
    std::string want = "(", got = "(";
    for (std::size_t k = 0; k < s.size(); ++k) want += (s[k] < 0 ? std::string("*") : std::to_string(s[k])) + (k + 1 < s.size() ? ", " : "");
    for (py::ssize_t k = 0; k < a.ndim(); ++k) got += std::to_string(a.shape(k)) + (k + 1 < a.ndim() ? ", " : "");
    throw InputError(std::string(name) + " has shape " + got + ") but " + want + ") is expected");
  }
}

template <class T>
py::array_t<T> to_numpy(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// The vector handed over to numpy without a copy (the array owns it).
inline py::array_t<double> moved_to_numpy(std::vector<double>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<double>(std::move(v));
  py::capsule free_it(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(shape, owned->data(), free_it);
}

// An exact local sum as the Python integer T with sum = T * 2^kExpMin (contactmg.distributed.exchange
// combines the ranks' integers and rounds once).
inline py::int_ exact_int(ExactAccumulator& acc) {
  const std::vector<unsigned char> b = acc.to_bytes();
  const py::object from_bytes = py::reinterpret_borrow<py::object>((PyObject*)&PyLong_Type).attr("from_bytes");
  return from_bytes(py::bytes(reinterpret_cast<const char*>(b.data()), b.size()), "little", py::arg("signed") = true);
}

// The lines of a line smoother as a list of node-id arrays, each in chain order.
inline py::list lines_to_list(const LineSet& L) {
  py::list out;
  for (Index k = 0; k < L.num_lines(); ++k)
    out.append(to_numpy(std::vector<Index>(L.nodes.begin() + L.ptr[k], L.nodes.begin() + L.ptr[k + 1]),
                        {(py::ssize_t)(L.ptr[k + 1] - L.ptr[k])}));
  return out;
}

// f(name, value) for every field of a cycle record, each value in the type of its history column.
template <class F>
void visit_record(const CycleRecord& r, F&& f) {
  f("cycle", r.cycle);
  f("outer", r.outer);
  f("correction_norm", r.correction_norm);
  f("solution_norm", r.solution_norm);
  f("energy", r.energy);
  f("seconds", r.seconds);
  f("error", r.error);
  f("active", r.active);
  f("stick", r.stick);
  f("slip", r.slip);
  f("rebuilt", r.rebuilt);
  f("step_size", r.step_size);
  f("frozen_decrease", r.frozen_decrease);
  f("linear_iterations", r.linear_iterations);
  f("petrov_galerkin", (std::int8_t)r.petrov_galerkin);
}

// One record as a dict (the progress callback's argument).
inline py::dict record_to_dict(const CycleRecord& r) {
  py::dict o;
  visit_record(r, [&](const char* name, auto v) { o[name] = v; });
  return o;
}

// The records as one numpy array per field (the result's history).
inline py::dict history_to_dict(const std::vector<CycleRecord>& H) {
  const py::ssize_t h = (py::ssize_t)H.size();
  py::dict out;
  std::vector<py::array> columns;
  visit_record(CycleRecord(), [&](const char* name, auto v) {
    columns.push_back(py::array_t<decltype(v)>(h));
    out[name] = columns.back();
  });
  for (py::ssize_t k = 0; k < h; ++k) {
    std::size_t c = 0;
    visit_record(H[k], [&](const char*, auto v) { static_cast<decltype(v)*>(columns[c++].mutable_data())[k] = v; });
  }
  return out;
}

// The parts of the module, each binding its subject.
void bind_fem(py::module_& m);
void bind_solver(py::module_& m);
void bind_local_levels(py::module_& m);
void bind_testing(py::module_& m);
void bind_distributed(py::module_& m);
void bind_anderson(py::module_& m);
void bind_distributed_levels(py::module_& m);
void bind_loop(py::module_& m);

}  // namespace cmg::bindings
