// The prolongation between two consecutive levels as scalar weights: nodal interpolation moves every
// component of a coarse node alike, so a block of P is w I -- or R_i^T w on a fine row i whose node
// carries a contact frame R_i (P <- T^T P, model/basis_transform.hpp). d x d blocks of doubles were 4
// (2D) to 9 (3D) times the bytes for the same information: 47 bytes a dof at level 9 in 2D
// (docs/dev/decisions/0011-memory-release.md), now 14; and the transfers stream a quarter of the bytes.
#pragma once
#include <algorithm>
#include "base/block_matrix.hpp"

namespace cmg {

template <int d>
struct Prolongation {
  static constexpr int bs = 1;       // values per entry (the renumbering moves entries by it)
  Index rows = 0, cols = 0;          // fine and coarse nodes
  std::vector<Index> indptr;         // rows + 1
  std::vector<ColIndex> indices;     // coarse node of each entry, sorted per row
  std::vector<double> values;        // the weight of each entry
  // Rows whose blocks are R^T w (the fine contact nodes): the rotation's index per row, or -1;
  // empty where no row is rotated (every coarse level).
  std::vector<std::int32_t> rotation_of_row;
  std::vector<Mat<d>> rotation;      // R^T

  Index nnz() const { return (Index)indices.size(); }
  bool rotated(Index i) const { return !rotation_of_row.empty() && rotation_of_row[i] >= 0; }
  const Mat<d>& rotation_of(Index i) const { return rotation[rotation_of_row[i]]; }

  // The block of entry k on row i, as the d x d blocks held it: R^T (w I) on a rotated row (the
  // same bits as the product formed once before), w I elsewhere.
  Mat<d> block(Index i, Index k) const {
    if (rotated(i)) return rotation_of(i) * (values[k] * Mat<d>::Identity());
    return values[k] * Mat<d>::Identity();
  }

  // Row i's blocks become R^T (old block): a contact frame on fine node i.
  void rotate_row(Index i, const Mat<d>& Rt) {
    if (rotation_of_row.empty()) rotation_of_row.assign(rows, -1);
    rotation_of_row[i] = (std::int32_t)rotation.size();
    rotation.push_back(Rt);
  }

  std::size_t memory_bytes() const {
    return sizeof(Index) * indptr.size() + sizeof(ColIndex) * indices.size() + sizeof(double) * values.size() +
           sizeof(std::int32_t) * rotation_of_row.size() + sizeof(Mat<d>) * rotation.size();
  }
};

// Prolongation from interpolation weights (fine node <- coarse nodes), canonical basis on both
// levels (a basis transform of the fine level is applied afterwards, model/basis_transform.hpp).
template <int d>
Prolongation<d> make_prolongation(Index n_fine, Index n_coarse, const Index* ptr, const Index* parent, const double* weight) {
  Prolongation<d> P;
  P.rows = n_fine;
  P.cols = n_coarse;
  check_block_count(n_fine);
  check_block_count(n_coarse);
  P.indptr.assign(ptr, ptr + n_fine + 1);
  P.indices.resize(ptr[n_fine]);
  P.values.assign(ptr[n_fine], 0.0);
  std::vector<std::pair<Index, double>> row;
  for (Index i = 0; i < n_fine; ++i) {
    row.clear();
    for (Index k = ptr[i]; k < ptr[i + 1]; ++k) {
      if (parent[k] < 0 || parent[k] >= n_coarse) throw InputError("prolongation refers to a coarse node out of range");
      row.emplace_back(parent[k], weight[k]);
    }
    std::sort(row.begin(), row.end());
    for (std::size_t m = 0; m < row.size(); ++m) {
      P.indices[ptr[i] + m] = (ColIndex)row[m].first;
      P.values[ptr[i] + m] = row[m].second;
    }
  }
  return P;
}

}  // namespace cmg
