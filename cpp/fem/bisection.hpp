// Conforming local refinement of triangles by newest-vertex bisection (NVB), nested.
//
// Convention: a cell (a, b, c) has the refinement edge (a, b) and the newest vertex c. Bisection
// puts m at the midpoint of (a, b) and makes the children (c, a, m) and (b, c, m): each child's
// refinement edge is an edge of the parent and m is its newest vertex, orientation is kept. NVB
// produces at most 4 similarity classes per coarse cell (Sewell; Mitchell), so the angles stay
// bounded below however often a region is refined.
//
// One call refines one level: every edge of a marked cell is bisected (a marked cell gets the
// 4 children of three bisections, "bisec3"), and the closure marks the refinement edge of every
// cell that has a marked edge until no cell has a marked edge other than through its refinement
// edge. Then a cell is split along its marked edges only (2, 3 or 4 children) and every marked edge
// is split in both of its cells: the mesh stays conforming. All new nodes are midpoints of edges of
// the input mesh, so the input nodes keep their numbers and the interpolation is 1/2, 1/2: the
// hierarchy is nested exactly as under uniform refinement.
#pragma once
#include <algorithm>
#include <array>
#include <utility>
#include "fem/refine_2d.hpp"  // RefinedMesh: the same output as uniform refinement

namespace cmg {

namespace nvb_detail {

// Undirected edges of the cells, numbered by sorted 64-bit keys, with the (at most two) cells of each.
class Edges {
 public:
  Edges(Index n, const Index* cells, Index m) : n_(n) {
    keys_.reserve(3 * m);
    for (Index c = 0; c < m; ++c)
      for (int a = 0; a < 3; ++a) keys_.push_back(key(cells[3 * c + a], cells[3 * c + (a + 1) % 3]));
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
    cell_edge_.resize(3 * m);
    cells_of_.assign(2 * keys_.size(), -1);
    for (Index c = 0; c < m; ++c)
      for (int a = 0; a < 3; ++a) {
        const Index e = find(cells[3 * c + a], cells[3 * c + (a + 1) % 3]);
        cell_edge_[3 * c + a] = e;
        if (cells_of_[2 * e] < 0) cells_of_[2 * e] = c;
        else if (cells_of_[2 * e + 1] < 0) cells_of_[2 * e + 1] = c;
        else throw InputError("the edge between nodes " + std::to_string(cells[3 * c + a]) + " and " +
                              std::to_string(cells[3 * c + (a + 1) % 3]) + " belongs to more than two cells");
      }
  }
  Index size() const { return (Index)keys_.size(); }
  // -1 if (a, b) is no edge of a cell
  Index find(Index a, Index b) const {
    const Index k = key(a, b);
    auto it = std::lower_bound(keys_.begin(), keys_.end(), k);
    return (it != keys_.end() && *it == k) ? Index(it - keys_.begin()) : -1;
  }
  std::pair<Index, Index> nodes(Index e) const { return {keys_[e] / n_, keys_[e] % n_}; }
  // edge a of cell c joins its local vertices a and a+1; edge 0 is the refinement edge
  Index of_cell(Index c, int a) const { return cell_edge_[3 * c + a]; }
  Index cell(Index e, int side) const { return cells_of_[2 * e + side]; }

