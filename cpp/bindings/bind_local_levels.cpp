// One rank's part of a distributed cycle (python/contactmg/distributed/cycle.py), bound: its fine
// level (steps/rank_fine_level.hpp) and the gathered coarsest level's bounded correction
// (mg/distributed_levels.hpp). Shapes are checked here; the algorithms live in those headers.
#include <algorithm>
#include "bindings/common.hpp"
#include "mg/distributed_levels.hpp"
#include "laws/law.hpp"
#include "steps/rank_fine_level.hpp"

namespace cmg::bindings {

namespace {

template <class T>
T* writable(py::array_t<T>& a, const char* name, py::ssize_t size) {
  if (!(a.flags() & py::array::c_style) || !a.writeable())
    throw InputError(std::string(name) + " must be a writable C-contiguous array");
  if (a.size() != size) throw InputError(std::string(name) + " has " + std::to_string(a.size()) + " entries, " + std::to_string(size) + " expected");
  return a.mutable_data();
}

void check_rows(const IArr& rows, Index n) {
  const Index* r = rows.data();
  for (py::ssize_t q = 0; q < rows.size(); ++q)
    if (r[q] < 0 || r[q] >= n) throw InputError("a row to sweep (" + std::to_string(r[q]) + ") is outside 0.." + std::to_string(n - 1));
}

std::vector<Index> row_list(const IArr& rows, Index n) {
  std::vector<Index> out(rows.data(), rows.data() + rows.size());
  for (Index i : out)
    if (i < 0 || i >= n) throw InputError("a row to sweep (" + std::to_string(i) + ") is outside 0.." + std::to_string(n - 1));
  return out;
}

// The Python face of one rank's fine level (steps/rank_fine_level.hpp): shapes checked, arrays
// in and out, the GIL released around the passes over the matrix.
template <int d>
struct LocalContactLevel {
  RankFineLevel<d> F;

  LocalContactLevel(const BlockMatrix<d>& A, DArr f, BArr fixed, DArr fixed_values, IArr nodes, DArr normals, DArr gaps,
                    DArr coefficients, const std::string& law_name)
      : F(make(A, f, fixed, fixed_values, nodes, normals, gaps, coefficients), parse_law(law_name)) {}

  static ContactProblem<d> make(const BlockMatrix<d>& A, DArr f, BArr fixed, DArr fixed_values, IArr nodes, DArr normals, DArr gaps,
                                DArr coefficients) {
    const Index n = A.rows, nc = (Index)nodes.size();
    require_shape(f, "f", {(py::ssize_t)n, d});
    require_shape(fixed, "fixed", {(py::ssize_t)n, d});
    require_shape(fixed_values, "fixed_values", {(py::ssize_t)n, d});
    require_shape(normals, "normals", {(py::ssize_t)nc, d});
    require_shape(gaps, "gaps", {(py::ssize_t)nc});
    require_shape(coefficients, "coefficients", {(py::ssize_t)nc});
    std::vector<Index> cn(nodes.data(), nodes.data() + nc);
    return ContactProblem<d>(A, f.data(), fixed.data(), fixed_values.data(), cn, normals.data(), gaps.data(), coefficients.data());
  }

  Index n() const { return F.n(); }
  const ContactProblem<d>& problem() const { return F.P; }

  void sweep(py::array_t<double>& u, const IArr& rows, bool forward, double omega, int threads) {
    double* x = writable(u, "u", n() * d);
    if (!(omega > 0 && omega < 2)) throw InputError("omega must lie in (0, 2)");
    if (threads < 1) throw InputError("threads must be >= 1");
    check_rows(rows, n());
    py::gil_scoped_release free;
    F.sweep(x, rows.data(), (Index)rows.size(), forward, omega, threads);
  }

  py::array_t<double> multiply(const DArr& v, int threads) const {
    require_shape(v, "v", {(py::ssize_t)n(), d});
    if (threads < 1) throw InputError("threads must be >= 1");
    py::array_t<double> y({(py::ssize_t)n(), (py::ssize_t)d});
    double* out = y.mutable_data();
    const double* in = v.data();
    py::gil_scoped_release free;
    ThreadScope team(threads);
    F.P.matrix().multiply(in, out);
    return y;
  }

