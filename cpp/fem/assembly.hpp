// Finite-element assembly of linear elasticity (P1/Q1, d = 2 plane strain and d = 3), loads and
// boundary measures; one generic routine per quantity, instantiated per cell type.
#pragma once
#include <cmath>
#include "base/block_matrix.hpp"
#include "fem/element.hpp"

namespace cmg {

struct Material {
  double E, nu;
  double lambda() const { return E * nu / ((1 + nu) * (1 - 2 * nu)); }
  double mu() const { return E / (2 * (1 + nu)); }
  void validate() const {
    if (!(E > 0) || !std::isfinite(E)) throw InputError("Young's modulus E must be positive and finite, got " + std::to_string(E));
    if (!(nu > -1 && nu < 0.5)) throw InputError("Poisson ratio nu must lie in (-1, 0.5), got " + std::to_string(nu));
  }
};

template <CellType T>
inline void gather(const double* points, const Index* cell, double* X) {
  constexpr int d = Element<T>::dim, k = Element<T>::nodes;
  for (int a = 0; a < k; ++a)
    for (int i = 0; i < d; ++i) X[a * d + i] = points[cell[a] * d + i];
}

// Every cell must have det J > 0 at its corners and quadrature points (inverted or degenerate
// cells would silently give an indefinite stiffness).
template <CellType T>
void check_cells(const double* points, Index n_points, const Index* cells, Index n_cells) {
  using E = Element<T>;
  constexpr int d = E::dim, k = E::nodes;
  const auto C = corners<T>();
  CellGeometry<T> geo;
  double X[k * d];
  for (Index c = 0; c < n_cells; ++c) {
    for (int a = 0; a < k; ++a)
      if (cells[c * k + a] < 0 || cells[c * k + a] >= n_points)
        throw InputError("cell " + std::to_string(c) + " refers to node " + std::to_string(cells[c * k + a]) +
                         ", outside 0.." + std::to_string(n_points - 1));
    gather<T>(points, cells + c * k, X);
    double h2 = 0;
    for (int a = 0; a < k; ++a)
      for (int b = a + 1; b < k; ++b) {
        double s = 0;
        for (int i = 0; i < d; ++i) s += (X[a * d + i] - X[b * d + i]) * (X[a * d + i] - X[b * d + i]);
        h2 = std::max(h2, s);
      }
    const double tol = 1e-12 * std::pow(h2, 0.5 * d);
    auto check = [&](const double* xi) {
      geo.at(X, xi);
      if (!(geo.detJ > tol))
        throw InputError(std::string("cell ") + std::to_string(c) + " (" + cell_name(T) + ") is " +
                         (geo.detJ < -tol ? "inverted" : "degenerate") + " (det J = " + std::to_string(geo.detJ) + ")");
    };
    for (int a = 0; a < k; ++a) check(C[a].data());
    for (int q = 0; q < E::nq; ++q) check(E::qp[q].data());
  }
}

// The block pattern of a mesh's couplings: row i holds, sorted, every node that shares a cell with node
// i -- the pattern pattern_from_groups gives -- made row by row from the cells around each node (32-bit
// cell ids) in two passes (lengths, then columns). Why: pattern_from_groups lists the k^2 64-bit pairs
// of every cell before sorting them, 2.3x the bytes of the finished matrix for tetrahedra and the peak
// of a 3D solve (docs/dev/decisions/0011-memory-release.md: 301 of 775 MiB at tetrahedral sphere level
// 4).
template <int d>
BlockMatrix<d> pattern_of_cells(Index n, const Index* cells, Index m, int k) {
  if (m > (Index)std::numeric_limits<ColIndex>::max()) return pattern_from_groups<d>(n, cells, m, k);
  check_block_count(n);
  std::vector<Index> ptr(n + 1, 0);  // the cells around node i: around[ptr[i]:ptr[i + 1]]
  for (Index e = 0; e < m * k; ++e) ++ptr[cells[e] + 1];
  for (Index i = 0; i < n; ++i) ptr[i + 1] += ptr[i];
  std::vector<ColIndex> around(ptr[n]);
  for (Index c = 0; c < m; ++c)
    for (int a = 0; a < k; ++a) around[ptr[cells[c * k + a]]++] = (ColIndex)c;  // ptr[i] moves to the end of row i
  for (Index i = n; i > 0; --i) ptr[i] = ptr[i - 1];                         // back to the starts
  ptr[0] = 0;
  std::vector<ColIndex> row;
  auto columns = [&](Index i) {
    row.clear();
    for (Index q = ptr[i]; q < ptr[i + 1]; ++q)
      for (int b = 0; b < k; ++b) row.push_back((ColIndex)cells[(Index)around[q] * k + b]);
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  };
  BlockMatrix<d> A;
  A.rows = A.cols = n;
  A.indptr.assign(n + 1, 0);
  for (Index i = 0; i < n; ++i) {
    columns(i);
    A.indptr[i + 1] = A.indptr[i] + (Index)row.size();
  }
  A.indices.resize(A.indptr[n]);
  for (Index i = 0; i < n; ++i) {
    columns(i);
    std::copy(row.begin(), row.end(), A.indices.begin() + A.indptr[i]);
  }
  A.values.assign(A.indices.size() * BlockMatrix<d>::bs, 0.0);
  A.find_diagonal();
  return A;
}

// The material of every cell: one for all (stride 0) or one per cell (stride 1), e.g. a body of
// several regions.
struct CellMaterials {
  const Material* materials;
  Index stride;
  const Material& operator[](Index c) const { return materials[c * stride]; }
};

template <CellType T>
BlockMatrix<Element<T>::dim> assemble_elasticity(const double* points, Index n_points, const Index* cells, Index n_cells,
                                                 const CellMaterials& materials) {
  using E = Element<T>;
  constexpr int d = E::dim, k = E::nodes;
  for (Index c = 0; c < (materials.stride ? n_cells : 1); ++c) materials[c].validate();
  BlockMatrix<d> A = pattern_of_cells<d>(n_points, cells, n_cells, k);
  CellGeometry<T> geo;
  double X[k * d];
  Eigen::Matrix<double, k * d, k * d> K;
  for (Index c = 0; c < n_cells; ++c) {
    const double lam = materials[c].lambda(), mu = materials[c].mu();
    const Index* cell = cells + c * k;
    gather<T>(points, cell, X);
    K.setZero();
    for (int q = 0; q < E::nq; ++q) {
      geo.at(X, E::qp[q].data());
      if (!(geo.detJ > 0) || !std::isfinite(geo.detJ))
        throw InputError("cell " + std::to_string(c) + " (" + cell_name(T) + ") is inverted or degenerate (det J = " +
                         std::to_string(geo.detJ) + ")");
      const double w = E::qw[q] * geo.detJ;
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const double gg = geo.grad.row(a).dot(geo.grad.row(b));
          for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j)
              K(a * d + i, b * d + j) += w * (lam * geo.grad(a, i) * geo.grad(b, j) + mu * geo.grad(a, j) * geo.grad(b, i) +
                                               (i == j ? mu * gg : 0.0));
        }
    }
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) {
        Index pos = A.find(cell[a], cell[b]);
        A.block(pos) += K.template block<d, d>(a * d, b * d);
      }
  }
  return A;
}

