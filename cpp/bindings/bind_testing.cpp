// The testing submodule _core.testing: the pieces of the core on their own (line smoothing, nodal
// solves, bound restriction, Galerkin products, the coarsest solver's update, Anderson mixing),
// the solver's internals (single sweeps, level matrices and lines, the linear correction) and the
// memory bandwidth probes of the benchmarks. Nothing of the package calls them.
#include "base/bandwidth.hpp"
#include "bindings/common.hpp"
#include "solver/contact_solver.hpp"

namespace cmg::bindings {

namespace {

template <int d>
void bind_dim(py::module_& m) {
  const std::string sfx = std::to_string(d) + "D";
  using BM = BlockMatrix<d>;
  using CS = ContactSolver<d>;
  m.def("smooth", [](CS& S, DArr u0, int sweeps, const std::string& ordering, int threads, double omega, bool per_row) {
             require_shape(u0, "u0", {(py::ssize_t)S.num_nodes(), d});
             if (sweeps < 0) throw InputError("sweeps must be >= 0");
             if (!(omega > 0 && omega < 2)) throw InputError("omega: the over-relaxation must lie in (0, 2)");
             std::vector<double> u;
             {
               const Ordering o = parse_ordering(ordering);
               py::gil_scoped_release release;
               ThreadScope team(threads);
               u = S.smooth(u0.data(), sweeps, o, omega, per_row);
             }
             return to_numpy(u, {(py::ssize_t)S.num_nodes(), d});
           }, py::arg("solver"), py::arg("u0"), py::arg("sweeps") = 1, py::arg("ordering") = "lexicographic", py::arg("threads") = 0,
           py::arg("omega") = 1.0, py::arg("per_row") = false,
           "Nonlinear Gauss-Seidel sweeps (alternating, forward first) from u0; a solution is a fixed point. omega: the "
           "over-relaxation of the rows without contact; per_row: every row through the per-row path (the reference of "
           "the range kernel of a level stored by colours)");
  m.def("coarse_matrix", [](const CS& S, int l) {
             if (l < 0 || l >= S.hierarchy().num_coarse_levels()) throw py::index_error("no such coarse level");
             return std::make_shared<BM>(S.coarse_matrix_in_user_order(l));
           });
  m.def("fine_matrix", [](const CS& S) { return std::make_shared<BM>(S.fine_matrix_in_user_order()); });
  m.def("rebuild_coarse", &CS::rebuild_coarse, "Full Galerkin rebuild of the coarse matrices for the current truncation");
  m.def("linear_solve", [](CS& S, DArr r, int max_iterations, double reduction, bool lines, py::object cycle) {
             require_shape(r, "r", {(py::ssize_t)S.num_nodes(), d});
             if (max_iterations < 1) throw InputError("max_iterations must be at least 1");
             SolverOptions co = S.options();
             if (!cycle.is_none()) co.cycle = parse_cycle(cycle.cast<std::string>());
             co.lines = lines;
             std::vector<double> e, w;
             {
               py::gil_scoped_release release;
               w = S.linear_solve(r.data(), co, max_iterations, reduction, e);
             }
             return py::make_tuple(to_numpy(w, {(py::ssize_t)S.num_nodes(), d}), to_numpy(e, {(py::ssize_t)e.size()}));
           }, py::arg("solver"), py::arg("r"), py::arg("max_iterations"), py::arg("reduction") = 0.0, py::arg("lines") = true,
           py::arg("cycle") = py::none(),
           "TNNMG's linear correction on the current linearization (fresh solver: linear elasticity in the contact "
           "frames, Dirichlet dofs masked): PCG preconditioned by the truncated linear cycle for K w = M r, r in the "
           "frames. Returns (w, energies after each iteration)");
  m.def("fine_lines", [](CS& S, bool lines) {
             return lines_to_list(S.fine_lines(lines));
           }, py::arg("solver"), py::arg("lines") = true, "the lines of the fine line smoother (node ids in chain order)");
  m.def("coarse_lines", [](const CS& S, int l) {
             if (l < 0 || l >= S.hierarchy().num_coarse_levels()) throw py::index_error("no such coarse level");
             return lines_to_list(S.coarse_lines(l));
           }, py::arg("solver"), py::arg("level"), "the lines of coarse level `level` (node ids in chain order)");
  m.def("num_colours", &CS::num_fine_colours, "colours of the fine block graph (coloured sweeps)");
  m.def("level_colours", [](CS& S, int level, const std::string& ordering) {
             const std::vector<Index> c = S.level_colours(level, parse_ordering(ordering));
             return to_numpy(c, {(py::ssize_t)c.size()});
           }, py::arg("solver"), py::arg("level"), py::arg("ordering") = "hashed",
           "the colour of every node of level `level` (0: coarsest; the fine level last) in the coloured or hashed "
           "sweeps, in the user's numbering (-1: not smoothed)");
  m.def("coarsest_factorizations", [](const CS& S) { return S.hierarchy().coarsest_factorizations(); },
                             "factorizations of the coarsest-level matrix by this solver so far");
  m.def(("line_gauss_seidel_" + sfx).c_str(), [](const BM& A, DArr b, DArr x0, int sweeps, py::object active) {
    if (A.rows != A.cols) throw InputError("the matrix must be square");
    require_shape(b, "b", {(py::ssize_t)A.rows, d});
    require_shape(x0, "x0", {(py::ssize_t)A.rows, d});
    if (sweeps < 0) throw InputError("sweeps must be >= 0");
    std::vector<std::uint8_t> act;
    if (!active.is_none()) {
      py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast> a = active.cast<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>>();
      require_shape(a, "active", {(py::ssize_t)A.rows, d});
      act.assign(a.data(), a.data() + A.rows * d);
    }
    LineGaussSeidel<d> gs(find_lines<d>(A));
    gs.factor(A, act.empty() ? nullptr : act.data());
    std::vector<double> x(x0.data(), x0.data() + A.rows * d);
    for (int s = 0; s < sweeps; ++s) gs.sweep(A, act.empty() ? nullptr : act.data(), b.data(), x.data(), s % 2 == 0);
    return py::make_tuple(to_numpy(x, {(py::ssize_t)A.rows, d}), lines_to_list(gs.lines()));
  }, py::arg("A"), py::arg("b"), py::arg("x0"), py::arg("sweeps") = 1, py::arg("active") = py::none(),
     "Line Gauss-Seidel (mg/line_smoother.hpp): the lines of A found from the matrix, `sweeps` sweeps (alternating, "
     "forward first) for A x = b from x0, active (n, d): 0 on truncated dofs. Returns (x, lines)");

  m.def(("restrict_bounds_" + sfx).c_str(), [](Index n_fine, Index n_coarse, IArr ptr, IArr parent, DArr weight, py::object mask,
                                               DArr lo, DArr hi) {
    if (ptr.size() != n_fine + 1) throw InputError("ptr must have n_fine + 1 entries");
    Prolongation<d> P = make_prolongation<d>(n_fine, n_coarse, ptr.data(), parent.data(), weight.data());
    require_shape(lo, "lo", {(py::ssize_t)n_fine, d}); require_shape(hi, "hi", {(py::ssize_t)n_fine, d});
    BArr mk;
    const std::uint8_t* mp = nullptr;
    if (!mask.is_none()) { mk = mask.cast<BArr>(); require_shape(mk, "mask", {(py::ssize_t)n_fine, d}); mp = mk.data(); }
    py::array_t<double> lc({(py::ssize_t)n_coarse, (py::ssize_t)d}), hc({(py::ssize_t)n_coarse, (py::ssize_t)d});
    restrict_bounds<d>(P, mp, lo.data(), hi.data(), lc.mutable_data(), hc.mutable_data());
    return py::make_tuple(lc, hc);
  });
  m.def(("friction_hessian_" + sfx).c_str(), [](double s, DArr u, int free) {
    require_shape(u, "u", {d});
    Mat<d> H = friction_hessian<d>(s, u.data(), (TangentMask)free);
    py::array_t<double> out({(py::ssize_t)d, (py::ssize_t)d});
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) out.mutable_at(a, b) = H(a, b);
    return out;
  }, py::arg("s"), py::arg("u"), py::arg("free") = (int)all_tangents<d>(),
  "Hessian of s |u_T| (frame components, free tangential mask) at a sliding node");
  m.def(("minimize_box_qp_" + sfx).c_str(), [](const BM& A, DArr b, DArr lo, DArr hi, DArr x0, int max_steps) {
    if (A.rows != A.cols) throw InputError("the matrix must be square");
    for (auto* a : {&b, &lo, &hi, &x0}) require_shape(*a, "vectors", {(py::ssize_t)A.rows, d});
    std::vector<double> x(x0.data(), x0.data() + A.rows * d);
    const int steps = minimize_box_qp<d>(A, b.data(), lo.data(), hi.data(), x.data(), max_steps, 1e-14);
    return py::make_tuple(to_numpy(x, {(py::ssize_t)A.rows, d}), steps);
  }, py::arg("A"), py::arg("b"), py::arg("lo"), py::arg("hi"), py::arg("x0"), py::arg("max_steps") = 30,
     "The box QP min 1/2 x^T A x - b^T x, lo <= x <= hi (mg/box_qp.hpp) from the feasible x0 (n, d): (x, Newton steps)");
  m.def(("galerkin_product_" + sfx).c_str(), [](const BM& A, Index n_coarse, IArr ptr, IArr parent, DArr weight) {
    if (ptr.size() != A.rows + 1) throw InputError("ptr must have num_fine + 1 entries");
    Prolongation<d> P = make_prolongation<d>(A.rows, n_coarse, ptr.data(), parent.data(), weight.data());
    auto C = std::make_shared<BM>();
    GalerkinProduct<d> gp;
    gp.build(A, P, nullptr, *C);
    return C;
  });
}

}  // namespace

