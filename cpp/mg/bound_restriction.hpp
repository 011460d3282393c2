// Restriction of correction bounds to the next coarser level
// (docs/dev/decisions/0001-monotone-restriction.md).
#pragma once
#include <algorithm>
#include <cmath>
#include "mg/prolongation.hpp"

namespace cmg {

// Monotone restriction of correction bounds lo <= c <= hi (lo <= 0 <= hi) through diag(mask) P:
// any coarse correction within the returned bounds keeps every fine dof within its bounds.
// A fine dof v = sum_k w_k c_k with sum |w_k| <= sigma holds if each w_k c_k stays within
// [lo, hi] / max(1, sigma); a coarse dof takes the tightest of these over all fine dofs it touches.
// Coarse dofs that touch no bounded fine dof keep (-inf, inf).
// The bounds of fine row i (components with mask 0 or no finite bound skipped) into lo_c, hi_c.
template <int d>
inline void restrict_row_bounds(const Prolongation<d>& P, const std::uint8_t* mask, Index i, const double* lo_i, const double* hi_i,
                                double* lo_c, double* hi_c) {
  // entry (c, a) of block k of row i: w I on a plain row (read without forming the block: the
  // coarse levels restrict their slack this way on every visit), R^T w on a rotated one
  const bool rotated = P.rotated(i);
  const auto entry = [&](Index k, int c, int a) { return rotated ? P.block(i, k)(c, a) : (a == c ? P.values[k] : 0.0); };
  for (int c = 0; c < d; ++c) {
    if ((mask && !mask[i * d + c]) || (lo_i[c] == -kInf && hi_i[c] == kInf)) continue;
    double sigma = 0;
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k)
      for (int a = 0; a < d; ++a) sigma += std::abs(entry(k, c, a));
    const double scale = 1.0 / std::max(1.0, sigma);
    const double lo = lo_i[c] * scale, hi = hi_i[c] * scale;
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k)
      for (int a = 0; a < d; ++a) {
        const double w = entry(k, c, a);
        if (w == 0) continue;
        const Index g = P.indices[k] * d + a;
        if (w > 0) { hi_c[g] = std::min(hi_c[g], hi); lo_c[g] = std::max(lo_c[g], lo); }
        else { hi_c[g] = std::min(hi_c[g], -lo); lo_c[g] = std::max(lo_c[g], -hi); }
      }
  }
}

template <int d>
void restrict_bounds(const Prolongation<d>& P, const std::uint8_t* mask, const double* lo_f, const double* hi_f, double* lo_c,
                     double* hi_c) {
  std::fill(lo_c, lo_c + d * P.cols, -kInf);
  std::fill(hi_c, hi_c + d * P.cols, kInf);
  for (Index i = 0; i < P.rows; ++i) restrict_row_bounds<d>(P, mask, i, lo_f + i * d, hi_f + i * d, lo_c, hi_c);
}

// The same for the slack lo - x, hi - x that remains to an iterate x on the fine level, formed per row
// (a scratch pair of fine vectors and a pass less, docs/dev/decisions/0011-memory-release.md; the same
// bits). bounded (per fine row, or nullptr): the rows with a finite bound; the others add nothing and
// are skipped (this serial pass over every fine row of a level ran at each visit of the coarse cycle;
// the bounded rows are the few near the contact zone).
template <int d>
void restrict_slack(const Prolongation<d>& P, const double* lo_f, const double* hi_f, const double* x, double* lo_c, double* hi_c,
                    const std::uint8_t* bounded = nullptr) {
  std::fill(lo_c, lo_c + d * P.cols, -kInf);
  std::fill(hi_c, hi_c + d * P.cols, kInf);
  for (Index i = 0; i < P.rows; ++i) {
    if (bounded && !bounded[i]) continue;
    double lo[d], hi[d];
    for (int c = 0; c < d; ++c) { lo[c] = lo_f[i * d + c] - x[i * d + c]; hi[c] = hi_f[i * d + c] - x[i * d + c]; }
    restrict_row_bounds<d>(P, nullptr, i, lo, hi, lo_c, hi_c);
  }
}

// Fine correction bounds that can be finite only at some nodes (the contact nodes): lo, hi hold d
// entries for each of `nodes` (the fine vectors of bounds were 16 bytes per dof,
// docs/dev/decisions/0011-memory-release.md).
struct NodeBounds {
  const std::vector<Index>* nodes = nullptr;  // nullptr: no bounds
  const double* lo = nullptr;
  const double* hi = nullptr;
};

template <int d>
void restrict_bounds(const Prolongation<d>& P, const std::uint8_t* mask, const NodeBounds& b, double* lo_c, double* hi_c) {
  std::fill(lo_c, lo_c + d * P.cols, -kInf);
  std::fill(hi_c, hi_c + d * P.cols, kInf);
  if (!b.nodes) return;
  const Index m = (Index)b.nodes->size();
  for (Index c = 0; c < m; ++c) restrict_row_bounds<d>(P, mask, (*b.nodes)[c], b.lo + c * d, b.hi + c * d, lo_c, hi_c);
}

}  // namespace cmg
