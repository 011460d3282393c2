// Gauss-Seidel sweeps on one level: block (linear) and projected (bounds per component), over the
// rows of a SweepOrder; and the inverted diagonal blocks they use.
#pragma once
#include <algorithm>
#include "base/block_matrix.hpp"
#include "mg/sweep_order.hpp"

namespace cmg {

// Largest diagonal entry: the scale of the inert-dof test below.
template <int d>
double max_diagonal(const BlockMatrix<d>& A) {
  double m = 0;
  for (Index i = 0; i < A.rows; ++i)
    if (A.diag[i] >= 0)
      for (int c = 0; c < d; ++c) m = std::max(m, A.block(A.diag[i])(c, c));
  return m;
}

// Inverse of a symmetric positive semi-definite diagonal block; where the block is singular (a
// truncated coarse node whose x and y dofs both map onto the one tangential direction of rotated
// fine frames) the pseudo-inverse: the minimum-norm exact minimizer over the block, so the sweep
// still lowers the energy, where the plain inverse gave inf/NaN.
template <int d>
Mat<d> block_inverse(const Mat<d>& D) {
  Eigen::LLT<Mat<d>> llt(D);
  const double top = D.diagonal().cwiseAbs().maxCoeff();
  if (llt.info() == Eigen::Success && llt.matrixL().toDenseMatrix().diagonal().minCoeff() > 1e-6 * std::sqrt(top))
    return D.inverse();
  Eigen::SelfAdjointEigenSolver<Mat<d>> es(D);
  const auto ev = es.eigenvalues();
  const double cut = 1e-12 * std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
  Mat<d> inv = Mat<d>::Zero();
  for (int k = 0; k < d; ++k)
    if (ev[k] > cut) inv += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / ev[k];
  return inv;
}

// Inverted diagonal blocks of the rows [first, last). A component whose diagonal entry is zero up
// to round-off (relative to `scale`) has an empty row and column — a truncated or unused dof, or
// one emptied by incremental coarse updates: it is inert, inverted as identity, and with its
// (zero) right-hand side it stays zero.
template <int d>
Mat<d> diagonal_block_inverse(const BlockMatrix<d>& A, Index i, double thr, std::uint8_t* inert) {
  Mat<d> D = Mat<d>::Zero();
  if (A.diag[i] >= 0) D = A.block(A.diag[i]);
  for (int c = 0; c < d; ++c) {
    inert[c] = D(c, c) <= thr;
    if (inert[c]) { D.row(c).setZero(); D.col(c).setZero(); D(c, c) = 1; }
  }
  return block_inverse<d>(D);
}

template <int d>
void invert_diagonal(const BlockMatrix<d>& A, std::vector<double>& Dinv, std::vector<std::uint8_t>& inert, double scale,
                     Index first = 0, Index last = -1) {
  if (last < 0) last = A.rows;
  Dinv.resize(A.rows * d * d);
  inert.resize(A.rows * d);
  const double thr = 1e-12 * scale;
  for (Index i = first; i < last; ++i) MatMap<d>(Dinv.data() + i * d * d) = diagonal_block_inverse<d>(A, i, thr, inert.data() + i * d);
}

// b_i - sum_{k != i} A_ik x_k
// (the blocks before and after the diagonal one in two loops: no test per block)
template <int d, class V>
inline Vec<d> local_rhs(const BlockMatrix<d>& A, const V* vals, const double* x, const double* b, Index i) {
  Vec<d> s = CVecMap<d>(b + d * i);
  const Index k0 = A.indptr[i], k1 = A.indptr[i + 1], kd = A.diag[i];
  if (kd < 0) {
    accumulate_blocks<d, true>(vals, A.indices.data(), k0, k1, x, s.data());
    return s;
  }
  accumulate_blocks<d, true>(vals, A.indices.data(), k0, kd, x, s.data());
  accumulate_blocks<d, true>(vals, A.indices.data(), kd + 1, k1, x, s.data());
  return s;
}

template <int d>
inline Vec<d> local_rhs(const BlockMatrix<d>& A, const double* x, const double* b, Index i) {
  return local_rhs<d>(A, A.values.data(), x, b, i);
}

// x_i <- x_i + omega (y - x_i), y the exact block solve (omega = 1: y; SolverOptions::omega says why)
template <int d>
inline void relaxed_assign(VecMap<d>& xi, const Vec<d>& y, double omega) {
  if (omega == 1.0) xi = y;
  else xi += omega * (y - Vec<d>(xi));
}

// x <- x + omega (inv s - x) (relaxed_assign of inv * s) on scalars: Eigen's product summed each
// row into a stack slot and read the two back as one 16-byte load -- a store-forwarding stall a
// row, the hottest instruction of the fine sweep's kernel in perf annotate. The same products and
// sums in the same order: the same bits.
template <int d, class M>
inline void relaxed_block_solve(const M& inv, const double* s, double* x, double omega) {
  double y[d];
  for (int a = 0; a < d; ++a) {
    double t = inv(a, 0) * s[0];
    for (int c = 1; c < d; ++c) t += inv(a, c) * s[c];
    y[a] = t;
  }
  if (omega == 1.0)
    for (int a = 0; a < d; ++a) x[a] = y[a];
  else
    for (int a = 0; a < d; ++a) x[a] += omega * (y[a] - x[a]);
}

// A bounded row of the projected sweep: component-wise exact minimization with clamping.
template <int d>
inline void projected_row(const BlockMatrix<d>& A, const std::uint8_t* inert, const double* lo, const double* hi, const Vec<d>& s,
                          double* x, Index i) {
  VecMap<d> xi(x + d * i);
  const auto D = A.block(A.diag[i]);
  for (int c = 0; c < d; ++c) {
    if (inert[d * i + c]) continue;
    double v = s[c];
    for (int a = 0; a < d; ++a)
      if (a != c) v -= D(c, a) * xi[a];
    // max/min rather than std::clamp: rounding may leave lo a hair above hi
    xi[c] = std::max(lo[d * i + c], std::min(v / D(c, c), hi[d * i + c]));
  }
}

template <int d, class V>
__attribute__((noinline)) void projected_row_out_of_line(const BlockMatrix<d>& A, const V* vals, const std::uint8_t* inert,
                                                         const double* lo, const double* hi, const double* b, double* x, Index i) {
  projected_row<d>(A, inert, lo, hi, local_rhs<d>(A, vals, x, b, i), x, i);
}

// The rows [r0, r1) of one colour of a level stored by colours (the coarse sweeps' kernel, as the
// fine sweep's sweep_range): the matrix arrays in registers, x prefetched at the columns of the row
// kPrefetchRows ahead (other colours' ranges), the stored inverse applied on scalars; bounded rows
// (bounded != nullptr: a projected sweep; only near the contact zone) go out of line. The same
// sums and products in the same order as the per-row path: the same bits.
//
// gs_rows is that loop over the rows row(0), ..., row(count - 1), row(q) prefetched where has(q):
// gs_range's rows [r0, r1), and gs_list's list of rows (the owned rows of one colour between two
// ghost exchanges of a distributed coarse sweep, python/contactmg/distributed/cycle.py).
template <int d, class V, class Row, class Has>
void gs_rows(const BlockMatrix<d>& A, const V* values, const double* Dinv, const std::uint8_t* bounded, const std::uint8_t* inert,
             const double* lo, const double* hi, const double* b, double* x, double omega, Index count, Row row, Has has) {
  const ColIndex* cols = A.indices.data();
  const Index* ptr = A.indptr.data();
  const Index* diag = A.diag.data();
  for (Index q = 0; q < count; ++q) {
    const Index i = row(q);
    prefetch_rows_ahead<d>(values, cols, ptr, x, q, row, has);
    if (bounded && bounded[i]) {
      projected_row_out_of_line<d>(A, values, inert, lo, hi, b, x, i);
      continue;
    }
    double s[d];
    for (int a = 0; a < d; ++a) s[a] = b[d * i + a];
    const Index kd = diag[i];
    if (kd < 0) accumulate_blocks<d, true>(values, cols, ptr[i], ptr[i + 1], x, s);
    else {
      accumulate_blocks<d, true>(values, cols, ptr[i], kd, x, s);
      accumulate_blocks<d, true>(values, cols, kd + 1, ptr[i + 1], x, s);
    }
    relaxed_block_solve<d>(CMatMap<d>(Dinv + i * d * d), s, x + d * i, omega);
  }
}

template <int d, class V>
void gs_range(const BlockMatrix<d>& A, const V* values, const double* Dinv, const std::uint8_t* bounded, const std::uint8_t* inert,
              const double* lo, const double* hi, const double* b, double* x, double omega, Index r0, Index r1) {
  // the prefetches run on past r1, into the rows of the next colour
  const Index n = A.rows;
  gs_rows<d>(A, values, Dinv, bounded, inert, lo, hi, b, x, omega, r1 - r0, [r0](Index q) { return r0 + q; },
             [r0, n](Index q) { return r0 + q < n; });
}

// rows[0], ..., rows[count - 1] in that order (backward: the reverse); bounded == nullptr: no bounds.
template <int d>
void gs_list(const BlockMatrix<d>& A, const double* Dinv, const std::uint8_t* bounded, const std::uint8_t* inert, const double* lo,
             const double* hi, const double* b, double* x, double omega, const Index* rows, Index count, bool forward) {
  const auto in_list = [count](Index q) { return q < count; };
  if (forward)
    gs_rows<d>(A, A.values.data(), Dinv, bounded, inert, lo, hi, b, x, omega, count, [rows](Index q) { return rows[q]; }, in_list);
  else
    gs_rows<d>(A, A.values.data(), Dinv, bounded, inert, lo, hi, b, x, omega, count,
               [rows, count](Index q) { return rows[count - 1 - q]; }, in_list);
}

template <int d>
void gs_range(const BlockMatrix<d>& A, const double* Dinv, const std::uint8_t* bounded, const std::uint8_t* inert, const double* lo,
              const double* hi, const double* b, double* x, double omega, Index r0, Index r1) {
  gs_range<d>(A, A.values.data(), Dinv, bounded, inert, lo, hi, b, x, omega, r0, r1);
}

template <int d>
void block_gs_sweep(const BlockMatrix<d>& A, const std::vector<double>& Dinv, const double* b, double* x, bool forward,
                    const SweepOrder& order = SweepOrder(), double omega = 1.0) {
  if (order.contiguous()) {
    order.visit_ranges(forward, [&](Index r0, Index r1) {
      gs_range<d>(A, Dinv.data(), nullptr, nullptr, nullptr, nullptr, b, x, omega, r0, r1);
    });
    return;
  }
  order.visit(A.rows, forward, [&](Index i) {
    VecMap<d> xi(x + d * i);
    relaxed_assign<d>(xi, CMatMap<d>(Dinv.data() + i * d * d) * local_rhs<d>(A, x, b, i), omega);
  });
}

// Projected Gauss-Seidel: nodes without finite bounds get the exact block solve, bounded nodes a
// component-wise exact minimization with clamping (each step lowers the quadratic energy).
template <int d>
void projected_gs_sweep(const BlockMatrix<d>& A, const std::vector<double>& Dinv, const std::vector<std::uint8_t>& bounded,
                        const std::vector<std::uint8_t>& inert, const double* lo, const double* hi, const double* b, double* x, bool forward,
                        const SweepOrder& order = SweepOrder(), double omega = 1.0) {
  if (order.contiguous()) {
    order.visit_ranges(forward, [&](Index r0, Index r1) {
      gs_range<d>(A, Dinv.data(), bounded.data(), inert.data(), lo, hi, b, x, omega, r0, r1);
    });
    return;
  }
  order.visit(A.rows, forward, [&](Index i) {
    const Vec<d> s = local_rhs<d>(A, x, b, i);
    if (!bounded[i]) {
      VecMap<d> xi(x + d * i);
      relaxed_assign<d>(xi, CMatMap<d>(Dinv.data() + i * d * d) * s, omega);
      return;
    }
    projected_row<d>(A, inert.data(), lo, hi, s, x, i);
  });
}

}  // namespace cmg