template <CellType T>
BlockMatrix<Element<T>::dim> assemble_elasticity(const double* points, Index n_points, const Index* cells, Index n_cells,
                                                 const Material& mat) {
  return assemble_elasticity<T>(points, n_points, cells, n_cells, CellMaterials{&mat, 0});
}

// Consistent load of a field given by its nodal values (interpolated with the same basis):
// F_a = sum over cells of integral phi_a phi_b v_b.
template <CellType T>
void assemble_mass_load(const double* points, const Index* cells, Index n_cells, const double* nodal, int ncomp,
                        double* out) {
  using E = Element<T>;
  constexpr int d = E::dim, k = E::nodes;
  CellGeometry<T> geo;
  double X[k * d], N[k];
  for (Index c = 0; c < n_cells; ++c) {
    const Index* cell = cells + c * k;
    gather<T>(points, cell, X);
    for (int q = 0; q < E::nq; ++q) {
      geo.at(X, E::qp[q].data());
      E::shape(E::qp[q].data(), N);
      const double w = E::qw[q] * geo.detJ;
      for (int m = 0; m < ncomp; ++m) {
        double v = 0;
        for (int b = 0; b < k; ++b) v += N[b] * nodal[cell[b] * ncomp + m];
        for (int a = 0; a < k; ++a) out[cell[a] * ncomp + m] += w * N[a] * v;
      }
    }
  }
}

// The same on boundary facets embedded in R^dim (lines in 2D; triangles/quads in 3D): the measure
// comes from the Gram determinant of the facet Jacobian.
template <CellType F, int dim>
void assemble_facet_load(const double* points, const Index* facets, Index n_facets, const double* nodal, int ncomp,
                         double* out) {
  using E = Element<F>;
  constexpr int k = E::nodes, r = E::dim;
  double N[k], G[k * r];
  for (Index f = 0; f < n_facets; ++f) {
    const Index* fc = facets + f * k;
    for (int q = 0; q < E::nq; ++q) {
      E::shape(E::qp[q].data(), N);
      E::grad(E::qp[q].data(), G);
      Eigen::Matrix<double, dim, r> J = Eigen::Matrix<double, dim, r>::Zero();
      for (int a = 0; a < k; ++a)
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < r; ++j) J(i, j) += points[fc[a] * dim + i] * G[a * r + j];
      const double w = E::qw[q] * std::sqrt((J.transpose() * J).determinant());
      for (int m = 0; m < ncomp; ++m) {
        double v = 0;
        for (int b = 0; b < k; ++b) v += N[b] * nodal[fc[b] * ncomp + m];
        for (int a = 0; a < k; ++a) out[fc[a] * ncomp + m] += w * N[a] * v;
      }
    }
  }
}

}  // namespace cmg
