// The serial step's Anderson mixing (steps/settled_anderson.hpp) for a distributed cycle
// (python/contactmg/distributed/cycle.py): the same class with node sums in place of the chunked
// sums. Each of the step's dot products is summed as exchange.node_dots sums: a node's products
// left to right in double, the owned nodes' values exactly, the ranks' integers combined by the
// caller's `combine` (one collective for all of a step's sums). The vectors span every local dof,
// ghosts included: the mixed iterate is formed entry by entry from values a ghost shares with its
// owner and weights every rank shares, so a ghost entry is its owner's, bit for bit, without an
// exchange.
#include <algorithm>
#include <array>
#include "bindings/common.hpp"
#include "steps/settled_anderson.hpp"

namespace cmg::bindings {

namespace {

// The sums of a distributed step: per node (width entries) the terms of each sum added left to
// right, the flagged (owned) nodes' values summed exactly, then over the ranks by `combine` (a list
// of the local integers -> a list of the rounded global sums).
struct NodeSums {
  BArr rows;
  int width = 1;
  py::object combine;

  template <int M, class F>
  std::array<double, M> sums(Index n, int m, F&& f) const {
    const std::uint8_t* flag = rows.data();
    std::array<ExactBins, M> bins;
    std::array<ExactAccumulator, M> acc;
    const Index nodes = n / width;
    for (Index start = 0; start < nodes; start += ExactBins::kTermsPerFlush) {
      const Index end = std::min<Index>(nodes, start + ExactBins::kTermsPerFlush);
      for (Index i = start; i < end; ++i) {
        std::array<double, M> node{};
        for (Index k = i * width; k < (i + 1) * width; ++k) f(k, node.data());  // every entry: the step writes its slots here
        if (!flag[i]) continue;
        for (int j = 0; j < m; ++j)
          if (!exact_detail::add_double(bins[j], node[j]))
            throw InputError("a dot product of the Anderson step has a non-finite term at node " + std::to_string(i));
      }
      for (int j = 0; j < m; ++j) {
        bins[j].flush_into(acc[j]);
        acc[j].normalise();
      }
    }
    py::list local;
    for (int j = 0; j < m; ++j) local.append(exact_int(acc[j]));
    const py::list total = combine(local);
    std::array<double, M> out{};
    for (int j = 0; j < m; ++j) out[j] = total[j].cast<double>();
    return out;
  }
};

// y or plain of the step as an (n / width, width) array over the step's memory (no copy)
py::array_t<double> view(const double* p, Index n, int width) {
  return py::array_t<double>({(py::ssize_t)(n / width), (py::ssize_t)width}, p, py::capsule(p, [](void*) {}));
}

struct NodeAnderson {
  SettledAnderson<NodeSums> A;
  NodeAnderson(BArr rows, int width, py::object combine) : A(NodeSums{std::move(rows), width, std::move(combine)}) {}
};

}  // namespace

void bind_anderson(py::module_& m) {
  py::class_<NodeAnderson>(m, "NodeAnderson",
                           "Anderson mixing of the settled Coulomb cycle (steps/settled_anderson.hpp) with node sums over ranks")
      .def(py::init([](BArr rows, int width, py::object combine) {
             if (width < 1) throw InputError("width must be >= 1");
             if (rows.ndim() != 1) throw InputError("rows needs one flag per node");
             return new NodeAnderson(std::move(rows), width, std::move(combine));
           }), py::arg("rows"), py::arg("width"), py::arg("combine"),
           "rows: a flag per node (the nodes this rank sums: its owned ones), width: entries a node, "
           "combine(list of local exact integers) -> list of the global sums")
      .def("step", [](NodeAnderson& a, const DArr& x, py::array_t<double>& gx, py::object admit, bool restart) {
             const Index n = (Index)x.size();
             const int width = a.A.sums().width;
             if (n != (Index)a.A.sums().rows.size() * width || (Index)gx.size() != n)
               throw InputError("x and gx need " + std::to_string(a.A.sums().rows.size()) + " nodes of " + std::to_string(width) + " entries");
             if (!(gx.flags() & py::array::c_style) || !gx.writeable()) throw InputError("gx must be a writable C-contiguous array");
             double* g = gx.mutable_data();
             return a.A.step(x.data(), g, n, [&](double* y, const double* plain) {
               return admit(view(y, n, width), view(plain, n, width)).cast<bool>();
             }, restart);
           }, py::arg("x"), py::arg("gx"), py::arg("admit"), py::arg("restart") = false,
           "x: the iterate before the cycle, gx: G(x), replaced in place by the mixed iterate where admit(candidate, "
           "plain) accepts it (it may adjust the candidate); returns whether it did. restart: forget the history first")
      .def("settle", [](NodeAnderson& a, const DArr& x, py::array_t<double>& gx, bool any_sliding, bool state_changed,
                        double best_step, py::object change_norm, py::object admit, py::object keep_change) {
             const Index n = (Index)x.size();
             const int width = a.A.sums().width;
             if (n != (Index)a.A.sums().rows.size() * width || (Index)gx.size() != n)
               throw InputError("x and gx need " + std::to_string(a.A.sums().rows.size()) + " nodes of " + std::to_string(width) + " entries");
             if (!(gx.flags() & py::array::c_style) || !gx.writeable()) throw InputError("gx must be a writable C-contiguous array");
             return a.A.settle(
                 x.data(), gx.mutable_data(), n, any_sliding, state_changed, best_step,
                 [&] { return change_norm().cast<double>(); },
                 [&](double* y, const double* plain) { return admit(view(y, n, width), view(plain, n, width)).cast<bool>(); },
                 [&] { keep_change(); });
           }, py::arg("x"), py::arg("gx"), py::arg("any_sliding"), py::arg("state_changed"), py::arg("best_step"),
           py::arg("change_norm"), py::arg("admit"), py::arg("keep_change"),
           "The settled-cycle rule around step() (steps/settled_anderson.hpp settle): change_norm() -> |G(x) - x|_A, "
           "admit(candidate, plain) -> bool, keep_change() takes the measured change into A u; returns that step "
           "where the state changed and the mixed iterate was refused, else -1")
      .def("reset", [](NodeAnderson& a) { a.A.reset(); }, "forget the history (a new contact state)")
      .def("memory_bytes", [](const NodeAnderson& a) { return a.A.memory_bytes(); }, "the bytes of the slots held");
}

}  // namespace cmg::bindings
