// Transfer between consecutive levels: prolongation with optional truncation mask, restriction,
// the Galerkin triple product and the monotone restriction of correction bounds.
#pragma once
#include <algorithm>
#include <cmath>
#include "block_matrix.hpp"

namespace cmg {

// Prolongation from interpolation weights (fine node <- coarse nodes); rows of nodes that carry a
// local frame Q (columns n, t, s) are premultiplied by Q^T so that fine dofs live in that frame.
template <int d>
BlockMatrix<d> make_prolongation(Index n_fine, Index n_coarse, const Index* ptr, const Index* parent, const double* weight,
                                 const Index* frame_node = nullptr, const double* frames = nullptr, Index n_frames = 0) {
  BlockMatrix<d> P;
  P.rows = n_fine;
  P.cols = n_coarse;
  check_block_count(n_fine);
  check_block_count(n_coarse);
  P.indptr.assign(ptr, ptr + n_fine + 1);
  P.indices.resize(ptr[n_fine]);
  P.values.assign(ptr[n_fine] * d * d, 0.0);
  for (Index i = 0; i < n_fine; ++i) {
    std::vector<std::pair<Index, double>> row;
    for (Index k = ptr[i]; k < ptr[i + 1]; ++k) {
      if (parent[k] < 0 || parent[k] >= n_coarse) throw InputError("prolongation refers to a coarse node out of range");
      row.emplace_back(parent[k], weight[k]);
    }
    std::sort(row.begin(), row.end());
    for (std::size_t m = 0; m < row.size(); ++m) {
      P.indices[ptr[i] + m] = row[m].first;
      P.block(ptr[i] + m) = row[m].second * Mat<d>::Identity();
    }
  }
  for (Index c = 0; c < n_frames; ++c) {
    const Index i = frame_node[c];
    CMatMap<d> Q(frames + c * d * d);  // row-major d x d, columns are n, t(, s)
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) P.block(k) = Q.transpose() * Mat<d>(P.block(k));
  }
  return P;
}

template <int d>
BlockMatrix<d> transpose(const BlockMatrix<d>& P) {
  BlockMatrix<d> T;
  T.rows = P.cols;
  T.cols = P.rows;
  T.indptr.assign(T.rows + 1, 0);
  for (Index k = 0; k < P.nnz(); ++k) T.indptr[P.indices[k] + 1]++;
  for (Index i = 0; i < T.rows; ++i) T.indptr[i + 1] += T.indptr[i];
  T.indices.resize(P.nnz());
  T.values.resize(P.values.size());
  std::vector<Index> fill(T.indptr.begin(), T.indptr.end() - 1);
  for (Index i = 0; i < P.rows; ++i)
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) {
      Index pos = fill[P.indices[k]]++;
      T.indices[pos] = i;
      T.block(pos) = P.block(k).transpose();
    }
  return T;
}

// C = P~^T A P~ with P~ = diag(mask) P (mask per fine dof, nullptr = all ones). The pattern of C is
// computed once; later calls with a changed mask only refill the values.
template <int d>
class GalerkinProduct {
 public:
  void build(const BlockMatrix<d>& A, const BlockMatrix<d>& P, const std::uint8_t* mask, BlockMatrix<d>& C) {
    if (PT_.rows != P.cols || PT_.cols != P.rows) {
      PT_ = transpose(P);
      symbolic(A, P, C);
    }
    numeric(A, P, mask, C);
  }

