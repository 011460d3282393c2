// Reference elements: first-order Lagrange shape functions and quadrature, one struct per cell type.
#pragma once
#include <array>
#include "fem/cell_table.hpp"

namespace cmg {

template <CellType T> struct Element;

template <> struct Element<CellType::Line> {
  static constexpr int dim = 1, nodes = 2, nq = 2;
  static constexpr double g = 0.57735026918962576451;
  static constexpr std::array<std::array<double, 1>, nq> qp{{{0.5 - 0.5 * g}, {0.5 + 0.5 * g}}};
  static constexpr std::array<double, nq> qw{0.5, 0.5};
  static void shape(const double* x, double* N) { N[0] = 1 - x[0]; N[1] = x[0]; }
  static void grad(const double*, double* G) { G[0] = -1; G[1] = 1; }
};

template <> struct Element<CellType::Triangle> {
  static constexpr int dim = 2, nodes = 3, nq = 3;
  static constexpr std::array<std::array<double, 2>, nq> qp{{{1. / 6, 1. / 6}, {2. / 3, 1. / 6}, {1. / 6, 2. / 3}}};
  static constexpr std::array<double, nq> qw{1. / 6, 1. / 6, 1. / 6};
  static void shape(const double* x, double* N) { N[0] = 1 - x[0] - x[1]; N[1] = x[0]; N[2] = x[1]; }
  static void grad(const double*, double* G) { G[0] = -1; G[1] = -1; G[2] = 1; G[3] = 0; G[4] = 0; G[5] = 1; }
};

template <> struct Element<CellType::Quad> {
  static constexpr int dim = 2, nodes = 4, nq = 4;
  static constexpr double a = 0.5 - 0.28867513459481288225, b = 0.5 + 0.28867513459481288225;
  static constexpr std::array<std::array<double, 2>, nq> qp{{{a, a}, {b, a}, {b, b}, {a, b}}};
  static constexpr std::array<double, nq> qw{0.25, 0.25, 0.25, 0.25};
  // counterclockwise: (0,0) (1,0) (1,1) (0,1)
  static void shape(const double* x, double* N) {
    N[0] = (1 - x[0]) * (1 - x[1]); N[1] = x[0] * (1 - x[1]); N[2] = x[0] * x[1]; N[3] = (1 - x[0]) * x[1];
  }
  static void grad(const double* x, double* G) {
    G[0] = -(1 - x[1]); G[1] = -(1 - x[0]);
    G[2] = (1 - x[1]);  G[3] = -x[0];
    G[4] = x[1];        G[5] = x[0];
    G[6] = -x[1];       G[7] = (1 - x[0]);
  }
};

template <> struct Element<CellType::Tetra> {
  static constexpr int dim = 3, nodes = 4, nq = 4;
  static constexpr double a = 0.1381966011250105, b = 0.5854101966249685;
  static constexpr std::array<std::array<double, 3>, nq> qp{{{a, a, a}, {b, a, a}, {a, b, a}, {a, a, b}}};
  static constexpr std::array<double, nq> qw{1. / 24, 1. / 24, 1. / 24, 1. / 24};
  static void shape(const double* x, double* N) { N[0] = 1 - x[0] - x[1] - x[2]; N[1] = x[0]; N[2] = x[1]; N[3] = x[2]; }
  static void grad(const double*, double* G) {
    const double g[12] = {-1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 12; ++i) G[i] = g[i];
  }
};

template <> struct Element<CellType::Hexahedron> {
  static constexpr int dim = 3, nodes = 8, nq = 8;
  static constexpr double a = 0.5 - 0.28867513459481288225, b = 0.5 + 0.28867513459481288225;
  static constexpr std::array<std::array<double, 3>, nq> qp{
      {{a, a, a}, {b, a, a}, {b, b, a}, {a, b, a}, {a, a, b}, {b, a, b}, {b, b, b}, {a, b, b}}};
  static constexpr std::array<double, nq> qw{0.125, 0.125, 0.125, 0.125, 0.125, 0.125, 0.125, 0.125};
  // VTK ordering: bottom face counterclockwise, then top face.
  static constexpr int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  static double f1(int c, double t) { return c ? t : 1 - t; }
  static double d1(int c) { return c ? 1.0 : -1.0; }
  static void shape(const double* x, double* N) {
    for (int i = 0; i < 8; ++i) N[i] = f1(corner[i][0], x[0]) * f1(corner[i][1], x[1]) * f1(corner[i][2], x[2]);
  }
  static void grad(const double* x, double* G) {
    for (int i = 0; i < 8; ++i) {
      const int* c = corner[i];
      G[3 * i + 0] = d1(c[0]) * f1(c[1], x[1]) * f1(c[2], x[2]);
      G[3 * i + 1] = f1(c[0], x[0]) * d1(c[1]) * f1(c[2], x[2]);
      G[3 * i + 2] = f1(c[0], x[0]) * f1(c[1], x[1]) * d1(c[2]);
    }
  }
};

// Reference corner coordinates (for Jacobian checks at the vertices).
template <CellType T> inline std::array<std::array<double, Element<T>::dim>, Element<T>::nodes> corners();
template <> inline std::array<std::array<double, 2>, 3> corners<CellType::Triangle>() { return {{{0, 0}, {1, 0}, {0, 1}}}; }
template <> inline std::array<std::array<double, 2>, 4> corners<CellType::Quad>() { return {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}}; }
template <> inline std::array<std::array<double, 3>, 4> corners<CellType::Tetra>() { return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}; }
template <> inline std::array<std::array<double, 3>, 8> corners<CellType::Hexahedron>() {
  std::array<std::array<double, 3>, 8> c{};
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) c[i][k] = Element<CellType::Hexahedron>::corner[i][k];
  return c;
}

// Geometry of one cell at a reference point: physical shape gradients and det J.
template <CellType T>
struct CellGeometry {
  using E = Element<T>;
  static constexpr int d = E::dim, k = E::nodes;
  Eigen::Matrix<double, k, d> grad;  // physical gradients, row a = grad phi_a
  double detJ = 0;
  void at(const double* X /* k x d node coordinates, row-major */, const double* xi) {
    Eigen::Matrix<double, k, d, Eigen::RowMajor> Gr;
    E::grad(xi, Gr.data());
    Eigen::Map<const Eigen::Matrix<double, k, d, Eigen::RowMajor>> Xm(X);
    Eigen::Matrix<double, d, d> J = Xm.transpose() * Gr;  // J_ij = dx_i/dxi_j
    detJ = J.determinant();
    grad = Gr * J.inverse();
  }
};

}  // namespace cmg