 private:
  Index key(Index a, Index b) const { return a < b ? a * n_ + b : b * n_ + a; }
  Index n_;
  std::vector<Index> keys_, cell_edge_, cells_of_;
};

}  // namespace nvb_detail

// points: n x 2, cells: m x 3 (refinement edge first), facets: nf x 2 with tags, marked: cell ids.
inline RefinedMesh bisect_2d(const double* points, Index n, const Index* cells, Index m, const Index* facets,
                              const Index* tags, Index nf, const Index* marked, Index nm) {
  constexpr int d = 2;
  nvb_detail::Edges edges(n, cells, m);
  const Index ne = edges.size();
  std::vector<char> split(ne, 0);
  std::vector<Index> work;  // cells whose closure condition must be checked again
  auto mark = [&](Index e) {
    if (split[e]) return;
    split[e] = 1;
    for (int s = 0; s < 2; ++s)
      if (edges.cell(e, s) >= 0) work.push_back(edges.cell(e, s));
  };
  for (Index k = 0; k < nm; ++k) {
    const Index c = marked[k];
    if (c < 0 || c >= m)
      throw InputError("marked cell " + std::to_string(c) + " is outside 0.." + std::to_string(m - 1));
    for (int a = 0; a < 3; ++a) mark(edges.of_cell(c, a));
  }
  // closure: a cell with a split edge must split its refinement edge
  while (!work.empty()) {
    const Index c = work.back();
    work.pop_back();
    if (split[edges.of_cell(c, 1)] || split[edges.of_cell(c, 2)]) mark(edges.of_cell(c, 0));
  }

  RefinedMesh R;
  std::vector<Index> mid(ne, -1);
  Index n_fine = n;
  for (Index e = 0; e < ne; ++e)
    if (split[e]) mid[e] = n_fine++;
  R.points.resize(n_fine * d);
  R.ptr.reserve(n_fine + 1);
  R.ptr.push_back(0);
  for (Index i = 0; i < n; ++i) {
    R.parent.push_back(i);
    R.weight.push_back(1.0);
    R.ptr.push_back((Index)R.parent.size());
    for (int j = 0; j < d; ++j) R.points[i * d + j] = points[i * d + j];
  }
  for (Index e = 0; e < ne; ++e) {
    if (!split[e]) continue;
    auto [a, b] = edges.nodes(e);
    R.parent.insert(R.parent.end(), {a, b});
    R.weight.insert(R.weight.end(), {0.5, 0.5});
    R.ptr.push_back((Index)R.parent.size());
    for (int j = 0; j < d; ++j) R.points[mid[e] * d + j] = 0.5 * (points[a * d + j] + points[b * d + j]);
  }

  R.cells.reserve(3 * (m + 3 * nm) + 6 * n_fine);
  auto emit = [&](Index a, Index b, Index c) { R.cells.insert(R.cells.end(), {a, b, c}); };
  for (Index c = 0; c < m; ++c) {
    const Index a = cells[3 * c], b = cells[3 * c + 1], v = cells[3 * c + 2];
    const Index m0 = mid[edges.of_cell(c, 0)], m1 = mid[edges.of_cell(c, 1)], m2 = mid[edges.of_cell(c, 2)];
    if (m0 < 0) {  // the closure guarantees that edges 1 and 2 are not split either
      emit(a, b, v);
      continue;
    }
    // children (v, a, m0) with refinement edge (v, a) = edge 2, and (b, v, m0) with (b, v) = edge 1
    if (m2 < 0) emit(v, a, m0);
    else { emit(m0, v, m2); emit(a, m0, m2); }
    if (m1 < 0) emit(b, v, m0);
    else { emit(m0, b, m1); emit(v, m0, m1); }
  }

  for (Index f = 0; f < nf; ++f) {
    const Index a = facets[2 * f], b = facets[2 * f + 1];
    if (a < 0 || a >= n || b < 0 || b >= n)
      throw InputError("boundary facet " + std::to_string(f) + " refers to a node out of range");
    const Index e = edges.find(a, b);
    if (e < 0) throw InputError("boundary facet " + std::to_string(f) + " is not an edge of any cell");
    if (mid[e] < 0) {
      R.facets.insert(R.facets.end(), {a, b});
      R.facet_tags.push_back(tags[f]);
      continue;
    }
    R.facets.insert(R.facets.end(), {a, mid[e], mid[e], b});
    R.facet_tags.insert(R.facet_tags.end(), {tags[f], tags[f]});
    R.boundary_nodes.push_back(mid[e]);
    R.boundary_tags.push_back(tags[f]);
  }
  return R;
}

}  // namespace cmg