 private:
  void symbolic(const BlockMatrix<d>& A, const BlockMatrix<d>& P, BlockMatrix<d>& C) {
    const Index nc = P.cols;
    C.rows = C.cols = nc;
    C.indptr.assign(nc + 1, 0);
    C.indices.clear();
    std::vector<Index> marker(nc, -1);
    std::vector<Index> row;
    for (Index I = 0; I < nc; ++I) {
      row.clear();
      for (Index a = PT_.indptr[I]; a < PT_.indptr[I + 1]; ++a) {
        const Index i = PT_.indices[a];
        for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
          const Index j = A.indices[k];
          for (Index b = P.indptr[j]; b < P.indptr[j + 1]; ++b) {
            const Index J = P.indices[b];
            if (marker[J] != I) { marker[J] = I; row.push_back(J); }
          }
        }
      }
      if (std::find(row.begin(), row.end(), I) == row.end()) row.push_back(I);  // keep a diagonal slot
      std::sort(row.begin(), row.end());
      C.indices.insert(C.indices.end(), row.begin(), row.end());
      C.indptr[I + 1] = C.indices.size();
    }
    C.values.assign(C.indices.size() * d * d, 0.0);
    C.find_diagonal();
  }

  void numeric(const BlockMatrix<d>& A, const BlockMatrix<d>& P, const std::uint8_t* mask, BlockMatrix<d>& C) {
    const Index nc = P.cols;
    std::fill(C.values.begin(), C.values.end(), 0.0);
    std::vector<Index> pos(nc, -1);
    Mat<d> Z, Y;
    for (Index I = 0; I < nc; ++I) {
      for (Index k = C.indptr[I]; k < C.indptr[I + 1]; ++k) pos[C.indices[k]] = k;
      for (Index a = PT_.indptr[I]; a < PT_.indptr[I + 1]; ++a) {
        const Index i = PT_.indices[a];
        Z = PT_.block(a);  // (P_iI)^T
        if (mask)
          for (int c = 0; c < d; ++c) Z.col(c) *= mask[i * d + c];
        if (Z.isZero(0.0)) continue;
        for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
          const Index j = A.indices[k];
          Y.noalias() = Z * A.block(k);
          if (mask)
            for (int c = 0; c < d; ++c) Y.col(c) *= mask[j * d + c];
          for (Index b = P.indptr[j]; b < P.indptr[j + 1]; ++b) C.block(pos[P.indices[b]]).noalias() += Y * P.block(b);
        }
      }
    }
  }

  BlockMatrix<d> PT_;
};

// x_fine += diag(mask) P x_coarse
template <int d>
void prolongate_add(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* xc, double* xf) {
  for (Index i = 0; i < P.rows; ++i) {
    Vec<d> s = Vec<d>::Zero();
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) s.noalias() += P.block(k) * CVecMap<d>(xc + d * P.indices[k]);
    if (mask)
      for (int c = 0; c < d; ++c) s[c] *= mask[i * d + c];
    VecMap<d>(xf + d * i) += s;
  }
}

// y_coarse = P^T diag(mask) r_fine
template <int d>
void restrict_residual(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* rf, double* yc) {
  std::fill(yc, yc + d * P.cols, 0.0);
  for (Index i = 0; i < P.rows; ++i) {
    Vec<d> r = CVecMap<d>(rf + d * i);
    if (mask)
      for (int c = 0; c < d; ++c) r[c] *= mask[i * d + c];
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) VecMap<d>(yc + d * P.indices[k]).noalias() += P.block(k).transpose() * r;
  }
}

// Monotone restriction of correction bounds lo <= c <= hi (lo <= 0 <= hi) through diag(mask) P:
// any coarse correction within the returned bounds keeps every fine dof within its bounds.
// A fine dof v = sum_k w_k c_k with sum |w_k| <= sigma holds if each w_k c_k stays within
// [lo, hi] / max(1, sigma); a coarse dof takes the tightest of these over all fine dofs it touches.
// Coarse dofs that touch no bounded fine dof keep (-inf, inf).
template <int d>
void restrict_bounds(const BlockMatrix<d>& P, const std::uint8_t* mask, const double* lo_f, const double* hi_f, double* lo_c,
                     double* hi_c) {
  std::fill(lo_c, lo_c + d * P.cols, -kInf);
  std::fill(hi_c, hi_c + d * P.cols, kInf);
  for (Index i = 0; i < P.rows; ++i)
    for (int c = 0; c < d; ++c) {
      const Index f = i * d + c;
      if ((mask && !mask[f]) || (lo_f[f] == -kInf && hi_f[f] == kInf)) continue;
      double sigma = 0;
      for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k)
        for (int a = 0; a < d; ++a) sigma += std::abs(P.block(k)(c, a));
      const double scale = 1.0 / std::max(1.0, sigma);
      const double lo = lo_f[f] * scale, hi = hi_f[f] * scale;
      for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k)
        for (int a = 0; a < d; ++a) {
          const double w = P.block(k)(c, a);
          if (w == 0) continue;
          const Index g = P.indices[k] * d + a;
          if (w > 0) { hi_c[g] = std::min(hi_c[g], hi); lo_c[g] = std::max(lo_c[g], lo); }
          else { hi_c[g] = std::min(hi_c[g], -lo); lo_c[g] = std::max(lo_c[g], -hi); }
        }
    }
}

}  // namespace cmg
