// The Galerkin triple product of one level, C = P~^T A P~, symbolic once and numeric per truncation.
#pragma once
#include "mg/transfer.hpp"

namespace cmg {

// The columns of P row by row without its blocks: for coarse node I, the fine rows i with a block
// P_iI and where that block is in P (8 bytes an entry where a transposed copy of P took 36-76).
template <int d>
struct TransposedPattern {
  std::vector<Index> indptr;             // P.cols + 1
  std::vector<ColIndex> indices;         // fine row of each entry, ascending per coarse node
  std::vector<std::int32_t> position;    // its block in P
  explicit TransposedPattern(const Prolongation<d>& P) {
    if (P.nnz() >= (Index)std::numeric_limits<std::int32_t>::max()) throw InputError("a prolongation has too many entries");
    indptr.assign(P.cols + 1, 0);
    for (Index k = 0; k < P.nnz(); ++k) indptr[P.indices[k] + 1]++;
    for (Index I = 0; I < P.cols; ++I) indptr[I + 1] += indptr[I];
    indices.resize(P.nnz());
    position.resize(P.nnz());
    std::vector<Index> fill(indptr.begin(), indptr.end() - 1);
    for (Index i = 0; i < P.rows; ++i)
      for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) {
        const Index q = fill[P.indices[k]]++;
        indices[q] = (ColIndex)i;
        position[q] = (std::int32_t)k;
      }
  }
};

// The block pattern of P^T A P (PT: P's transposed pattern), a diagonal slot in every row; no values.
template <int d>
BlockMatrix<d> galerkin_pattern(const BlockMatrix<d>& A, const Prolongation<d>& P, const TransposedPattern<d>& PT) {
  const Index nc = P.cols;
  BlockMatrix<d> C;
  C.rows = C.cols = nc;
  C.indptr.assign(nc + 1, 0);
  std::vector<Index> marker(nc, -1);
  std::vector<ColIndex> row;
  for (Index I = 0; I < nc; ++I) {
    row.clear();
    for (Index a = PT.indptr[I]; a < PT.indptr[I + 1]; ++a) {
      const Index i = PT.indices[a];
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
        const Index j = A.indices[k];
        for (Index b = P.indptr[j]; b < P.indptr[j + 1]; ++b) {
          const Index J = P.indices[b];
          if (marker[J] != I) { marker[J] = I; row.push_back((ColIndex)J); }
        }
      }
    }
    if (std::find(row.begin(), row.end(), (ColIndex)I) == row.end()) row.push_back((ColIndex)I);  // keep a diagonal slot
    std::sort(row.begin(), row.end());
    C.indices.insert(C.indices.end(), row.begin(), row.end());
    C.indptr[I + 1] = C.indices.size();
  }
  C.find_diagonal();
  return C;
}

// C = P~^T A P~ with P~ = diag(mask) P (mask per fine dof, nullptr = all ones). The pattern of C is
// computed once; later calls with a changed mask only refill the values.
template <int d>
class GalerkinProduct {
 public:
  // P's transposed pattern is formed per call and dropped after: kept, a transposed copy of every
  // prolongation was about 35 bytes per fine dof at level 9 (docs/dev/decisions/0011-memory-release.md);
  // forming it is one pass over P, small beside the product. The blocks are read from P itself.
  void build(const BlockMatrix<d>& A, const Prolongation<d>& P, const std::uint8_t* mask, BlockMatrix<d>& C) {
    const TransposedPattern<d> PT(P);
    if (!symbolic_done_) {
      C = galerkin_pattern<d>(A, P, PT);
      C.values.assign(C.indices.size() * d * d, 0.0);
      symbolic_done_ = true;
    }
    numeric(A, P, PT, mask, C);
  }

 private:
  // Row I of C is formed by one thread from the rows of P^T, in the same order on any thread count
  // (bit for bit); each thread keeps its own column -> position map.
  void numeric(const BlockMatrix<d>& A, const Prolongation<d>& P, const TransposedPattern<d>& PT, const std::uint8_t* mask,
               BlockMatrix<d>& C) {
    const Index nc = P.cols;
    std::fill(C.values.begin(), C.values.end(), 0.0);
    std::vector<std::vector<Index>> pos_of_thread(team_size());
    parallel_for(nc, [&](Index I) {
      std::vector<Index>& pos = pos_of_thread[thread_id()];
      if (pos.empty()) pos.assign(nc, -1);
      Mat<d> Z, Y;
      for (Index k = C.indptr[I]; k < C.indptr[I + 1]; ++k) pos[C.indices[k]] = k;
      for (Index a = PT.indptr[I]; a < PT.indptr[I + 1]; ++a) {
        const Index i = PT.indices[a];
        Z = P.block(i, PT.position[a]).transpose();  // (P_iI)^T
        if (mask)
          for (int c = 0; c < d; ++c) Z.col(c) *= mask[i * d + c];
        if (Z.isZero(0.0)) continue;
        for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
          const Index j = A.indices[k];
          Y.noalias() = Z * A.block(k);
          if (mask)
            for (int c = 0; c < d; ++c) Y.col(c) *= mask[j * d + c];
          for (Index b = P.indptr[j]; b < P.indptr[j + 1]; ++b) C.block(pos[P.indices[b]]).noalias() += Y * P.block(j, b);
        }
      }
    }, 256);
  }

  bool symbolic_done_ = false;
};

}  // namespace cmg