  py::array_t<double> residual(const DArr& u, const IArr& rows) const {
    require_shape(u, "u", {(py::ssize_t)n(), d});
    check_rows(rows, n());
    py::array_t<double> r({(py::ssize_t)n(), (py::ssize_t)d});
    double* out = r.mutable_data();
    py::gil_scoped_release free;
    F.residual(u.data(), rows.data(), (Index)rows.size(), out);
    return r;
  }

  py::int_ difference_product(const DArr& u, const DArr& old, py::array_t<double>& out, const BArr& rows, bool add) const {
    require_shape(u, "u", {(py::ssize_t)n(), d});
    require_shape(old, "old", {(py::ssize_t)n(), d});
    require_shape(rows, "rows", {(py::ssize_t)n()});
    double* y = writable(out, "out", n() * d);
    ExactAccumulator acc;
    {
      py::gil_scoped_release free;
      acc = F.difference_product(u.data(), old.data(), y, rows.data(), add);
    }
    return exact_int(acc);
  }

  py::tuple linearize(const DArr& u, py::array_t<double>& r, const IArr& contacts) const {
    require_shape(u, "u", {(py::ssize_t)n(), d});
    double* rr = writable(r, "r", n() * d);
    const Index nc = F.P.num_contact();
    py::array_t<std::uint8_t> mask({(py::ssize_t)n(), (py::ssize_t)d});
    std::vector<double> lo(nc * d, -kInf), hi(nc * d, kInf), H(nc * d * d, 0.0);
    const bool bounded = F.linearize(u.data(), rr, row_list(contacts, nc), mask.mutable_data(), lo.data(), hi.data(), H.data());
    return py::make_tuple(mask, to_numpy(lo, {(py::ssize_t)nc, d}), to_numpy(hi, {(py::ssize_t)nc, d}),
                          to_numpy(H, {(py::ssize_t)nc, d, d}), bounded);
  }

  py::tuple contact_state(const DArr& u, const IArr& contacts, py::object Au) const {
    require_shape(u, "u", {(py::ssize_t)n(), d});
    DArr Av;
    if (!Au.is_none()) {
      Av = Au.cast<DArr>();
      require_shape(Av, "Au", {(py::ssize_t)n(), d});
    }
    const std::vector<Index> cs = row_list(contacts, F.P.num_contact());
    std::vector<std::int8_t> state(cs.size(), 0);
    std::vector<double> energy(cs.size(), 0.0);
    F.contact_state(u.data(), cs, Au.is_none() ? nullptr : Av.data(), state.data(), energy.data());
    return py::make_tuple(to_numpy(state, {(py::ssize_t)cs.size()}), to_numpy(energy, {(py::ssize_t)cs.size()}));
  }

  py::array_t<std::uint8_t> admit_mixed(py::array_t<double>& y, const DArr& u, const IArr& contacts) const {
    double* yy = writable(y, "y", n() * d);
    require_shape(u, "u", {(py::ssize_t)n(), d});
    const std::vector<Index> cs = row_list(contacts, F.P.num_contact());
    std::vector<std::uint8_t> ok(cs.size(), 1);
    F.admit_mixed(yy, u.data(), cs, ok.data());
    return to_numpy(ok, {(py::ssize_t)cs.size()});
  }

  py::array_t<double> frames() const {
    const auto& T = F.P.basis();
    py::array_t<double> Q({(py::ssize_t)T.num_blocks(), (py::ssize_t)d, (py::ssize_t)d});
    for (Index c = 0; c < T.num_blocks(); ++c)
      for (int a = 0; a < d; ++a)
        for (int b = 0; b < d; ++b) Q.mutable_data()[(c * d + a) * d + b] = T.block(c)(a, b);
    return Q;
  }

