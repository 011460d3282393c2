// pybind11 bindings: small flat functions over numpy arrays and two classes per dimension
// (BlockMatrix, ContactSolver). Shapes are checked here; Python checks meaning.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <utility>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include "bandwidth.hpp"
#include "contact_solver.hpp"
#include "fem/assembly.hpp"
#include "fem/bisection.hpp"
#include "fem/bisection_3d.hpp"
#include "fem/refine_2d.hpp"
#include "fem/refine_3d.hpp"

namespace py = pybind11;
using namespace cmg;

using DArr = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IArr = py::array_t<Index, py::array::c_style | py::array::forcecast>;
using BArr = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

namespace {

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

struct MeshView {
  CellType type;
  int d, k;
  const double* X;
  Index n;
  const Index* C;
  Index m;
};
MeshView view(const DArr& points, const IArr& cells, const std::string& cell_type) {
  MeshView v;
  v.type = parse_cell(cell_type);
  v.d = cell_info(v.type).dim;
  v.k = cell_info(v.type).nodes;
  require_shape(points, "points", {-1, v.d});
  require_shape(cells, "cells", {-1, v.k});
  v.X = points.data(); v.n = points.shape(0); v.C = cells.data(); v.m = cells.shape(0);
  for (Index i = 0; i < v.n * v.d; ++i)
    if (!std::isfinite(v.X[i])) throw InputError("point " + std::to_string(i / v.d) + " has a non-finite coordinate");
  for (Index i = 0; i < v.m * v.k; ++i)
    if (v.C[i] < 0 || v.C[i] >= v.n)
      throw InputError("cell " + std::to_string(i / v.k) + " refers to node " + std::to_string(v.C[i]) + ", outside 0.." + std::to_string(v.n - 1));
  return v;
}

template <class T>
py::array_t<T> to_numpy(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

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

py::dict record_to_dict(const CycleRecord& r) {
  py::dict o;
  o["cycle"] = r.cycle; o["outer"] = r.outer; o["correction_norm"] = r.correction_norm; o["energy"] = r.energy;
  o["seconds"] = r.seconds; o["error"] = r.error; o["active"] = r.active; o["stick"] = r.stick; o["slip"] = r.slip;
  o["rebuilt"] = r.rebuilt; o["step_size"] = r.step_size; o["frozen_decrease"] = r.frozen_decrease;
  o["linear_iterations"] = r.linear_iterations;
  return o;
}

// The vector handed over to numpy without a copy (the array owns it).
py::array_t<double> moved_to_numpy(std::vector<double>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<double>(std::move(v));
  py::capsule free_it(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(shape, owned->data(), free_it);
}

// the lines of a line smoother as a list of node-id arrays, each in chain order
py::list lines_to_list(const LineSet& L) {
  py::list out;
  for (Index k = 0; k < L.num_lines(); ++k)
    out.append(to_numpy(std::vector<Index>(L.nodes.begin() + L.ptr[k], L.nodes.begin() + L.ptr[k + 1]),
                        {(py::ssize_t)(L.ptr[k + 1] - L.ptr[k])}));
  return out;
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
  const py::ssize_t h = R.history.size();
  py::array_t<int> cyc(h), outer(h), linits(h);
  py::array_t<double> cn(h), en(h), sec(h), err(h), step(h), fdec(h);
  py::array_t<Index> act(h), st(h), sl(h);
  py::array_t<bool> rb(h);
  py::array_t<std::int8_t> pg(h);
  for (py::ssize_t k = 0; k < h; ++k) {
    const auto& r = R.history[k];
    cyc.mutable_at(k) = r.cycle; outer.mutable_at(k) = r.outer; cn.mutable_at(k) = r.correction_norm;
    en.mutable_at(k) = r.energy; sec.mutable_at(k) = r.seconds; err.mutable_at(k) = r.error; act.mutable_at(k) = r.active;
    st.mutable_at(k) = r.stick; sl.mutable_at(k) = r.slip; rb.mutable_at(k) = r.rebuilt;
    step.mutable_at(k) = r.step_size; fdec.mutable_at(k) = r.frozen_decrease; linits.mutable_at(k) = r.linear_iterations;
    pg.mutable_at(k) = (std::int8_t)r.petrov_galerkin;
  }
  py::dict hist;
  hist["cycle"] = cyc; hist["outer"] = outer; hist["correction_norm"] = cn; hist["energy"] = en;
  hist["seconds"] = sec; hist["error"] = err; hist["active"] = act; hist["stick"] = st; hist["slip"] = sl; hist["rebuilt"] = rb;
  hist["step_size"] = step; hist["frozen_decrease"] = fdec; hist["linear_iterations"] = linits;
  hist["petrov_galerkin"] = pg;
  out["history"] = hist;
  out["outer_changes"] = to_numpy(R.outer_changes, {(py::ssize_t)R.outer_changes.size()});
  out["converged"] = R.converged;
  out["status"] = R.status;
  out["cycles"] = R.cycles;
  out["outer_iterations"] = R.outer_iterations;
  out["rebuilds"] = R.rebuilds;
  out["seconds"] = R.seconds;
  out["rebuild_seconds"] = R.rebuild_seconds;
  out["sweep_check"] = R.sweep_check;
  py::dict phases;
  for (int k = 0; k < (int)Phase::Count; ++k) phases[phase_name(k)] = R.phase_seconds[k];
  out["phase_seconds"] = phases;
  return out;
}


// --- the options dict: the field names of SolverOptions (solver/solver_options.hpp) -------------
bool is_integer(py::handle v) { return !PyBool_Check(v.ptr()) && PyIndex_Check(v.ptr()); }
bool is_real(py::handle v) { return !PyBool_Check(v.ptr()) && (PyFloat_Check(v.ptr()) || PyIndex_Check(v.ptr()) || py::isinstance(v, py::module_::import("numbers").attr("Real"))); }

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
                                      "projected_coarse_correction"};
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
      .def("memory_bytes", &BM::memory_bytes)
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
           "bad value raises ValueError): the options every solve starts from. ordering 'coloured' also stores every "
           "level but the coarsest by colours (each colour one contiguous range of rows, so a coloured sweep streams "
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
             if (co.omega_post > 0) out["omega_post"] = co.omega_post;
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
           "called after every cycle (cycle, outer, correction_norm, energy, seconds, error, active, stick, slip, rebuilt, "
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
      .def("smooth", [](CS& S, DArr u0, int sweeps, const std::string& ordering, int threads, double omega, bool per_row) {
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
           }, py::arg("u0"), py::arg("sweeps") = 1, py::arg("ordering") = "lexicographic", py::arg("threads") = 0,
           py::arg("omega") = 1.0, py::arg("per_row") = false,
           "Nonlinear Gauss-Seidel sweeps (alternating, forward first) from u0; a solution is a fixed point. omega: the "
           "over-relaxation of the rows without contact; per_row: every row through the per-row path (the reference of "
           "the range kernel of a level stored by colours)")
      .def_property_readonly("num_levels", [](const CS& S) { return S.hierarchy().num_coarse_levels() + 1; })
      .def_property_readonly("frames", [](const CS& S) { return frames_array<d>(S); },
                             "the contact frames Q = [n, t(, s)] (columns), shape (num_contact, d, d)")
      .def_property_readonly("frame_fixed", [](const CS& S) { return frame_fixed_array<d>(S); },
                             "the components of each contact node fixed in its frame (num_contact, d)")
      .def("coarse_matrix", [](const CS& S, int l) {
             if (l < 0 || l >= S.hierarchy().num_coarse_levels()) throw py::index_error("no such coarse level");
             return std::make_shared<BM>(S.coarse_matrix_in_user_order(l));
           })
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
      .def_property_readonly("coarsest_factorizations", [](const CS& S) { return S.hierarchy().coarsest_factorizations(); },
                             "factorizations of the coarsest-level matrix by this solver so far")
      .def("keep_workspace", &CS::keep_workspace, py::arg("on"),
           "whether the fine vectors of the cycles (r, u_old, the Anderson history) stay from one solve to the next "
           "(True, the default: a later solve touches no new pages) or go at the end of each (a solver made for one "
           "solve: the lower peak); returns the previous setting")
      .def("fine_matrix", [](const CS& S) { return std::make_shared<BM>(S.fine_matrix_in_user_order()); })
      .def_property_readonly("renumbered", &CS::renumbered, "whether the levels are stored by colours")
      .def("memory_bytes", &CS::memory_bytes)
      .def_property_readonly("num_colours", &CS::num_fine_colours, "colours of the fine block graph (coloured sweeps)")
      .def("rebuild_coarse", &CS::rebuild_coarse, "Full Galerkin rebuild of the coarse matrices for the current truncation")
      .def("linear_solve", [](CS& S, DArr r, int max_iterations, double reduction, bool lines, py::object cycle) {
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
           }, py::arg("r"), py::arg("max_iterations"), py::arg("reduction") = 0.0, py::arg("lines") = true,
           py::arg("cycle") = py::none(),
           "TNNMG's linear correction on the current linearization (fresh solver: linear elasticity in the contact "
           "frames, Dirichlet dofs masked): PCG preconditioned by the truncated linear cycle for K w = M r, r in the "
           "frames. Returns (w, energies after each iteration)")
      .def("fine_lines", [](CS& S, bool lines) {
             return lines_to_list(S.fine_lines(lines));
           }, py::arg("lines") = true, "the lines of the fine line smoother (node ids in chain order)")
      .def("coarse_lines", [](const CS& S, int l) {
             if (l < 0 || l >= S.hierarchy().num_coarse_levels()) throw py::index_error("no such coarse level");
             return lines_to_list(S.coarse_lines(l));
           }, py::arg("level"), "the lines of coarse level `level` (node ids in chain order)")
      .def("enable_tied_correction", &CS::enable_tied_correction,
           "after each nmg coarse correction a second one, without bounds, with every contact dof frozen (two bodies)")
      .def_property_readonly("tied_correction", &CS::tied_correction);

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
  m.def(("friction_hessian_" + sfx).c_str(), [](double s, DArr u, int free) {
    require_shape(u, "u", {d});
    Mat<d> H = friction_hessian<d>(s, u.data(), (TangentMask)free);
    py::array_t<double> out({(py::ssize_t)d, (py::ssize_t)d});
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) out.mutable_at(a, b) = H(a, b);
    return out;
  }, py::arg("s"), py::arg("u"), py::arg("free") = (int)all_tangents<d>(),
  "Hessian of s |u_T| (frame components, free tangential mask) at a sliding node");
  m.def(("galerkin_product_" + sfx).c_str(), [](const BM& A, Index n_coarse, IArr ptr, IArr parent, DArr weight) {
    if (ptr.size() != A.rows + 1) throw InputError("ptr must have num_fine + 1 entries");
    Prolongation<d> P = make_prolongation<d>(A.rows, n_coarse, ptr.data(), parent.data(), weight.data());
    auto C = std::make_shared<BM>();
    GalerkinProduct<d> gp;
    gp.build(A, P, nullptr, *C);
    return C;
  });
}

