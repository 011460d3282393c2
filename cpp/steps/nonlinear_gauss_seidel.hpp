// Nonlinear Gauss-Seidel on the fine level: each node in turn minimizes the energy exactly, with
// the law's nodal solve at contact nodes and the inverted diagonal block elsewhere. A solution is
// a fixed point of a sweep (the nodal rules keep every local solution), which makes the sweep
// both the smoother and the independent stopping check.
#pragma once
#include "contact_problem.hpp"
#include "mg/level_smoothers.hpp"

namespace cmg {

template <int d, class L>
struct NonlinearGaussSeidel {
  static void sweep(const ContactProblem<d>& P, double* u, bool forward, const SweepOrder& order = SweepOrder()) {
    const BlockMatrix<d>& A = P.matrix();
    const double* f = P.load().data();
    const double omega = P.smoothing_omega();
    order.visit(A.rows, forward, [&](Index i) {
      const Vec<d> b = local_rhs<d>(A, u, f, i);
      VecMap<d> ui(u + d * i);
      const Index c = L::has_contact ? P.contact_of_node(i) : -1;
      if (c < 0) {
        relaxed_assign<d>(ui, P.diagonal_inverse(i) * b, omega);
        return;
      }
      const Mat<d> B = A.block(A.diag[i]);
      ui = L::template solve<d>(B, b, P.node(c), Vec<d>(ui));
    });
  }
};

}  // namespace cmg