  py::array_t<double> to_canonical(const DArr& u) const {
    require_shape(u, "u", {(py::ssize_t)n(), d});
    std::vector<double> v(u.data(), u.data() + n() * d);
    F.P.basis().to_canonical(v.data());
    return to_numpy(v, {(py::ssize_t)n(), d});
  }
};

template <int d>
void bind_local(py::module_& m) {
  const std::string sfx = std::to_string(d) + "D";
  using BM = BlockMatrix<d>;
  using L = LocalContactLevel<d>;
  py::class_<L>(m, ("LocalContactLevel" + sfx).c_str(), "One rank's fine level of a distributed solve")
      .def(py::init([](const BM& A, DArr f, BArr fixed, DArr fixed_values, IArr nodes, DArr normals, DArr gaps, DArr coefficients,
                       const std::string& law) { return new L(A, f, fixed, fixed_values, nodes, normals, gaps, coefficients, law); }),
           py::arg("A"), py::arg("f"), py::arg("fixed"), py::arg("fixed_values"), py::arg("contact_nodes"), py::arg("normals"),
           py::arg("gaps"), py::arg("coefficients"), py::arg("law"))
      .def("sweep", &L::sweep, py::arg("u"), py::arg("rows"), py::arg("forward"), py::arg("omega") = 1.0, py::arg("threads") = 1,
           "one nonlinear Gauss-Seidel pass over `rows` (in order, or reversed), u (n, d) in place; threads > 1: "
           "`rows` are one colour, updated on that many threads")
      .def("residual", &L::residual, py::arg("u"), py::arg("rows"), "f - A u on rows (zero elsewhere)")
      .def("multiply", &L::multiply, py::arg("v"), py::arg("threads") = 1, "A v on every local row (owned rows complete)")
      .def_property_readonly("memory_bytes", [](const L& l) { return l.problem().memory_bytes(); },
                             "bytes of the level's matrix, load, Dirichlet and contact data")
      .def("linearize", &L::linearize, py::arg("u"), py::arg("r"), py::arg("contacts"),
           "(mask, lo, hi, hessian, bounded) at the given contact nodes; the friction gradient is added into r")
      .def("contact_state", &L::contact_state, py::arg("u"), py::arg("contacts"), py::arg("Au") = py::none(),
           "(state, friction energy) at the given contact nodes; the energy needs A u")
      .def("difference_product", &L::difference_product, py::arg("u"), py::arg("old"), py::arg("out"), py::arg("rows"),
           py::arg("add") = false,
           "A (u - old) on the flagged rows into out (add: added), and the exact local sum of the node values "
           "(u - old)_i . (A (u - old))_i as the integer T with sum = T * 2^-2252")
      .def("admit_mixed", &L::admit_mixed, py::arg("y"), py::arg("u"), py::arg("contacts"),
           "the Anderson step's mixed iterate y at the given contact nodes, adjusted to the state of u in place; "
           "per node whether it admits y")
      .def("frames", &L::frames, "the contact frames Q (nc, d, d): local = Q^T canonical")
      .def("to_canonical", &L::to_canonical, py::arg("u"))
      // a view, not a copy: the Galerkin kernel reads it at every rebuild (every cycle under 3D
      // Coulomb friction, where a copy of the fine matrix per cycle showed)
      .def_property_readonly("matrix", [](const L& l) -> const BM& { return l.problem().matrix(); },
                             py::return_value_policy::reference_internal,
                             "T^T A T with the Dirichlet rows and columns eliminated (read-only view)")
      .def_property_readonly("load", [](const L& l) { return to_numpy(l.problem().load(), {(py::ssize_t)l.n(), d}); })
      .def_property_readonly("base_mask", [](const L& l) { return to_numpy(l.problem().base_mask(), {(py::ssize_t)l.n(), d}); });
  using S = GatheredCoarsestSmoother<d>;
  py::class_<S>(m, ("GatheredCoarsestSmoother" + sfx).c_str(), "The gathered coarsest level's bounded correction")
      .def(py::init([](const BM& A, double scale) { return new S(A, scale); }), py::arg("A"), py::arg("scale"))
      .def("bound", [](S& s, py::array_t<double>& x, const DArr& b, const DArr& lo, const DArr& hi, double omega, bool shifted) {
             const Index n = s.A.rows;
             if (!(omega > 0 && omega < 2)) throw InputError("omega must lie in (0, 2)");
             double* xx = writable(x, "x", n * d);
             require_shape(b, "b", {(py::ssize_t)n, d});
             require_shape(lo, "lo", {(py::ssize_t)n, d});
             require_shape(hi, "hi", {(py::ssize_t)n, d});
             py::gil_scoped_release free;
             s.bound(xx, b.data(), lo.data(), hi.data(), omega, shifted);
           }, py::arg("x"), py::arg("b"), py::arg("lo"), py::arg("hi"), py::arg("omega"), py::arg("shifted"),
           "x (n, d): the exact solution in, the bounded correction out (mg/bounded_coarsest.hpp, the serial "
           "cycle's); shifted: the factorization was shifted");
}

}  // namespace

void bind_local_levels(py::module_& m) {
  bind_local<2>(m);
  bind_local<3>(m);
}

}  // namespace cmg::bindings
