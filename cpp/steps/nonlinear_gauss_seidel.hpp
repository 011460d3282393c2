// Nonlinear Gauss-Seidel on the fine level: each node in turn minimizes the energy exactly, with
// the law's nodal solve at contact nodes and the inverted diagonal block elsewhere. A solution is
// a fixed point of a sweep (the nodal rules keep every local solution), which makes the sweep
// both the smoother and the independent stopping check.
#pragma once
#include "model/contact_problem.hpp"
#include "mg/level_smoothers.hpp"

namespace cmg {

template <int d, class L>
struct NonlinearGaussSeidel {
  // omega: the over-relaxation of the rows without contact, an argument of every sweep (the
  // options' omega, or omega_post for the post-smoothing; never state of the problem). per_row:
  // every row through row_update, also on a level stored by colours (tests compare it with the
  // range kernel).
  static void sweep(const ContactProblem<d>& P, double* u, bool forward, const SweepOrder& order, double omega,
                    bool per_row = false) {
    if (order.contiguous() && !per_row) {
      order.visit_ranges(forward, [&](Index b, Index e) { sweep_range(P, u, b, e, omega); });
      return;
    }
    order.visit(P.matrix().rows, forward, [&](Index i) { row_update(P, u, i, omega); });
  }

  // Row i, whatever it is: the law's nodal solve at a contact node, the diagonal block's inverse
  // (a special one where kept) elsewhere.
  static void row_update(const ContactProblem<d>& P, double* u, Index i, double omega) {
    const BlockMatrix<d>& A = P.matrix();
    const Vec<d> b = local_rhs<d>(A, u, P.load().data(), i);
    VecMap<d> ui(u + d * i);
    const Index c = L::has_contact ? P.contact_of_node(i) : -1;
    if (c < 0) {
      relaxed_assign<d>(ui, P.diagonal_inverse(i) * b, omega);
      return;
    }
    const Mat<d> B = A.block(A.diag[i]);
    ui = L::template solve<d>(B, b, P.node(c), Vec<d>(ui));
  }

  // The rows [b, e) of one colour (a level stored by colours). Nearly every row is neither a contact
  // node nor one with a special inverse: those run in this loop, with the matrix arrays in registers,
  // one flag byte read per row, the inverse formed inline and x prefetched at the columns of the row
  // kPrefetchRows ahead (the neighbours' x are in other colours' ranges: their loads stalled the sweep,
  // docs/dev/decisions/0015-locality-order.md). The rest go through row_update, out of line. The same
  // sums and products in the same order as row_update: the same bits (the test above).
  static void sweep_range(const ContactProblem<d>& P, double* u, Index b, Index e, double omega) {
    // the prefetches run on past e, into the rows of the next colour
    const Index n = P.matrix().rows;
    sweep_rows(P, u, e - b, omega, [b](Index q) { return b + q; }, [b, n](Index q) { return b + q < n; });
  }

  // The rows rows[0], ..., rows[count - 1] in that order (backward: the reverse), by the loop of
  // sweep_range: the owned rows of one colour between two ghost exchanges of a distributed sweep
  // (python/contactmg/distributed/cycle.py), stored in ascending global id rather than by colours.
  // The prefetches look ahead in the list. The same bits as row_update.
  static void sweep_list(const ContactProblem<d>& P, double* u, const Index* rows, Index count, bool forward, double omega) {
    const auto in_list = [count](Index q) { return q < count; };
    if (forward) sweep_rows(P, u, count, omega, [rows](Index q) { return rows[q]; }, in_list);
    else sweep_rows(P, u, count, omega, [rows, count](Index q) { return rows[count - 1 - q]; }, in_list);
  }

 private:
  // The loop of sweep_range and sweep_list over rows row(0), ..., row(count - 1); row(q) is
  // prefetched where has(q).
  template <class Row, class Has>
  static void sweep_rows(const ContactProblem<d>& P, double* u, Index count, double omega, Row row, Has has) {
    using CP = ContactProblem<d>;
    const BlockMatrix<d>& A = P.matrix();
    const double* values = A.values.data();
    const ColIndex* cols = A.indices.data();
    const Index* ptr = A.indptr.data();
    const Index* diag = A.diag.data();
    const double* f = P.load().data();
    const std::uint8_t* flags = P.row_flags();
    // law::Linear has no contact rows: its contact nodes only carry frames (row_update's c < 0)
    const std::uint8_t other = L::has_contact ? (CP::kSpecialInverse | CP::kContactRow) : CP::kSpecialInverse;
    for (Index q = 0; q < count; ++q) {
      const Index i = row(q);
      prefetch_rows_ahead<d>(values, cols, ptr, u, q, row, has);
      if (flags[i] & other) {
        other_row(P, u, i, omega);
        continue;
      }
      const Index kd = diag[i];  // >= 0: a row without a diagonal block has a special inverse
      Vec<d> s = CVecMap<d>(f + d * i);
      accumulate_blocks<d, true>(values, cols, ptr[i], kd, u, s.data());
      accumulate_blocks<d, true>(values, cols, kd + 1, ptr[i + 1], u, s.data());
      const Mat<d> inv = Mat<d>(CMatMap<d>(values + kd * d * d)).inverse();  // ContactProblem::diagonal_inverse's
      relaxed_block_solve<d>(inv, s.data(), u + d * i, omega);
    }
  }

  __attribute__((noinline)) static void other_row(const ContactProblem<d>& P, double* u, Index i, double omega) {
    row_update(P, u, i, omega);
  }
};

}  // namespace cmg
