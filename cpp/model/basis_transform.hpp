// A change of basis x = T x_local applied once to a whole problem: A <- T^T A T, f <- T^T f, the
// fine prolongation P <- T^{-1} P (= T^T P: T is orthogonal here) and the output u <- T u. Today
// T is block-diagonal with the nodal contact frames on the contact nodes and the identity
// elsewhere; the dual mortar basis of two-body contact will be a sparse T of the same role.
#pragma once
#include "base/block_matrix.hpp"

namespace cmg {

template <int d>
class BasisTransform {
 public:
  BasisTransform() = default;
  // Q[c] is the (orthogonal) block of node nodes[c]; every other node keeps the canonical basis.
  BasisTransform(Index n, const std::vector<Index>& nodes, std::vector<Mat<d>> Q) : nodes_(nodes), Q_(std::move(Q)) {
    block_of_node_.assign(n, -1);
    for (std::size_t c = 0; c < nodes_.size(); ++c) block_of_node_[nodes_[c]] = (Index)c;
  }

  Index num_blocks() const { return (Index)Q_.size(); }
  const Mat<d>& block(Index c) const { return Q_[c]; }
  Index node(Index c) const { return nodes_[c]; }
  // the block of node i, or nullptr where the node keeps the canonical basis
  const Mat<d>* block_of(Index i) const {
    return block_of_node_.empty() || block_of_node_[i] < 0 ? nullptr : &Q_[block_of_node_[i]];
  }

  // A <- T^T A T
  void transform_matrix(BlockMatrix<d>& A) const {
    for (Index i = 0; i < A.rows; ++i) {
      const Index ci = block_of_node_[i];
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
        const Index cj = block_of_node_[A.indices[k]];
        if (ci < 0 && cj < 0) continue;
        Mat<d> B = A.block(k);
        if (ci >= 0) B = Q_[ci].transpose() * B;
        if (cj >= 0) B = B * Q_[cj];
        A.block(k) = B;
      }
    }
  }
  // P <- T^{-1} P for a prolongation onto this level (rows are the nodes of T; any type with
  // rotate_row(row, R), mg/prolongation.hpp's)
  template <class Prolongation>
  void transform_prolongation(Prolongation& P) const {
    for (std::size_t c = 0; c < nodes_.size(); ++c) P.rotate_row(nodes_[c], Q_[c].transpose());
  }
  // v <- T^T v (a load; and, T being orthogonal, canonical -> local coordinates)
  void to_local(double* v) const {
    for (std::size_t c = 0; c < nodes_.size(); ++c) {
      VecMap<d> vi(v + nodes_[c] * d);
      vi = Q_[c].transpose() * Vec<d>(vi);
    }
  }
  // u <- T u
  void to_canonical(double* u) const {
    for (std::size_t c = 0; c < nodes_.size(); ++c) {
      VecMap<d> ui(u + nodes_[c] * d);
      ui = Q_[c] * Vec<d>(ui);
    }
  }

 private:
  std::vector<Index> nodes_, block_of_node_;
  std::vector<Mat<d>> Q_;
};

}  // namespace cmg
