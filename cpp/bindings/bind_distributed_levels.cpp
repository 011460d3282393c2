// The coarse levels of a distributed cycle on one rank (python/contactmg/distributed/cycle.py): a
// level's rows and smoother (CoarseRows*D), the transfer from the level below with the Galerkin rows
// it forms (DistributedTransfer*D). Flat kernels of mg/distributed_galerkin.hpp; the ghost exchanges
// between them stay in Python.
#include <cstring>
#include "bindings/common.hpp"
#include "mg/distributed_galerkin.hpp"

namespace cmg::bindings {

namespace {

std::vector<Index> index_list(const IArr& a) { return std::vector<Index>(a.data(), a.data() + a.size()); }

std::vector<std::uint8_t> flags(const BArr& a, Index n, const char* name) {
  if (a.size() != n) throw InputError(std::string(name) + " has " + std::to_string(a.size()) + " entries, " + std::to_string(n) + " expected");
  return std::vector<std::uint8_t>(a.data(), a.data() + n);
}

double* writable_array(py::array_t<double>& a, const char* name, py::ssize_t size) {
  if (!(a.flags() & py::array::c_style) || !a.writeable())
    throw InputError(std::string(name) + " must be a writable C-contiguous array");
  if (a.size() != size) throw InputError(std::string(name) + " has " + std::to_string(a.size()) + " entries, " + std::to_string(size) + " expected");
  return a.mutable_data();
}

// An optional uint8 array of n entries (None: nullptr), kept alive by `keep`.
const std::uint8_t* optional_flags(const py::object& o, Index n, const char* name, BArr& keep) {
  if (o.is_none()) return nullptr;
  keep = o.cast<BArr>();
  if (keep.size() != n) throw InputError(std::string(name) + " has " + std::to_string(keep.size()) + " entries, " + std::to_string(n) + " expected");
  return keep.data();
}

// visit: every coarse node once
void check_visit(const IArr& visit, Index n) {
  if ((Index)visit.size() != n) throw InputError("visit must list every coarse node once");
  std::vector<std::uint8_t> seen(n, 0);
  for (py::ssize_t q = 0; q < visit.size(); ++q) {
    const Index I = visit.data()[q];
    if (I < 0 || I >= n || seen[I]) throw InputError("visit must list every coarse node once");
    seen[I] = 1;
  }
}

template <int d>
void bind_levels(py::module_& m) {
  const std::string sfx = std::to_string(d) + "D";
  using BM = BlockMatrix<d>;
  using C = CoarseRows<d>;
  using T = DistributedTransfer<d>;
  py::class_<C, std::shared_ptr<C>>(m, ("CoarseRows" + sfx).c_str(),
                                    "A coarse level's rows on one rank (owned rows, ghost rows empty) and their Gauss-Seidel")
      .def(py::init<>())
      .def_property_readonly("n", &C::n)
      .def("memory_bytes", &C::bytes)
      .def("max_diagonal", [](const C& c, const BArr& owned) { return c.max_diagonal(flags(owned, c.n(), "owned").data()); },
           py::arg("owned"), "the largest diagonal entry of the rows flagged in owned")
      .def("invert", &C::invert, py::arg("scale"), "the diagonal inverses (the inert threshold 1e-12 scale)")
      .def("residual", [](const C& c, const DArr& x, const DArr& b, const BArr& owned) {
             require_shape(x, "x", {(py::ssize_t)c.n(), d});
             require_shape(b, "b", {(py::ssize_t)c.n(), d});
             const auto o = flags(owned, c.n(), "owned");
             py::array_t<double> r({(py::ssize_t)c.n(), (py::ssize_t)d});
             c.residual(x.data(), b.data(), o.data(), r.mutable_data());
             return r;
           }, py::arg("x"), py::arg("b"), py::arg("owned"), "b - A x on the owned rows (blocks ascending), zero elsewhere")
      .def("sweep", [](C& c, py::array_t<double>& x, const DArr& b, const IArr& rows, bool forward, double omega, py::object lo,
                       py::object hi, py::object bounded, int threads) {
             const Index n = c.n();
             if (!(omega > 0 && omega < 2)) throw InputError("omega must lie in (0, 2)");
             if (threads < 1) throw InputError("threads must be >= 1");
             if (c.Dinv.size() != (std::size_t)(n * d * d)) throw InputError("sweep before invert");
             double* xx = writable_array(x, "x", n * d);
             require_shape(b, "b", {(py::ssize_t)n, d});
             const Index* r = rows.data();
             const Index count = (Index)rows.size();
             for (Index q = 0; q < count; ++q)
               if (r[q] < 0 || r[q] >= n) throw InputError("a row to sweep is outside the level");
             DArr l, h;
             BArr bv;
             if (!lo.is_none()) {
               l = lo.cast<DArr>(), h = hi.cast<DArr>();
               require_shape(l, "lo", {(py::ssize_t)n, d});
               require_shape(h, "hi", {(py::ssize_t)n, d});
               bv = bounded.cast<BArr>();
               if (bv.size() != n) throw InputError("bounded has " + std::to_string(bv.size()) + " entries, " + std::to_string(n) + " expected");
             }
             const bool bnd = !lo.is_none();
             const std::uint8_t* bp = bnd ? bv.data() : nullptr;
             const std::uint8_t* in = bnd ? c.inert.data() : nullptr;
             const double* lp = bnd ? l.data() : nullptr;
             const double* hp = bnd ? h.data() : nullptr;
             py::gil_scoped_release free;
             if (threads == 1 || count < kSerialColourRows) {
               gs_list<d>(c.A, c.Dinv.data(), bp, in, lp, hp, b.data(), xx, omega, r, count, forward);
               return;
             }
             // one colour's rows (not coupled): a chunk per thread, the bits of one thread
             const Index chunk = (count + threads - 1) / threads;
             ThreadScope team(threads);
             parallel_for(threads, [&](Index t) {
               const Index s0 = std::min(count, t * chunk), s1 = std::min(count, s0 + chunk);
               gs_list<d>(c.A, c.Dinv.data(), bp, in, lp, hp, b.data(), xx, omega, r + s0, s1 - s0, true);
             }, 1);
           }, py::arg("x"), py::arg("b"), py::arg("rows"), py::arg("forward"), py::arg("omega") = 1.0, py::arg("lo") = py::none(),
           py::arg("hi") = py::none(), py::arg("bounded") = py::none(), py::arg("threads") = 1,
           "one block (or, with bounds, projected) Gauss-Seidel pass over rows, x (n, d) in place; threads > 1: rows "
           "are one colour, updated on that many threads")
      .def("set_blocks", [](C& c, const IArr& indptr, const IArr& indices, const DArr& blocks) {
             const Index n = (Index)indptr.size() - 1;
             if (n < 0 || indptr.data()[0] != 0 || indptr.data()[n] != (Index)indices.size())
               throw InputError("indptr and indices are not one block CSR pattern");
             require_shape(blocks, "blocks", {(py::ssize_t)indices.size(), d, d});
             for (Index i = 0; i < n; ++i)
               for (Index k = indptr.data()[i]; k < indptr.data()[i + 1]; ++k) {
                 const Index j = indices.data()[k];
                 if (j < 0 || j >= n || (k > indptr.data()[i] && j <= indices.data()[k - 1]))
                   throw InputError("a row's block columns must lie in 0..n-1, ascending");
               }
             const bool same = c.A.rows == n && std::equal(c.A.indptr.begin(), c.A.indptr.end(), indptr.data()) &&
                               std::equal(c.A.indices.begin(), c.A.indices.end(), indices.data(),
                                          [](ColIndex a, Index b) { return (Index)a == b; });
             c.changed.assign(n, same ? 0 : 1);
             if (!same) {
               c.A.rows = c.A.cols = n;
               c.A.indptr.assign(indptr.data(), indptr.data() + n + 1);
               c.A.indices.assign(indices.data(), indices.data() + indices.size());
               c.A.values.assign(indices.size() * d * d, 0.0);
               c.A.find_diagonal();
             }
             for (Index i = 0; i < n; ++i) {
               const Index b0 = c.A.indptr[i] * d * d, len = (c.A.indptr[i + 1] - c.A.indptr[i]) * d * d;
               if (std::memcmp(c.A.values.data() + b0, blocks.data() + b0, sizeof(double) * len) != 0) {
                 std::copy(blocks.data() + b0, blocks.data() + b0 + len, c.A.values.data() + b0);
                 c.changed[i] = 1;
               }
             }
           }, py::arg("indptr"), py::arg("indices"), py::arg("blocks"),
           "the rows from a block CSR matrix (n x n, columns ascending per row); changed marks the rows whose bits changed")
      .def("clear_changed", [](C& c) { std::fill(c.changed.begin(), c.changed.end(), 0); }, "no row changed")
      .def("blocks", [](const C& c) {
             return py::make_tuple(to_numpy(c.A.indptr, {(py::ssize_t)c.A.indptr.size()}),
                                   to_numpy(c.A.indices, {(py::ssize_t)c.A.indices.size()}),
                                   to_numpy(c.A.values, {(py::ssize_t)c.A.nnz(), d, d}));
           }, "copies of (indptr, indices, blocks (nnz, d, d))")
      .def_property_readonly("changed", [](const C& c) { return to_numpy(c.changed, {(py::ssize_t)c.changed.size()}); },
                             "per row: whether the last Galerkin pass changed its values");

  py::class_<T, std::shared_ptr<T>>(m, ("DistributedTransfer" + sfx).c_str(),
                                    "The transfer onto one rank's fine nodes from the coarse level's, and the Galerkin rows it forms")
      .def(py::init([](const BM& P, const BArr& owned_fine, const BArr& owned_coarse) {
             return std::make_shared<T>(P, flags(owned_fine, P.rows, "owned_fine"), flags(owned_coarse, P.cols, "owned_coarse"));
           }), py::arg("P"), py::arg("owned_fine"), py::arg("owned_coarse"))
      .def_property_readonly("fine_nodes", &T::fine_nodes)
      .def_property_readonly("coarse_nodes", &T::coarse_nodes)
      .def_property_readonly("has_ghost_pattern", &T::has_ghost_pattern)
      .def("memory_bytes", &T::bytes)
      .def("set_fine", [](T& t, const BM& A, const BArr& mask, const IArr& hess_nodes, const DArr& hess) {
             if (mask.size() != A.rows * d) throw InputError("the mask needs one entry per fine dof");
             require_shape(hess, "hess", {(py::ssize_t)hess_nodes.size(), d, d});
             const std::vector<Index> hn = index_list(hess_nodes);
             py::gil_scoped_release free;
             t.set_fine(A, mask.data(), hn, hess.data(), nullptr);
           }, py::arg("A"), py::arg("mask"), py::arg("hess_nodes"), py::arg("hess"),
           "the inputs of the next Galerkin rows: the fine matrix, the mask per fine dof and Hessian blocks at hess_nodes")
      .def("set_fine", [](T& t, const C& above) {
             py::gil_scoped_release free;
             t.set_fine(above.A, nullptr, {}, nullptr, above.changed.empty() ? nullptr : above.changed.data());
           }, py::arg("rows"), "the inputs of the next Galerkin rows: a coarse level's rows (no mask)")
      .def("z_pattern", [](const T& t, const BM& A, const IArr& nodes) {
             auto pc = t.z_pattern(A, index_list(nodes));
             return py::make_tuple(to_numpy(pc.first, {(py::ssize_t)pc.first.size()}), to_numpy(pc.second, {(py::ssize_t)pc.second.size()}));
           }, py::arg("A"), py::arg("nodes"), "(block-row pointer, local coarse columns) of the owned Z rows of nodes")
      .def("z_pattern", [](const T& t, const C& above, const IArr& nodes) {
             auto pc = t.z_pattern(above.A, index_list(nodes));
             return py::make_tuple(to_numpy(pc.first, {(py::ssize_t)pc.first.size()}), to_numpy(pc.second, {(py::ssize_t)pc.second.size()}));
           }, py::arg("rows"), py::arg("nodes"))
      .def("z_values", [](const T& t, const BM& A, const IArr& nodes) {
             std::vector<double> v = t.z_values(A, index_list(nodes));
             const py::ssize_t k = (py::ssize_t)v.size() / (d * d);
             return moved_to_numpy(std::move(v), {k, d, d});
           }, py::arg("A"), py::arg("nodes"), "the blocks of the owned Z rows of nodes (k, d, d)")
      .def("z_values", [](const T& t, const C& above, const IArr& nodes) {
             std::vector<double> v = t.z_values(above.A, index_list(nodes));
             const py::ssize_t k = (py::ssize_t)v.size() / (d * d);
             return moved_to_numpy(std::move(v), {k, d, d});
           }, py::arg("rows"), py::arg("nodes"))
      .def("set_ghost_pattern", [](T& t, const IArr& nodes, const IArr& ptr, const IArr& cols) {
             t.set_ghost_pattern(index_list(nodes), index_list(ptr), index_list(cols));
           }, py::arg("nodes"), py::arg("ptr"), py::arg("cols"),
           "the ghost Z rows' patterns as sent (local coarse columns, -1: not held, the row left out), once")
      .def("set_ghost_values", [](T& t, const DArr& values) { t.set_ghost_values(values.data(), (Index)values.size()); },
           py::arg("values"), "the ghost Z rows' blocks from their owners, in the pattern's order")
      .def("form_coarse", [](T& t, const BM& A, C& rows, const IArr& visit) {
             check_visit(visit, t.coarse_nodes());
             py::gil_scoped_release free;
             t.form_coarse(A, rows, visit.data());
           }, py::arg("A"), py::arg("rows"), py::arg("visit"),
           "the owned coarse rows P^T Z into rows (formed again where a Z row changed), in the order visit")
      .def("form_coarse", [](T& t, const C& above, C& rows, const IArr& visit) {
             check_visit(visit, t.coarse_nodes());
             py::gil_scoped_release free;
             t.form_coarse(above.A, rows, visit.data());
           }, py::arg("above"), py::arg("rows"), py::arg("visit"))
      .def("restrict_residual", [](const T& t, const DArr& r, py::object mask) {
             require_shape(r, "r", {(py::ssize_t)t.fine_nodes(), d});
             BArr keep;
             const std::uint8_t* mk = optional_flags(mask, t.fine_nodes() * d, "mask", keep);
             py::array_t<double> b({(py::ssize_t)t.coarse_nodes(), (py::ssize_t)d});
             t.restrict_residual(r.data(), mk, b.mutable_data());
             return b;
           }, py::arg("r"), py::arg("mask") = py::none(), "P^T (M r) on the owned coarse rows, fine rows ascending; zero elsewhere")
      .def("restrict_fine_residual", [](const T& t, const BlockMatrix<d>& A, const DArr& x, const DArr& b, const DArr& r, const BArr& known,
                                        py::object mask) {
             const py::ssize_t n = t.fine_nodes();
             if (A.rows != (Index)n) throw InputError("A has " + std::to_string(A.rows) + " rows, the transfer " + std::to_string(n) + " fine nodes");
             require_shape(x, "x", {n, d});
             require_shape(b, "b", {n, d});
             require_shape(r, "r", {n, d});
             require_shape(known, "known", {n});
             BArr keep;
             const std::uint8_t* mk = optional_flags(mask, n * d, "mask", keep);
             py::array_t<double> bc({(py::ssize_t)t.coarse_nodes(), (py::ssize_t)d});
             double* out = bc.mutable_data();
             py::gil_scoped_release free;
             t.restrict_residual(A, x.data(), b.data(), r.data(), known.data(), mk, out);
             return bc;
           }, py::arg("A"), py::arg("x"), py::arg("b"), py::arg("r"), py::arg("known"), py::arg("mask") = py::none(),
           "restrict_residual of the fine residual: r where known, b - A x formed in the same pass elsewhere (the same bits)")
      .def("prolong", [](const T& t, const DArr& xc, py::object mask) {
             require_shape(xc, "xc", {(py::ssize_t)t.coarse_nodes(), d});
             BArr keep;
             const std::uint8_t* mk = optional_flags(mask, t.fine_nodes() * d, "mask", keep);
             py::array_t<double> xf({(py::ssize_t)t.fine_nodes(), (py::ssize_t)d});
             t.prolong(xc.data(), mk, xf.mutable_data(), false);
             return xf;
           }, py::arg("xc"), py::arg("mask") = py::none(), "M P xc on every local fine row")
      .def("prolong_add", [](const T& t, const DArr& xc, py::array_t<double>& xf) {
             require_shape(xc, "xc", {(py::ssize_t)t.coarse_nodes(), d});
             t.prolong(xc.data(), nullptr, writable_array(xf, "xf", t.fine_nodes() * d), true);
           }, py::arg("xc"), py::arg("xf"), "xf += P xc on every local fine row, in place")
      .def("restrict_bounds", [](const T& t, const DArr& lo, const DArr& hi, py::object x, py::object mask, py::object rows) {
             const py::ssize_t nf = t.fine_nodes(), nc = t.coarse_nodes();
             require_shape(lo, "lo", {nf, d});
             require_shape(hi, "hi", {nf, d});
             DArr xs;
             if (!x.is_none()) {
               xs = x.cast<DArr>();
               require_shape(xs, "x", {nf, d});
             }
             BArr km, kr;
             const std::uint8_t* mk = optional_flags(mask, nf * d, "mask", km);
             const std::uint8_t* rw = optional_flags(rows, nf, "rows", kr);
             py::array_t<double> lc({nc, (py::ssize_t)d}), hc({nc, (py::ssize_t)d});
             t.restrict_bounds(lo.data(), hi.data(), x.is_none() ? nullptr : xs.data(), mk, rw, lc.mutable_data(), hc.mutable_data());
             return py::make_tuple(lc, hc);
           }, py::arg("lo"), py::arg("hi"), py::arg("x") = py::none(), py::arg("mask") = py::none(), py::arg("rows") = py::none(),
           "monotone restriction of the bounds lo - x <= c <= hi - x of the fine rows flagged in rows (all if None), "
           "components with mask 0 skipped: (lo_c, hi_c) (n_coarse, d)");
}

}  // namespace

void bind_distributed_levels(py::module_& m) {
  m.def("finite_rows", [](const DArr& lo, const DArr& hi) {
          if (lo.ndim() != 2 || hi.ndim() != 2 || lo.shape(0) != hi.shape(0) || lo.shape(1) != hi.shape(1))
            throw InputError("lo and hi must be arrays (n, d) of one shape");
          const py::ssize_t n = lo.shape(0), w = lo.shape(1);
          py::array_t<std::uint8_t> out(n);
          std::uint8_t* o = out.mutable_data();
          const double *l = lo.data(), *h = hi.data();
          for (py::ssize_t i = 0; i < n; ++i) {
            bool f = false;
            for (py::ssize_t c = 0; c < w; ++c) f = f || std::isfinite(l[i * w + c]) || std::isfinite(h[i * w + c]);
            o[i] = f;
          }
          return out;
        }, py::arg("lo"), py::arg("hi"), "per row: 1 where a bound of the row is finite");
  using F = GatheredCoarsestFactor;
  py::class_<F, std::shared_ptr<F>>(m, "GatheredCoarsestFactor",
                                    "The gathered coarsest level's sparse LDL^T with the serial solver's low-rank updates "
                                    "(one thread, the same bits on every rank)")
      .def(py::init<>())
      .def("set", [](F& f, const IArr& indptr, const IArr& indices, const DArr& data, const BArr& inert, bool may_update) {
             const Index n = (Index)indptr.size() - 1;
             if (n < 0 || indices.size() != data.size() || indptr.data()[n] != (Index)indices.size())
               throw InputError("indptr, indices and data are not one CSR matrix");
             const std::vector<std::uint8_t> in = flags(inert, n, "inert");
             py::gil_scoped_release free;
             f.set(n, indptr.data(), indices.data(), data.data(), in.data(), may_update);
           }, py::arg("indptr"), py::arg("indices"), py::arg("data"), py::arg("inert"), py::arg("may_update"),
           "the matrix to solve with (symmetric scalar CSR; the inert dofs' rows and columns made identity); "
           "may_update: a low-rank correction of the kept factorization is allowed")
      .def_property_readonly("shifted", &F::shifted, "whether the matrix was semi-definite and factorized shifted by 1e-10 diag")
      .def_property_readonly("factorizations", &F::factorizations)
      .def("memory_bytes", &F::bytes)
      .def("solve", [](F& f, const DArr& b) {
             if (b.size() != f.n()) throw InputError("b has " + std::to_string(b.size()) + " entries, " + std::to_string(f.n()) + " expected");
             py::array_t<double> x(f.n());
             f.solve(b.data(), x.mutable_data());
             return x;
           }, py::arg("b"), "S^-1 b");
  bind_levels<2>(m);
  bind_levels<3>(m);
}

}  // namespace cmg::bindings
