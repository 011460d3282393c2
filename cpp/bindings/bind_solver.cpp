// The solver's Python face: BlockMatrix and ContactSolver per dimension, with the contact frames
// the package reads. A solve releases the GIL; Ctrl-C and the progress callback take it back.
#include <utility>
#include "bindings/options.hpp"
#include "solver/contact_solver.hpp"

namespace cmg::bindings {

namespace {

template <int d>
py::array_t<double> frames_array(const ContactSolver<d>& S) {
  const auto& T = S.problem().basis();
  py::array_t<double> Q({(py::ssize_t)T.num_blocks(), (py::ssize_t)d, (py::ssize_t)d});
  double* q = Q.mutable_data();
  for (Index c = 0; c < T.num_blocks(); ++c)
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) q[(c * d + a) * d + b] = T.block(c)(a, b);
  return Q;
}

// The dofs of the contact nodes fixed in their frames (a prescribed tangential component).
template <int d>
py::array_t<std::uint8_t> frame_fixed_array(const ContactSolver<d>& S) {
  const auto& P = S.problem();
  py::array_t<std::uint8_t> F({(py::ssize_t)P.num_contact(), (py::ssize_t)d});
  for (Index c = 0; c < P.num_contact(); ++c)
    for (int a = 0; a < d; ++a) F.mutable_data()[c * d + a] = P.fixed()[P.contact_node(c) * d + a];
  return F;
}

template <int d>
py::dict result_to_dict(SolveResult& R, const ContactSolver<d>& S) {
  const Index n = S.num_nodes(), nc = S.num_contact();
  py::dict out;
  out["frames"] = frames_array<d>(S);
  out["u"] = moved_to_numpy(std::move(R.u), {(py::ssize_t)n, d});
  out["contact_force"] = to_numpy(R.contact_force, {(py::ssize_t)nc, d});
  out["friction_bound"] = to_numpy(R.friction_bound, {(py::ssize_t)nc});
  out["state"] = to_numpy(R.state, {(py::ssize_t)nc});
  out["history"] = history_to_dict(R.history);
  out["outer_changes"] = to_numpy(R.outer_changes, {(py::ssize_t)R.outer_changes.size()});
  out["converged"] = R.converged;
  out["status"] = R.status;
  out["cycles"] = R.cycles;
  out["outer_iterations"] = R.outer_iterations;
  out["rebuilds"] = R.rebuilds;
  out["seconds"] = R.seconds;
  out["rebuild_seconds"] = R.rebuild_seconds;
  out["sweep_check"] = R.sweep_check;
  out["switched_at"] = R.switched_at;
  py::dict phases;
  for (int k = 0; k < (int)Phase::Count; ++k) phases[phase_name(k)] = R.phase_seconds[k];
  out["phase_seconds"] = phases;
  return out;
}


template <int d>
void bind_dim(py::module_& m) {
  const std::string sfx = std::to_string(d) + "D";
  using BM = BlockMatrix<d>;
  py::class_<BM, std::shared_ptr<BM>>(m, ("BlockMatrix" + sfx).c_str(), "Block sparse rows with d x d blocks")
      .def_property_readonly("shape", [](const BM& A) { return py::make_tuple(A.rows * d, A.cols * d); })
      .def_property_readonly("block_size", [](const BM&) { return d; })
      .def_property_readonly("nnz_blocks", &BM::nnz)
      .def_property_readonly("indptr", [](const BM& A) { return to_numpy(A.indptr, {(py::ssize_t)A.indptr.size()}); })
      .def_property_readonly("indices", [](const BM& A) { return to_numpy(A.indices, {(py::ssize_t)A.indices.size()}); })
      .def_property_readonly("data", [](const BM& A) { return to_numpy(A.values, {(py::ssize_t)A.nnz(), d, d}); })
      .def(py::init([](Index rows, Index cols, IArr indptr, IArr indices, DArr data) {
             // from block CSR arrays (scipy's bsr_matrix with d x d blocks): a matrix built outside
             // the assembly, e.g. T^T A T of the two-body mortar transformation
             check_block_count(rows);
             check_block_count(cols);
             const py::ssize_t nnz = indices.size();
             require_shape(indptr, "indptr", {(py::ssize_t)rows + 1});
             require_shape(data, "data", {nnz, d, d});
             auto A = std::make_shared<BM>();
             A->rows = rows;
             A->cols = cols;
             A->indptr.assign(indptr.data(), indptr.data() + rows + 1);
             if (A->indptr[0] != 0 || A->indptr[rows] != (Index)nnz) throw InputError("indptr does not match indices");
             for (Index i = 0; i < rows; ++i) {
               if (A->indptr[i + 1] < A->indptr[i]) throw InputError("indptr must not decrease");
               for (Index k = A->indptr[i]; k < A->indptr[i + 1]; ++k) {
                 const Index j = indices.data()[k];
                 if (j < 0 || j >= cols) throw InputError("a block column index is out of range");
                 if (k > A->indptr[i] && j <= indices.data()[k - 1]) throw InputError("block columns must be sorted and unique per row");
               }
             }
             A->indices.assign(indices.data(), indices.data() + nnz);
             A->values.assign(data.data(), data.data() + nnz * d * d);
             for (double v : A->values)
               if (!std::isfinite(v)) throw InputError("the matrix has a non-finite entry");
             A->find_diagonal();
             return A;
           }),
           py::arg("rows"), py::arg("cols"), py::arg("indptr"), py::arg("indices"), py::arg("data"),
           "from block CSR arrays: rows, cols in blocks, data (nnz, d, d)")
      .def("max_abs", [](const BM& A) {
             double m = 0;
             for (double v : A.values) m = std::max(m, std::abs(v));
             return m;
           }, "the largest absolute entry (the stiffness scale of the final check)")
      .def("memory_bytes", &BM::memory_bytes)
      .def("add_diagonal_blocks", [](BM& A, DArr blocks) {
        // e.g. the lumped stiffness of elastic supports (springs on boundary facets)
        require_shape(blocks, "blocks", {(py::ssize_t)A.rows, d, d});
        for (py::ssize_t i = 0; i < blocks.size(); ++i)
          if (!std::isfinite(blocks.data()[i])) throw InputError("a diagonal block has a non-finite entry");
        for (Index i = 0; i < A.rows; ++i) {
          const Index pos = A.find(i, i);
          if (pos < 0) throw InputError("row " + std::to_string(i) + " has no diagonal block");
          for (int a = 0; a < d; ++a)
            for (int b = 0; b < d; ++b) A.block(pos)(a, b) += blocks.data()[(i * d + a) * d + b];
        }
      }, py::arg("blocks"), "add blocks (rows, d, d) to the diagonal blocks")
      .def("matvec", [](const BM& A, DArr x) {
        require_shape(x, "x", {(py::ssize_t)A.cols, d});
        py::array_t<double> y({(py::ssize_t)A.rows, (py::ssize_t)d});
        A.multiply(x.data(), y.mutable_data());
        return y;
      });

  using CS = ContactSolver<d>;
  py::class_<CS>(m, ("ContactSolver" + sfx).c_str(), "Multigrid for linear elasticity with contact and friction")
      .def(py::init([](BM& A, DArr f, BArr fixed, DArr fixed_values, IArr contact_nodes, DArr normals, DArr gaps,
                       DArr coefficients, const std::string& law, py::list transfers, py::object options,
                       py::object frame_fixed, py::object frame_values, bool take_matrix) {
             const py::ssize_t n = A.rows, nc = contact_nodes.size();
             require_shape(f, "load", {n, d});
             require_shape(fixed, "fixed", {n, d});
             require_shape(fixed_values, "fixed_values", {n, d});
             require_shape(contact_nodes, "contact_nodes", {nc});
             require_shape(normals, "normals", {nc, d});
             require_shape(gaps, "gaps", {nc});
             require_shape(coefficients, "coefficients", {nc});
             const SolverOptions co = options_from_dict(options, SolverOptions());
             BArr ff;
             DArr fv;
             if (frame_fixed.is_none() != frame_values.is_none())
               throw InputError("frame_fixed and frame_values go together");
             if (!frame_fixed.is_none()) {
               ff = frame_fixed.cast<BArr>();
               fv = frame_values.cast<DArr>();
               require_shape(ff, "frame_fixed", {nc, d});
               require_shape(fv, "frame_values", {nc, d});
             }
             std::vector<typename CS::Transfer> T;
             for (auto item : transfers) {
               auto t = item.cast<py::tuple>();
               typename CS::Transfer tr;
               tr.n_fine = t[0].cast<Index>();
               tr.n_coarse = t[1].cast<Index>();
               IArr ptr = t[2].cast<IArr>(), par = t[3].cast<IArr>();
               DArr w = t[4].cast<DArr>();
               tr.ptr.assign(ptr.data(), ptr.data() + ptr.size());
               tr.parent.assign(par.data(), par.data() + par.size());
               tr.weight.assign(w.data(), w.data() + w.size());
               if (tr.ptr.empty() || tr.ptr.back() != (Index)tr.parent.size() || tr.parent.size() != tr.weight.size())
                 throw InputError("inconsistent prolongation arrays");
               T.push_back(std::move(tr));
             }
             std::vector<Index> cn(contact_nodes.data(), contact_nodes.data() + nc);
             // take_matrix: the caller gives its matrix up (left empty), so the fine matrix is held once
             BM fine = take_matrix ? std::exchange(A, BM()) : BM(A);
             return new CS(std::move(fine), f.data(), fixed.data(), fixed_values.data(), cn, normals.data(), gaps.data(),
                           coefficients.data(), parse_law(law), std::move(T), co, frame_fixed.is_none() ? nullptr : ff.data(),
                           frame_fixed.is_none() ? nullptr : fv.data());
           }),
           py::arg("A"), py::arg("load"), py::arg("fixed"), py::arg("fixed_values"), py::arg("contact_nodes"),
           py::arg("normals"), py::arg("gaps"), py::arg("coefficients"), py::arg("law"), py::arg("transfers"),
           py::arg("options") = py::dict(), py::arg("frame_fixed") = py::none(), py::arg("frame_values") = py::none(),
           py::arg("take_matrix") = false,
           "options: a dict of SolverOptions fields (method, cycle, nu1, nu2, tol, rtol, max_cycles, omega, omega_post, "
           "fixed_point_tol, fixed_point_max, fixed_point_stall_window, linear, lines, threads, ordering, petrov_galerkin, "
           "upwind_contact_sweep, projected_coarse_correction; a missing key takes the core's default, an unknown key or a "
           "bad value raises ValueError): the options every solve starts from. ordering 'coloured' or 'hashed' also stores every "
           "level but the coarsest by its colours (each colour one contiguous range of rows, so a coloured sweep streams "
           "memory; inputs and outputs keep the caller's numbering). fixed/fixed_values: Dirichlet components in "
           "canonical axes (a contact node keeps its contact condition in its free directions); frame_fixed/frame_values "
           "(nc, d): components fixed in the contact frames; take_matrix: the solver takes A over (A is left empty)")
      .def("solve", [](CS& S, py::object u0, py::object options, py::object progress, py::object reference) {
             const SolverOptions co = options_from_dict(options, S.options());
             if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw InputError("progress must be callable or None");
             DArr u;
             const double* up = nullptr;
             if (!u0.is_none()) {
               u = u0.cast<DArr>();
               require_shape(u, "u0", {(py::ssize_t)S.num_nodes(), d});
               up = u.data();
             }
             DArr ref;
             const double* refp = nullptr;
             if (!reference.is_none()) {
               ref = reference.cast<DArr>();
               require_shape(ref, "reference", {(py::ssize_t)S.num_nodes(), d});
               refp = ref.data();
             }
             // Ctrl-C and the progress callback need the GIL, taken only for them. A Python error
             // (KeyboardInterrupt, or one raised by the callback) is left set and stops the solve.
             S.monitor().interrupted = [] { py::gil_scoped_acquire g; return PyErr_CheckSignals() != 0; };
             if (!progress.is_none())
               S.monitor().progress = [&progress](const CycleRecord& r) {
                 py::gil_scoped_acquire g;
                 try { progress(record_to_dict(r)); }
                 catch (py::error_already_set& e) { e.restore(); throw Interrupted(); }
               };
             SolveResult R;
             bool interrupted = false;
             {
               py::gil_scoped_release release;
               ThreadScope team(co.threads);
               try { R = S.solve(up, co, refp); }
               catch (const Interrupted&) { interrupted = true; }
             }
             S.monitor().interrupted = nullptr;
             S.monitor().progress = nullptr;
             if (interrupted) throw py::error_already_set();
             py::dict out = result_to_dict<d>(R, S);
             out["options"] = options_to_dict(co);
             out["cycle_type"] = std::string(cycle_name(co.cycle)) + "(" + std::to_string(co.nu1) + "," + std::to_string(co.nu2) + ")";
             out["ordering"] = ordering_name(co.ordering);
             out["omega"] = co.omega;
             if (co.post_omega() != co.omega) out["omega_post"] = co.post_omega();
             if (co.petrov_galerkin) out["petrov_galerkin"] = true;
             if (co.upwind_contact_sweep) out["upwind_contact_sweep"] = true;
             if (co.projected_coarse_correction) out["projected_coarse_correction"] = true;
             if (co.method == Method::Tnnmg) { out["linear_correction"] = linear_correction_name(co.linear); out["lines"] = co.lines; }
             out["threads"] = co.threads == 0 ? max_threads() : (have_openmp() ? co.threads : 1);
             return out;
           },
           py::arg("u0") = py::none(), py::arg("options") = py::dict(), py::arg("progress") = py::none(),
           py::arg("reference") = py::none(),
           "A solve from u0 (n, d; None: 0) with the solver's options updated by `options` (a dict of SolverOptions "
           "fields, as the constructor's). method: 'nmg' (monotone multigrid; Algorithm 2 for Coulomb), 'tnnmg' "
           "(truncated nonsmooth Newton multigrid), 'fixed-point' (Algorithm 1, Coulomb only). progress(record: dict) is "
           "called after every cycle (cycle, outer, correction_norm, solution_norm, energy, seconds, error, active, stick, slip, rebuilt, "
           "step_size, frozen_decrease, linear_iterations, petrov_galerkin); reference (n, d): history['error'] records "
           "||u - reference||_A after every cycle. threads: the result does not depend on it")
      .def("set_load", [](CS& S, DArr load) {
             require_shape(load, "load", {(py::ssize_t)S.num_nodes(), d});
             S.set_load(load.data());
           }, py::arg("load"),
           "A new load (n, d), canonical, for the same matrix and data: a later solve is the one of a solver built with it")
      .def("set_fixed_values", [](CS& S, DArr values) {
             require_shape(values, "fixed_values", {(py::ssize_t)S.num_nodes(), d});
             S.set_fixed_values(values.data());
           }, py::arg("fixed_values"),
           "New Dirichlet values (n, d), canonical, read on the fixed components (the same ones): a later solve is the one "
           "of a solver built with them")
      .def_property_readonly("options", [](const CS& S) { return options_to_dict(S.options()); },
                             "the options every solve starts from")
      .def_property_readonly("num_levels", [](const CS& S) { return S.hierarchy().num_coarse_levels() + 1; })
      .def_property_readonly("level_sizes", [](const CS& S) {
             std::vector<Index> n;
             for (int l = 0; l < S.hierarchy().num_coarse_levels(); ++l) n.push_back(S.hierarchy().matrix(l).rows);
             n.push_back(S.num_nodes());
             return n;
           }, "the nodes (block rows) of every level, coarsest first, the fine level last")
      .def_property_readonly("frames", [](const CS& S) { return frames_array<d>(S); },
                             "the contact frames Q = [n, t(, s)] (columns), shape (num_contact, d, d)")
      .def_property_readonly("frame_fixed", [](const CS& S) { return frame_fixed_array<d>(S); },
                             "the components of each contact node fixed in its frame (num_contact, d)")
      .def("set_rows_to_smooth", [](CS& S, int l, IArr rows) {
             if (l < 0 || l >= S.hierarchy().num_coarse_levels()) throw py::index_error("no such coarse level");
             S.set_rows_to_smooth(l, std::vector<Index>(rows.data(), rows.data() + rows.size()));
           }, py::arg("level"), py::arg("rows"), "the rows smoothed on coarse level `level` (all by default)")
      .def("set_slip_origin", [](CS& S, py::object u_prev) {
             if (u_prev.is_none()) { S.set_slip_origin(nullptr); return; }
             DArr u = u_prev.cast<DArr>();
             require_shape(u, "u_prev", {(py::ssize_t)S.num_nodes(), d});
             S.set_slip_origin(u.data());
           }, py::arg("u_prev"),
           "Load paths: the previous step's displacement (n, d), canonical; friction then acts on the slip "
           "increment u_T - u_prev_T and stick means no slip in this step. None: from the reference configuration")
      .def_property_readonly("has_slip_origin", &CS::has_slip_origin)
      .def("keep_workspace", &CS::keep_workspace, py::arg("on"),
           "whether the fine vectors of the cycles (r, u_old, the Anderson history) stay from one solve to the next "
           "(True, the default: a later solve touches no new pages) or go at the end of each (a solver made for one "
           "solve: the lower peak); returns the previous setting")
      .def_property_readonly("renumbered", &CS::renumbered, "whether the levels are stored by colours")
      .def("residual", [](const CS& S) { return to_numpy(S.residual(), {(py::ssize_t)S.num_nodes(), d}); },
           "A u - f of the last iterate (n, d; canonical axes, the caller's numbering): meaningful on the rows "
           "that are not fixed")
      .def("stiffness_scale", &CS::stiffness_scale, "The largest entry of the fine matrix.")
      .def("memory_bytes", &CS::memory_bytes)
      .def("enable_tied_correction", &CS::enable_tied_correction,
           "after each nmg coarse correction a second one, without bounds, with every contact dof frozen (two bodies)")
      .def_property_readonly("tied_correction", &CS::tied_correction);

  // the nodal solves of the laws (the error estimator's local problems)
  m.def(("solve_node_tresca_" + sfx).c_str(), [](DArr B, DArr b, double g, double s, int free) {
    require_shape(B, "B", {d, d}); require_shape(b, "b", {d});
    Vec<d> x = solve_node_tresca<d>(CMatMap<d>(B.data()), CVecMap<d>(b.data()), g, s, (TangentMask)free);
    return to_numpy(std::vector<double>(x.data(), x.data() + d), {d});
  }, py::arg("B"), py::arg("b"), py::arg("g"), py::arg("s"), py::arg("free") = (int)all_tangents<d>());
  m.def(("solve_node_coulomb_" + sfx).c_str(), [](DArr B, DArr b, double g, double F, DArr old, int free) {
    require_shape(B, "B", {d, d}); require_shape(b, "b", {d}); require_shape(old, "old", {d});
    Vec<d> x = solve_node_coulomb<d>(CMatMap<d>(B.data()), CVecMap<d>(b.data()), g, F, CVecMap<d>(old.data()), (TangentMask)free);
    return to_numpy(std::vector<double>(x.data(), x.data() + d), {d});
  }, py::arg("B"), py::arg("b"), py::arg("g"), py::arg("F"), py::arg("old"), py::arg("free") = (int)all_tangents<d>());
  m.def(("contact_frames_" + sfx).c_str(), [](DArr normals, py::object fixed) {
    const py::ssize_t nc = normals.ndim() == 2 ? normals.shape(0) : 0;
    require_shape(normals, "normals", {nc, d});
    BArr fx;
    if (!fixed.is_none()) { fx = fixed.cast<BArr>(); require_shape(fx, "fixed", {nc, d}); }
    py::array_t<double> Q({nc, (py::ssize_t)d, (py::ssize_t)d});
    for (py::ssize_t c = 0; c < nc; ++c)
      MatMap<d>(Q.mutable_data() + c * d * d) = contact_frame<d>(normals.data() + c * d, fixed.is_none() ? nullptr : fx.data() + c * d, c);
    return Q;
  }, py::arg("normals"), py::arg("fixed") = py::none(),
  "the contact frames Q = [n, t(, s)] (columns) the solver builds for these normals and fixed canonical components");
  m.def(("classify_contact_dirichlet_" + sfx).c_str(), [](IArr nodes, BArr fixed, DArr values, DArr normals, DArr gaps) {
    const py::ssize_t nc = nodes.size();
    require_shape(fixed, "fixed", {nc, d}); require_shape(values, "values", {nc, d});
    require_shape(normals, "normals", {nc, d}); require_shape(gaps, "gaps", {nc});
    py::array_t<std::int8_t> kind(nc);
    for (py::ssize_t c = 0; c < nc; ++c)
      kind.mutable_at(c) = (std::int8_t)classify_contact_dirichlet<d>(normals.data() + c * d, gaps.data()[c], fixed.data() + c * d,
                                                                     values.data() + c * d, nodes.data()[c]);
    return kind;
  }, py::arg("nodes"), py::arg("fixed"), py::arg("values"), py::arg("normals"), py::arg("gaps"),
  "per contact node: 0 no component fixed, 1 tangential components fixed (a contact node), 2 normal prescribed "
  "(admissibly: not a contact node), 3 every component fixed; errors for penetration and misaligned rollers");
}

}  // namespace

void bind_solver(py::module_& m) {
  bind_dim<2>(m);
  bind_dim<3>(m);
}

}  // namespace cmg::bindings