// The fine mesh and the interpolation of one refinement step (uniform or bisection) as numpy arrays.
py::dict refined_to_dict(const RefinedMesh& R, int d, int k, int kf) {
  py::dict out;
  out["points"] = to_numpy(R.points, {(py::ssize_t)R.points.size() / d, d});
  out["cells"] = to_numpy(R.cells, {(py::ssize_t)R.cells.size() / k, k});
  out["facets"] = to_numpy(R.facets, {(py::ssize_t)R.facets.size() / kf, kf});
  out["facet_tags"] = to_numpy(R.facet_tags, {(py::ssize_t)R.facet_tags.size()});
  out["ptr"] = to_numpy(R.ptr, {(py::ssize_t)R.ptr.size()});
  out["parent"] = to_numpy(R.parent, {(py::ssize_t)R.parent.size()});
  out["weight"] = to_numpy(R.weight, {(py::ssize_t)R.weight.size()});
  out["boundary_nodes"] = to_numpy(R.boundary_nodes, {(py::ssize_t)R.boundary_nodes.size()});
  out["boundary_tags"] = to_numpy(R.boundary_tags, {(py::ssize_t)R.boundary_tags.size()});
  return out;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "contactmg compiled core";
#ifdef __GLIBC__
  // Allocations of 1 MiB and more get pages of their own and go back to the system when freed.
  // glibc's default threshold grows to 32 MiB after the first large free, and then the level-sized
  // temporaries of setup and of a solve's results stayed in the heap: 28 MiB of the peak at level 9
  // (issue 15).
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  bind_dim<2>(m);
  bind_dim<3>(m);

  m.def("openmp", [] { return have_openmp(); }, "whether the core was built with OpenMP threads");
  m.def("max_threads", [] { return max_threads(); }, "the cores the threads of a solve may use (threads=0)");
  // Tests: the coarsest solver on its own -- S0 factorized, then S as an update (a low-rank
  // correction where it allows one), then a solve with b. Returns (x, rank of the correction,
  // factorizations of this solver). Dense n x n arrays in, their nonzero entries taken.
  m.def("_coarsest_update_solve", [](DArr S0, DArr S, DArr b) {
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
    SettledAnderson A;
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
      mixed.mutable_at(s) = A.step(x, gx, [&](std::vector<double>&, const std::vector<double>&) {
        return refuse_every <= 0 || ++calls % refuse_every != 0;
      });
      x = gx;
      std::copy(x.begin(), x.end(), out.mutable_data() + s * n);
    }
    return py::make_tuple(out, mixed);
  }, py::arg("M"), py::arg("c"), py::arg("x0"), py::arg("steps"), py::arg("refuse_every") = 0, py::arg("threads") = 1,
  "test hook: the iterates x <- mix(diag(M, M, ...) x + c) of steps/settled_anderson.hpp (every refuse_every-th candidate refused) "
  "and whether each step took the mixed iterate");
  m.def("cell_table", [] {
    py::dict out;
    for (const CellInfo& c : cell_table()) {
      py::dict e;
      e["dim"] = c.dim;
      e["nodes"] = c.nodes;
      e["facet_type"] = cell_name(c.facet_type);
      e["facet_nodes"] = c.facet_nodes;
      py::list facets;
      for (int f = 0; f < c.num_facets; ++f) {
        py::list fl;
        for (int a = 0; a < c.facet_nodes; ++a) fl.append(c.facets[f][a]);
        facets.append(py::tuple(fl));
      }
      e["facets"] = facets;
      e["body"] = c.volume;
      out[c.name] = e;
    }
    return out;
  }, "The cell types of the core: dim, nodes, facet type, local nodes of each facet, whether a body cell");

  m.def("check_cells", [](DArr points, IArr cells, const std::string& cell_type) {
    MeshView v = view(points, cells, cell_type);
    dispatch_cell(v.type, [&](auto T) { check_cells<decltype(T)::value>(v.X, v.n, v.C, v.m); });
  });

  m.def("assemble_elasticity", [](DArr points, IArr cells, const std::string& cell_type, double E, double nu) -> py::object {
    MeshView v = view(points, cells, cell_type);
    Material mat{E, nu};
    mat.validate();
    return dispatch_cell(v.type, [&](auto T) -> py::object {
      constexpr CellType t = decltype(T)::value;
      auto A = std::make_shared<BlockMatrix<Element<t>::dim>>();
      {
        py::gil_scoped_release r;
        *A = assemble_elasticity<t>(v.X, v.n, v.C, v.m, mat);
      }
      return py::cast(A);
    });
  }, py::arg("points"), py::arg("cells"), py::arg("cell_type"), py::arg("E"), py::arg("nu"));

  m.def("assemble_mass_load", [](DArr points, IArr cells, const std::string& cell_type, DArr nodal) {
    MeshView v = view(points, cells, cell_type);
    if (nodal.ndim() != 2 || nodal.shape(0) != v.n) throw InputError("nodal values must have shape (num_points, components)");
    const int nc = nodal.shape(1);
    py::array_t<double> out({(py::ssize_t)v.n, (py::ssize_t)nc});
    std::fill(out.mutable_data(), out.mutable_data() + v.n * nc, 0.0);
    dispatch_cell(v.type, [&](auto T) { assemble_mass_load<decltype(T)::value>(v.X, v.C, v.m, nodal.data(), nc, out.mutable_data()); });
    return out;
  });

  m.def("assemble_facet_load", [](DArr points, IArr facets, DArr nodal) {
    const int d = points.ndim() == 2 ? points.shape(1) : 0;
    if (d != 2 && d != 3) throw InputError("points must have shape (n, 2) or (n, 3)");
    const int kf = facets.ndim() == 2 ? facets.shape(1) : 0;
    const Index n = points.shape(0), nf = facets.shape(0);
    if (!((d == 2 && kf == 2) || (d == 3 && (kf == 3 || kf == 4))))
      throw InputError("facets must have 2 nodes in 2D and 3 or 4 nodes in 3D");
    if (nodal.ndim() != 2 || nodal.shape(0) != n) throw InputError("nodal values must have shape (num_points, components)");
    for (Index i = 0; i < nf * kf; ++i)
      if (facets.data()[i] < 0 || facets.data()[i] >= n) throw InputError("a facet refers to a node out of range");
    const int nc = nodal.shape(1);
    py::array_t<double> out({(py::ssize_t)n, (py::ssize_t)nc});
    std::fill(out.mutable_data(), out.mutable_data() + n * nc, 0.0);
    if (d == 2) assemble_facet_load<CellType::Line, 2>(points.data(), facets.data(), nf, nodal.data(), nc, out.mutable_data());
    else if (kf == 3) assemble_facet_load<CellType::Triangle, 3>(points.data(), facets.data(), nf, nodal.data(), nc, out.mutable_data());
    else assemble_facet_load<CellType::Quad, 3>(points.data(), facets.data(), nf, nodal.data(), nc, out.mutable_data());
    return out;
  });

  m.def("refine", [](DArr points, IArr cells, const std::string& cell_type, IArr facets, IArr facet_tags) {
    MeshView v = view(points, cells, cell_type);
    const int kf = v.d == 2 ? 2 : (v.type == CellType::Tetra ? 3 : 4);
    require_shape(facets, "facets", {-1, kf});
    require_shape(facet_tags, "facet_tags", {facets.shape(0)});
    for (Index i = 0; i < (Index)facets.size(); ++i)
      if (facets.data()[i] < 0 || facets.data()[i] >= v.n) throw InputError("a facet refers to a node out of range");
    RefinedMesh R;
    {
      py::gil_scoped_release r;
      R = v.d == 2 ? refine_2d(v.type, v.X, v.n, v.C, v.m, facets.data(), facet_tags.data(), facets.shape(0))
                   : refine_3d(v.type, v.X, v.n, v.C, v.m, facets.data(), facet_tags.data(), facets.shape(0));
    }
    return refined_to_dict(R, v.d, v.k, kf);
  });

  m.def("bisect", [](DArr points, IArr cells, IArr facets, IArr facet_tags, IArr marked_cells, py::object marks,
                     int generations) {
    const bool three = points.ndim() == 2 && points.shape(1) == 3;
    MeshView v = view(points, cells, three ? "tetra" : "triangle");
    require_shape(facets, "facets", {-1, three ? 3 : 2});
    require_shape(facet_tags, "facet_tags", {facets.shape(0)});
    require_shape(marked_cells, "marked_cells", {-1});
    if (!three) {
      if (!marks.is_none()) throw InputError("marks are for tetrahedra: a triangle's state is its vertex order");
      RefinedMesh R;
      {
        py::gil_scoped_release r;
        R = bisect_2d(v.X, v.n, v.C, v.m, facets.data(), facet_tags.data(), facets.shape(0), marked_cells.data(),
                      marked_cells.shape(0));
      }
      return refined_to_dict(R, 2, 3, 2);
    }
    IArr state;
    if (!marks.is_none()) {
      state = marks.cast<IArr>();
      require_shape(state, "marks", {v.m});
    }
    Bisected3D B;
    {
      py::gil_scoped_release r;
      B = bisect_3d(v.X, v.n, v.C, v.m, facets.data(), facet_tags.data(), facets.shape(0), marked_cells.data(),
                    marked_cells.shape(0), marks.is_none() ? nullptr : state.data(), generations);
    }
    py::dict out = refined_to_dict(B.mesh, 3, 4, 3);
    out["marks"] = to_numpy(B.marks, {(py::ssize_t)B.marks.size()});
    out["edge_parents"] = to_numpy(B.edge_parents, {(py::ssize_t)B.edge_parents.size() / 2, 2});
    out["bisections"] = B.bisections;
    return out;
  }, py::arg("points"), py::arg("cells"), py::arg("facets"), py::arg("facet_tags"), py::arg("marked_cells"),
     py::arg("marks") = py::none(), py::arg("generations") = 3,
     "Newest-vertex bisection of the marked cells with conforming closure; the same keys as refine(). "
     "Triangles (points n x 2): the refinement edge is the first two vertices of a cell, every edge of a "
     "marked cell is bisected. Tetrahedra (points n x 3): Arnold-Mukherjee-Pouly marked bisection, every "
     "marked cell bisected `generations` times; `marks` is the state of the cells from the previous call "
     "(None: the initial longest-edge marking of this mesh); the result adds 'marks' (the state of the "
     "fine cells, whose vertex order it also fixes), 'edge_parents' (the two ends of the edge each new "
     "node bisects) and 'bisections'");
}
