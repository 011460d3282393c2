// Uniform refinement: red refinement of triangles, 4-split of quadrilaterals. Returns the fine mesh,
// the nodal-interpolation weights (fine node <- coarse nodes) and the new nodes on boundary facets
// so that the caller can project them onto a curved boundary.
#pragma once
#include <algorithm>
#include "fem/element.hpp"

namespace cmg {

struct RefinedMesh {
  int dim = 0;
  std::vector<double> points;
  std::vector<Index> cells, facets, facet_tags;
  // interpolation: fine node i = sum_k weight[k] * coarse node parent[k], k in [ptr[i], ptr[i+1])
  std::vector<Index> ptr, parent;
  std::vector<double> weight;
  std::vector<Index> boundary_nodes, boundary_tags;  // new nodes on boundary facets, with their facet's tag
};

// Unique undirected edges of a list of node pairs, found by sorting 64-bit keys.
class EdgeTable {
 public:
  explicit EdgeTable(Index n) : n_(n) {}
  void add(Index a, Index b) { keys_.push_back(key(a, b)); }
  void finish() {
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
  }
  Index size() const { return (Index)keys_.size(); }
  Index id(Index a, Index b) const {
    auto it = std::lower_bound(keys_.begin(), keys_.end(), key(a, b));
    return Index(it - keys_.begin());
  }
  std::pair<Index, Index> nodes(Index e) const { return {keys_[e] / n_, keys_[e] % n_}; }

 private:
  Index key(Index a, Index b) const { return a < b ? a * n_ + b : b * n_ + a; }
  Index n_;
  std::vector<Index> keys_;
};

inline RefinedMesh refine_2d(CellType type, const double* points, Index n, const Index* cells, Index m,
                             const Index* facets, const Index* tags, Index nf) {
  constexpr int d = 2;
  if (type != CellType::Triangle && type != CellType::Quad)
    throw InputError(std::string("uniform refinement of ") + cell_name(type) + " cells in 2D is not supported");
  const int k = type == CellType::Triangle ? 3 : 4;
  EdgeTable edges(n);
  for (Index c = 0; c < m; ++c)
    for (int a = 0; a < k; ++a) edges.add(cells[c * k + a], cells[c * k + (a + 1) % k]);
  edges.finish();
  const Index ne = edges.size();
  const Index n_fine = n + ne + (type == CellType::Quad ? m : 0);

  RefinedMesh R;
  R.dim = d;
  R.points.resize(n_fine * d);
  R.ptr.reserve(n_fine + 1);
  R.ptr.push_back(0);
  auto add_parent = [&](Index p, double w) { R.parent.push_back(p); R.weight.push_back(w); };
  for (Index i = 0; i < n; ++i) {
    add_parent(i, 1.0);
    R.ptr.push_back(R.parent.size());
    for (int j = 0; j < d; ++j) R.points[i * d + j] = points[i * d + j];
  }
  for (Index e = 0; e < ne; ++e) {
    auto [a, b] = edges.nodes(e);
    add_parent(a, 0.5); add_parent(b, 0.5);
    R.ptr.push_back(R.parent.size());
    for (int j = 0; j < d; ++j) R.points[(n + e) * d + j] = 0.5 * (points[a * d + j] + points[b * d + j]);
  }
  if (type == CellType::Quad) {
    for (Index c = 0; c < m; ++c) {
      const Index ctr = n + ne + c;
      for (int a = 0; a < 4; ++a) add_parent(cells[c * 4 + a], 0.25);
      R.ptr.push_back(R.parent.size());
      for (int j = 0; j < d; ++j) {
        double s = 0;
        for (int a = 0; a < 4; ++a) s += points[cells[c * 4 + a] * d + j];
        R.points[ctr * d + j] = 0.25 * s;
      }
    }
  }
  auto mid = [&](Index a, Index b) { return n + edges.id(a, b); };
  if (type == CellType::Triangle) {
    R.cells.reserve(m * 12);
    for (Index c = 0; c < m; ++c) {
      const Index* v = cells + c * 3;
      const Index m01 = mid(v[0], v[1]), m12 = mid(v[1], v[2]), m20 = mid(v[2], v[0]);
      const Index child[4][3] = {{v[0], m01, m20}, {m01, v[1], m12}, {m20, m12, v[2]}, {m01, m12, m20}};
      for (auto& t : child) R.cells.insert(R.cells.end(), t, t + 3);
    }
  } else {
    R.cells.reserve(m * 16);
    for (Index c = 0; c < m; ++c) {
      const Index* v = cells + c * 4;
      const Index ctr = n + ne + c;
      const Index m01 = mid(v[0], v[1]), m12 = mid(v[1], v[2]), m23 = mid(v[2], v[3]), m30 = mid(v[3], v[0]);
      const Index child[4][4] = {{v[0], m01, ctr, m30}, {m01, v[1], m12, ctr}, {ctr, m12, v[2], m23}, {m30, ctr, m23, v[3]}};
      for (auto& q : child) R.cells.insert(R.cells.end(), q, q + 4);
    }
  }
  for (Index f = 0; f < nf; ++f) {
    const Index a = facets[2 * f], b = facets[2 * f + 1];
    const Index e = edges.id(a, b);
    if (e >= ne || edges.nodes(e) != std::make_pair(std::min(a, b), std::max(a, b)))
      throw InputError("boundary facet " + std::to_string(f) + " is not an edge of any cell");
    const Index mm = n + e;
    R.facets.insert(R.facets.end(), {a, mm, mm, b});
    R.facet_tags.insert(R.facet_tags.end(), {tags[f], tags[f]});
    R.boundary_nodes.push_back(mm);
    R.boundary_tags.push_back(tags[f]);
  }
  return R;
}

}  // namespace cmg
