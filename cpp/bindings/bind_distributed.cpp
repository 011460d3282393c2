// The local halves of the distributed exact sums: this rank's terms summed exactly, as the Python
// integer T with sum = T * 2^kExpMin that contactmg.distributed.exchange combines over the ranks.
#include "bindings/common.hpp"

namespace cmg::bindings {

namespace {

std::string shape_of(const DArr& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += std::to_string(a.shape(k)) + (k + 1 < a.ndim() ? ", " : "");
  return s + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

void bind_distributed(py::module_& m) {
  m.def("exact_sum_limbs", [](DArr x) {
           ExactAccumulator acc;
           {
             py::gil_scoped_release release;
             acc = exact_sum(x.data(), (std::int64_t)x.size(), "the array");
           }
           return exact_int(acc);
         }, py::arg("x"),
         "The sum of all entries of x (any shape) exactly, as the integer T with sum = T * 2^-2252 (the "
         "local_fixed_point_sum of contactmg.distributed.exchange). ValueError for a non-finite entry.");
  m.def("exact_dot_limbs", [](DArr x, DArr y, py::object rows) {
           if (x.ndim() != y.ndim() || !std::equal(x.shape(), x.shape() + x.ndim(), y.shape()))
             throw InputError("exact_dot needs arrays of one length (one shape), got " + shape_of(x) + " and " + shape_of(y));
           BArr flags;
           std::int64_t width = 1;
           if (!rows.is_none()) {
             flags = rows.cast<BArr>();
             if (x.ndim() < 1 || flags.ndim() != 1 || flags.size() != x.shape(0))
               throw InputError("rows needs one flag per row of x, got " + std::to_string(flags.size()) + " for shape " + shape_of(x));
             width = x.shape(0) ? (std::int64_t)x.size() / x.shape(0) : 1;
           }
           ExactAccumulator acc;
           {
             py::gil_scoped_release release;
             acc = exact_dot(x.data(), y.data(), (std::int64_t)x.size(), "the first array", "the second array",
                             rows.is_none() ? nullptr : flags.data(), width);
           }
           return exact_int(acc);
         }, py::arg("x"), py::arg("y"), py::arg("rows") = py::none(),
         "sum(x * y) over all entries (x and y of one shape; with rows, a flag per row of x: the flagged rows' "
         "entries only) exactly, each product exact, as the integer T with sum = T * 2^-2252 (the "
         "local_fixed_point_dot of contactmg.distributed.exchange). ValueError for a non-finite entry or different shapes.");
  m.def("exact_node_dot_limbs", [](DArr x, DArr y, py::object rows) {
           if (x.ndim() != 2 || y.ndim() != 2 || x.shape(0) != y.shape(0) || x.shape(1) != y.shape(1) || x.shape(1) < 1)
             throw InputError("a nodal dot needs two arrays of one shape (nodes, components), got " + shape_of(x) + " and " + shape_of(y));
           BArr flags;
           if (!rows.is_none()) {
             flags = rows.cast<BArr>();
             if (flags.ndim() != 1 || flags.size() != x.shape(0))
               throw InputError("rows needs one flag per node, got " + std::to_string(flags.size()) + " for shape " + shape_of(x));
           }
           ExactAccumulator acc;
           {
             py::gil_scoped_release release;
             acc = exact_node_dot(x.data(), y.data(), (std::int64_t)x.shape(0), (int)x.shape(1), rows.is_none() ? nullptr : flags.data());
           }
           return exact_int(acc);
         }, py::arg("x"), py::arg("y"), py::arg("rows") = py::none(),
         "sum over the nodes (rows of x and y, with rows: the flagged ones) of the node's products x_i . y_i summed "
         "left to right in double, the node values summed exactly: the integer T with sum = T * 2^-2252 "
         "(local_node_dot of contactmg.distributed.exchange). ValueError for a non-finite node value or different shapes.");
}

}  // namespace cmg::bindings