void bind_testing(py::module_& m) {
  bind_dim<2>(m);
  bind_dim<3>(m);
  // Tests: the coarsest solver on its own -- S0 factorized, then S as an update (a low-rank
  // correction where it allows one), then a solve with b. Returns (x, rank of the correction,
  // factorizations of this solver). Dense n x n arrays in, their nonzero entries taken.
  m.def("coarsest_update_solve", [](DArr S0, DArr S, DArr b) {
    const Index n = b.size();
    require_shape(S0, "S0", {(py::ssize_t)n, (py::ssize_t)n}); require_shape(S, "S", {(py::ssize_t)n, (py::ssize_t)n});
    const auto sparse = [n](const DArr& A) {
      std::vector<Eigen::Triplet<double>> t;
      for (Index i = 0; i < n; ++i)
        for (Index j = 0; j < n; ++j)
          if (A.data()[i * n + j] != 0) t.emplace_back(i, j, A.data()[i * n + j]);
      Eigen::SparseMatrix<double> M(n, n);
      M.setFromTriplets(t.begin(), t.end());
      return M;
    };
    const auto factor = [](Eigen::SparseMatrix<double>& M, Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& f) {
      f.compute(M);
      if (f.info() != Eigen::Success) throw InputError("S0 or S is not positive definite");
      return 1;
    };
    CoarsestSolver C;
    C.set(sparse(S0), false, factor);
    C.set(sparse(S), true, factor);
    std::vector<double> x(n);
    C.solve(b.data(), x.data(), factor);
    return py::make_tuple(moved_to_numpy(std::move(x), {(py::ssize_t)n}), (Index)C.rank(), C.factorizations());
  });
  m.def("stream_triad", [](Index n, int repeats, int threads) {
    if (n < 1 || repeats < 1) throw InputError("stream_triad needs n >= 1 and repeats >= 1");
    py::gil_scoped_release release;
    ThreadScope team(threads);
    return triad_bytes_per_second(n, repeats) / 1e9;
  }, py::arg("n") = 40000000, py::arg("repeats") = 5, py::arg("threads") = 1,
  "GB/s of the triad a = b + 1.5 c over n doubles on `threads` threads (best of `repeats`; 24 bytes an entry)");
  m.def("stream_read", [](Index n, int repeats, int threads, int streams) {
    if (n < 64 || repeats < 1) throw InputError("stream_read needs n >= 64 and repeats >= 1");
    py::gil_scoped_release release;
    ThreadScope team(threads);
    return read_bytes_per_second(n, repeats, streams) / 1e9;
  }, py::arg("n") = 40000000, py::arg("repeats") = 5, py::arg("threads") = 1, py::arg("streams") = 4,
  "GB/s of a sum over n doubles on `threads` threads, each thread's part read as `streams` (1, 2, 4, 8) pieces at once "
  "(best of `repeats`; 8 bytes an entry, read only)");
  m.def("stream_read_blocks", [](Index blocks, int repeats, int threads, int dim) {
    if (blocks < 64 || repeats < 1) throw InputError("stream_read_blocks needs blocks >= 64 and repeats >= 1");
    if (dim != 2 && dim != 3) throw InputError("dim must be 2 or 3");
    py::gil_scoped_release release;
    ThreadScope team(threads);
    return (dim == 2 ? block_read_bytes_per_second<2>(blocks, repeats, 7) : block_read_bytes_per_second<3>(blocks, repeats, 15)) / 1e9;
  }, py::arg("blocks") = 9000000, py::arg("repeats") = 5, py::arg("threads") = 1, py::arg("dim") = 2,
  "GB/s of a matrix-like read: `blocks` dim x dim blocks of doubles with int32 columns (8 dim^2 + 4 bytes a block; 7 "
  "(2D) or 15 (3D) a row) times a cache-resident x through the row passes' kernel (best of `repeats`)");
  m.def("anderson_iterates", [](DArr M, DArr c, DArr x0, int steps, int refuse_every, int threads) {
    const Index n = c.size(), m = M.ndim() == 2 ? M.shape(0) : 0;
    if (m < 1 || n % m != 0) throw InputError("M must be m x m with m dividing the length of c");
    require_shape(M, "M", {(py::ssize_t)m, (py::ssize_t)m}); require_shape(x0, "x0", {(py::ssize_t)n});
    ThreadScope team(threads);
    std::vector<double> x(x0.data(), x0.data() + n), gx(n);
    SettledAnderson<> A;
    py::array_t<double> out({(py::ssize_t)steps, (py::ssize_t)n});
    py::array_t<std::uint8_t> mixed(steps);
    int calls = 0;
    for (int s = 0; s < steps; ++s) {
      for (Index i = 0; i < n; ++i) {  // block-diagonal: M on every block of m entries
        const Index b = i - i % m, r = i % m;
        double v = c.data()[i];
        for (Index j = 0; j < m; ++j) v += M.data()[r * m + j] * x[b + j];
        gx[i] = v;
      }
      mixed.mutable_at(s) = A.step(x.data(), gx.data(), n, [&](double*, const double*) {
        return refuse_every <= 0 || ++calls % refuse_every != 0;
      });
      x = gx;
      std::copy(x.begin(), x.end(), out.mutable_data() + s * n);
    }
    return py::make_tuple(out, mixed);
  }, py::arg("M"), py::arg("c"), py::arg("x0"), py::arg("steps"), py::arg("refuse_every") = 0, py::arg("threads") = 1,
  "test hook: the iterates x <- mix(diag(M, M, ...) x + c) of steps/settled_anderson.hpp (every refuse_every-th candidate refused) "
  "and whether each step took the mixed iterate");
}

}  // namespace cmg::bindings
