// Geometry and discretization: the cell types, mesh checks, assembly of the stiffness matrix and
// the loads, uniform refinement and newest-vertex bisection. Shapes are checked here; Python
// checks meaning.
#include "bindings/common.hpp"
#include "fem/assembly.hpp"
#include "fem/bisection.hpp"
#include "fem/bisection_3d.hpp"
#include "fem/refine_2d.hpp"
#include "fem/refine_3d.hpp"

namespace cmg::bindings {

namespace {

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

void bind_fem(py::module_& m) {
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

  m.def("assemble_elasticity", [](DArr points, IArr cells, const std::string& cell_type, DArr E, DArr nu) -> py::object {
    // E and nu: one number each, or one per cell (a body of several materials)
    MeshView v = view(points, cells, cell_type);
    const bool per_cell = E.ndim() == 1;
    if (per_cell) {
      require_shape(E, "E", {(py::ssize_t)v.m});
      require_shape(nu, "nu", {(py::ssize_t)v.m});
    } else if (E.ndim() != 0 || nu.ndim() != 0) {
      throw InputError("E and nu must be numbers or arrays with one value per cell");
    }
    std::vector<Material> mats(per_cell ? v.m : 1);
    for (size_t c = 0; c < mats.size(); ++c) {
      mats[c] = Material{E.data()[c], nu.data()[c]};
      mats[c].validate();
    }
    return dispatch_cell(v.type, [&](auto T) -> py::object {
      constexpr CellType t = decltype(T)::value;
      auto A = std::make_shared<BlockMatrix<Element<t>::dim>>();
      {
        py::gil_scoped_release r;
        *A = assemble_elasticity<t>(v.X, v.n, v.C, v.m, CellMaterials{mats.data(), per_cell ? 1 : 0});
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

}  // namespace cmg::bindings
