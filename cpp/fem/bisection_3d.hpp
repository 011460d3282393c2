// Conforming local refinement of tetrahedra by newest-vertex bisection in the marked-tetrahedron
// form of Arnold, Mukherjee and Pouly (SIAM J. Sci. Comput. 22 (2000) 431-448), nested.
//
// State of a tetrahedron (x0, x1, x2, x3): its refinement edge is x0x1, every face has a marked
// edge (the two faces through x0x1 are marked on it), so only two marks are free: m0 of the face
// opposite x0 and m1 of the face opposite x1, stored as the face's vertex off its marked edge (the
// "apex"); and a flag. Types: O (m0 = m1 = x2x3), A (exactly one of them is x2x3), P (m1 = x0c and
// m0 = x1c for one c: all marked edges in one plane), M (otherwise); P is flagged or unflagged.
// Bisection at z = (x0 + x1)/2 gives (x0, z, x2, x3) and (x1, z, x2, x3): inherited faces keep their
// mark, half faces are marked on their old edge (2D newest-vertex bisection of the face, so the
// two tetrahedra of a face always split it alike), the new face z x2 x3 on x2x3 (on z c in a
// flagged P tetrahedron); children of an unflagged P are flagged, other children unflagged; a
// child's refinement edge is the edge marked on two of its faces. In the steady state the types
// cycle M -> Pu -> Pf -> M, which is Maubach's / Kossaczky's tagged bisection: the descendants of
// a tetrahedron fall into finitely many similarity classes (shape regularity), and the closure
// terminates for the initial marking by a strict order of the edges (longest first, ties by node
// numbers), whatever the initial mesh (AMP section 4). Why AMP and not Maubach's tags directly:
// Maubach needs an initial mesh satisfying Stevenson's matching condition, which our generated
// meshes (the 12-tetrahedra split of a hexahedral ball) do not.
//
// One call refines one level of a hierarchy: every marked tetrahedron is bisected `generations`
// times (3 = d: 8 descendants, the mesh size halved there, as a marked triangle of the 2D
// bisection gets its 3 edges split), and the closure bisects every tetrahedron with a node in one
// of its edges until none is left (work list; each bisection re-examines the tetrahedra of its
// edge). New nodes are edge midpoints and come after the input nodes, which keep their numbers;
// the interpolation of a new node is the mean of its two parents' (barycentric coordinates in a
// coarse tetrahedron, so the hierarchy is nested exactly), and its two parents (the bisected
// edge) are returned as well. Boundary facets are split as the faces of the tetrahedra, with
// their tags and orientation; new nodes on them are listed for the boundary projection (the
// smallest tag on a rim, as in uniform refinement). The state of every fine tetrahedron comes
// back (cells in state order, positively oriented, and an 18-valued code) so that the next level
// continues the same bisection tree.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include "fem/refine_2d.hpp"  // RefinedMesh: the same output as uniform refinement

namespace cmg {

// The result of a bisection step: the refined mesh and the state of the fine tetrahedra.
struct Bisected3D {
  RefinedMesh mesh;
  std::vector<Index> marks;         // per fine cell: bisection_mark_code (cells in state order)
  std::vector<Index> edge_parents;  // per new node (n, n+1, ...): the two ends of the edge it bisects
  Index bisections = 0;             // bisections done (marked and closure)
};

namespace amp_detail {

struct Tet {
  Index v[4];
  Index apex0, apex1;  // the face opposite v0 (v1) is marked on its edge that avoids apex0 (apex1)
  bool flag;
  int budget;          // bisections still owed to the marking (closure bisections owe none)
  Index origin[4];     // input boundary facet of the face opposite v[i], -1 if none
};

inline std::uint64_t edge_key(Index a, Index b) {
  return a < b ? (std::uint64_t(a) << 32) | std::uint64_t(b) : (std::uint64_t(b) << 32) | std::uint64_t(a);
}

// The tetrahedron of vertices w (orientation sign `sign` in this order) with refinement edge pq,
// apex fa[i] of the face opposite w[i] and facet origins fo[i], in state order: the refinement
// edge first, positively oriented. (The refinement edge is given: a type O tetrahedron has two
// edges marked on two faces each.)
inline Tet normalized(const Index w[4], const Index fa[4], const Index fo[4], int sign, bool flag, int budget,
                      Index p, Index q) {
  int perm[4], c = 2;
  perm[0] = perm[1] = -1;
  for (int j = 0; j < 4; ++j) {
    if (w[j] == p) perm[0] = j;
    else if (w[j] == q) perm[1] = j;
    else if (c < 4) perm[c++] = j;
  }
  if (perm[0] < 0 || perm[1] < 0 || c != 4) throw std::logic_error("bisection: the refinement edge is not an edge");
  // the two faces through pq must be marked on it
  if (fa[perm[2]] != w[perm[3]] || fa[perm[3]] != w[perm[2]])
    throw std::logic_error("bisection: a face through the refinement edge is marked elsewhere");
  int inversions = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) inversions += perm[a] > perm[b];
  if ((inversions % 2 ? -sign : sign) < 0) std::swap(perm[2], perm[3]);
  Tet t;
  for (int a = 0; a < 4; ++a) {
    t.v[a] = w[perm[a]];
    t.origin[a] = fo[perm[a]];
  }
  t.apex0 = fa[perm[0]];
  t.apex1 = fa[perm[1]];
  t.flag = flag;
  t.budget = budget;
  return t;
}

// the edge of face {w[j] : j != i} that avoids apex
inline std::pair<Index, Index> marked_edge(const Index w[4], int i, Index apex) {
  Index e[2];
  int c = 0;
  for (int j = 0; j < 4; ++j)
    if (j != i && w[j] != apex && c < 2) e[c++] = w[j];
  return {e[0], e[1]};
}

inline Index encode(const Tet& t) {
  const Index a0 = t.apex0 == t.v[1] ? 0 : t.apex0 == t.v[2] ? 1 : 2;
  const Index a1 = t.apex1 == t.v[0] ? 0 : t.apex1 == t.v[2] ? 1 : 2;
  return a0 + 3 * a1 + 9 * Index(t.flag);
}

inline void decode(Index code, Tet& t) {
  const Index a0 = code % 3, a1 = (code / 3) % 3;
  t.apex0 = a0 == 0 ? t.v[1] : t.v[1 + a0];
  t.apex1 = a1 == 0 ? t.v[0] : t.v[1 + a1];
  t.flag = code >= 9;
}

inline std::array<Index, 3> face_key(Index a, Index b, Index c) {
  std::array<Index, 3> k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

struct FaceHash {
  std::size_t operator()(const std::array<Index, 3>& k) const {
    return std::hash<std::uint64_t>()(std::uint64_t(k[0]) * 0x9E3779B97F4A7C15ULL ^ std::uint64_t(k[1]) * 0xC2B2AE3D27D4EB4FULL ^
                                      std::uint64_t(k[2]));
  }
};

inline double signed_volume6(const double* X, const Index v[4]) {
  const double* p = X + 3 * v[0];
  double a[3], b[3], c[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = X[3 * v[1] + i] - p[i];
    b[i] = X[3 * v[2] + i] - p[i];
    c[i] = X[3 * v[3] + i] - p[i];
  }
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

}  // namespace amp_detail

// points: n x 3; cells: m x 4 tetrahedra, positively oriented; facets: nf x 3 with tags; marked: cell
// ids. marks: nullptr for the initial marking of the input mesh (longest edge first), or the codes
// of a previous call (cells then in its state order).
inline Bisected3D bisect_3d(const double* points, Index n, const Index* cells, Index m, const Index* facets,
                            const Index* tags, Index nf, const Index* marked, Index nm, const Index* marks,
                            int generations = 3) {
  using namespace amp_detail;
  constexpr int d = 3;
  if (generations < 1 || generations > 30) throw InputError("generations must lie in 1..30");
  if (n >= (Index(1) << 31)) throw InputError("too many nodes for the bisection's edge keys");

  // input boundary facets by their node triple
  std::unordered_map<std::array<Index, 3>, Index, FaceHash> facet_of;
  facet_of.reserve(2 * nf + 1);
  for (Index f = 0; f < nf; ++f) {
    const Index* v = facets + 3 * f;
    for (int a = 0; a < 3; ++a)
      if (v[a] < 0 || v[a] >= n)
        throw InputError("boundary facet " + std::to_string(f) + " refers to a node out of range");
    auto [it, fresh] = facet_of.emplace(face_key(v[0], v[1], v[2]), f);
    if (!fresh) throw InputError("boundary facet " + std::to_string(f) + " repeats facet " + std::to_string(it->second));
  }
  std::vector<char> facet_used(nf, 0);

  // initial state
  auto longer = [&](Index a, Index b, Index c, Index e) {  // edge ab after edge ce in the strict order?
    if (a > b) std::swap(a, b);
    if (c > e) std::swap(c, e);
    double lab = 0, lce = 0;
    for (int i = 0; i < d; ++i) {
      lab += (points[3 * a + i] - points[3 * b + i]) * (points[3 * a + i] - points[3 * b + i]);
      lce += (points[3 * c + i] - points[3 * e + i]) * (points[3 * c + i] - points[3 * e + i]);
    }
    if (lab != lce) return lab > lce;
    return std::make_pair(a, b) > std::make_pair(c, e);
  };
  std::vector<Tet> tets;
  tets.reserve(m * 4 + 16);
  std::vector<char> on_marked(m, 0);
  for (Index k = 0; k < nm; ++k) {
    if (marked[k] < 0 || marked[k] >= m)
      throw InputError("marked cell " + std::to_string(marked[k]) + " is outside 0.." + std::to_string(m - 1));
    on_marked[marked[k]] = 1;
  }
  for (Index c = 0; c < m; ++c) {
    const Index* v = cells + 4 * c;
    Index w[4] = {v[0], v[1], v[2], v[3]}, fa[4], fo[4];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (w[a] == w[b]) throw InputError("cell " + std::to_string(c) + " repeats node " + std::to_string(w[a]));
    const double vol = signed_volume6(points, w);
    if (!(vol > 0))
      throw InputError("cell " + std::to_string(c) + " (tetra) is " + (vol < 0 ? "inverted" : "degenerate"));
    for (int i = 0; i < 4; ++i) {
      const Index p = w[(i + 1) % 4], q = w[(i + 2) % 4], r = w[(i + 3) % 4];
      auto it = facet_of.find(face_key(p, q, r));
      fo[i] = it == facet_of.end() ? -1 : it->second;
      if (fo[i] >= 0) facet_used[fo[i]] = 1;
    }
    const int budget = on_marked[c] ? generations : 0;
    if (marks == nullptr) {
      for (int i = 0; i < 4; ++i) {  // the face opposite w[i] is marked on its longest edge
        const Index p = w[(i + 1) % 4], q = w[(i + 2) % 4], r = w[(i + 3) % 4];
        // the longest of pq, qr, rp; its apex is the third vertex
        Index apex = r;
        if (longer(q, r, p, q) && longer(q, r, r, p)) apex = p;
        else if (longer(r, p, p, q) && longer(r, p, q, r)) apex = q;
        fa[i] = apex;
      }
      // the refinement edge: the longest of the six
      Index p = w[0], q = w[1];
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
          if (longer(w[a], w[b], p, q)) p = w[a], q = w[b];
      tets.push_back(normalized(w, fa, fo, +1, false, budget, p, q));
    } else {
      const Index code = marks[c];
      if (code < 0 || code >= 18) throw InputError("bisection mark " + std::to_string(code) + " of cell " +
                                                   std::to_string(c) + " is outside 0..17");
      Tet t;
      for (int a = 0; a < 4; ++a) t.v[a] = w[a], t.origin[a] = fo[a];
      decode(code, t);
      t.budget = budget;
      tets.push_back(t);
    }
  }
  for (Index f = 0; f < nf; ++f)
    if (!facet_used[f]) throw InputError("boundary facet " + std::to_string(f) + " is not a face of any cell");
  if (marks != nullptr) {  // the two tetrahedra of a face must mark it alike
    std::unordered_map<std::array<Index, 3>, Index, FaceHash> mark_of;
    mark_of.reserve(4 * m);
    for (Index c = 0; c < m; ++c) {
      const Tet& t = tets[c];
      for (int i = 0; i < 4; ++i) {
        const Index apex = i == 0 ? t.apex0 : i == 1 ? t.apex1 : t.v[i == 2 ? 3 : 2];
        auto [it, fresh] = mark_of.emplace(face_key(t.v[(i + 1) % 4], t.v[(i + 2) % 4], t.v[(i + 3) % 4]), apex);
        if (!fresh && it->second != apex)
          throw InputError("the bisection marks of cell " + std::to_string(c) +
                           " disagree with a neighbour's on their common face (marks from another mesh?)");
      }
    }
  }

  // nodes: the input ones, then midpoints with their interpolation from the input nodes
  Bisected3D out;
  RefinedMesh& R = out.mesh;
  R.dim = d;
  R.points.assign(points, points + n * d);
  std::vector<std::vector<std::pair<Index, double>>> interp;  // of the new nodes
  std::unordered_map<std::uint64_t, Index> midpoint;
  std::vector<std::vector<Index>> tets_of(n);
  std::vector<char> alive(tets.size(), 1);
  for (Index c = 0; c < m; ++c)
    for (int a = 0; a < 4; ++a) tets_of[tets[c].v[a]].push_back(c);
  std::vector<Index> work;
  for (Index c = m - 1; c >= 0; --c)
    if (tets[c].budget > 0) work.push_back(c);

  auto weights_of = [&](Index p) {
    return p < n ? std::vector<std::pair<Index, double>>{{p, 1.0}} : interp[p - n];
  };
  auto add_tet = [&](const Tet& t) {
    const Index id = (Index)tets.size();
    tets.push_back(t);
    alive.push_back(1);
    for (int a = 0; a < 4; ++a) tets_of[t.v[a]].push_back(id);
    work.push_back(id);
  };
  // the midpoint node of edge ab, created (and the tetrahedra of the edge queued) if new
  auto mid = [&](Index a, Index b, Index self) {
    auto [it, fresh] = midpoint.emplace(edge_key(a, b), (Index)(R.points.size() / d));
    if (!fresh) return it->second;
    const Index z = it->second;
    for (int i = 0; i < d; ++i) R.points.push_back(0.5 * (R.points[a * d + i] + R.points[b * d + i]));
    std::vector<std::pair<Index, double>> w;
    for (auto& pw : weights_of(a)) w.push_back({pw.first, 0.5 * pw.second});
    for (auto& pw : weights_of(b)) w.push_back({pw.first, 0.5 * pw.second});
    std::sort(w.begin(), w.end());
    std::vector<std::pair<Index, double>> merged;
    for (auto& pw : w)
      if (!merged.empty() && merged.back().first == pw.first) merged.back().second += pw.second;
      else merged.push_back(pw);
    interp.push_back(std::move(merged));
    out.edge_parents.insert(out.edge_parents.end(), {std::min(a, b), std::max(a, b)});
    tets_of.emplace_back();
    for (Index s : tets_of[a])
      if (s != self && alive[s]) {
        const Tet& u = tets[s];
        if (u.v[0] == b || u.v[1] == b || u.v[2] == b || u.v[3] == b) work.push_back(s);
      }
    return z;
  };
  auto has_hanging_node = [&](const Tet& t) {
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (midpoint.count(edge_key(t.v[a], t.v[b]))) return true;
    return false;
  };

  const Index cap = 64 * m + 100000;
  while (!work.empty()) {
    const Index id = work.back();
    work.pop_back();
    if (!alive[id]) continue;
    if (tets[id].budget <= 0 && !has_hanging_node(tets[id])) continue;
    if (++out.bisections > cap)
      throw std::runtime_error("bisection: the closure exceeded " + std::to_string(cap) + " bisections (a bug)");
    const Tet t = tets[id];
    alive[id] = 0;
    const Index x0 = t.v[0], x1 = t.v[1], x2 = t.v[2], x3 = t.v[3];
    const Index z = mid(x0, x1, id);
    // type: O, A, P (common vertex c) or M
    const bool m0_opp = t.apex0 == x1, m1_opp = t.apex1 == x0;  // marked on x2x3
    bool planar = false;
    Index c = -1;
    if (!m0_opp && !m1_opp) {
      const Index a = t.apex1 == x2 ? x3 : x2;  // m1 = x0 a
      const Index b = t.apex0 == x2 ? x3 : x2;  // m0 = x1 b
      planar = a == b;
      c = a;
    }
    // the new face z x2 x3: marked on x2x3 (apex z), on z c in a flagged planar tetrahedron
    const Index new_apex = planar && t.flag ? (c == x2 ? x3 : x2) : z;
    const bool child_flag = planar && !t.flag;
    const int budget = std::max(t.budget - 1, 0);
    {
      const Index w[4] = {x0, z, x2, x3}, fa[4] = {new_apex, t.apex1, z, z};
      const Index fo[4] = {-1, t.origin[1], t.origin[2], t.origin[3]};
      const auto r = marked_edge(t.v, 1, t.apex1);  // m1
      add_tet(normalized(w, fa, fo, +1, child_flag, budget, r.first, r.second));
    }
    {
      const Index w[4] = {x1, z, x2, x3}, fa[4] = {new_apex, t.apex0, z, z};
      const Index fo[4] = {-1, t.origin[0], t.origin[2], t.origin[3]};
      const auto r = marked_edge(t.v, 0, t.apex0);  // m0
      add_tet(normalized(w, fa, fo, -1, child_flag, budget, r.first, r.second));
    }
  }

  // interpolation
  const Index n_fine = (Index)(R.points.size() / d);
  R.ptr.reserve(n_fine + 1);
  R.ptr.push_back(0);
  for (Index i = 0; i < n; ++i) {
    R.parent.push_back(i);
    R.weight.push_back(1.0);
    R.ptr.push_back((Index)R.parent.size());
  }
  for (auto& w : interp) {
    for (auto& pw : w) {
      R.parent.push_back(pw.first);
      R.weight.push_back(pw.second);
    }
    R.ptr.push_back((Index)R.parent.size());
  }
  // cells, with their state
  for (std::size_t s = 0; s < tets.size(); ++s)
    if (alive[s]) {
      R.cells.insert(R.cells.end(), tets[s].v, tets[s].v + 4);
      out.marks.push_back(encode(tets[s]));
    }
  // boundary facets: the faces of the fine tetrahedra that lie in an input facet, oriented like it
  struct FineFacet {
    Index origin;
    std::array<Index, 3> key, nodes;
  };
  std::vector<FineFacet> ff;
  for (std::size_t s = 0; s < tets.size(); ++s) {
    if (!alive[s]) continue;
    const Tet& t = tets[s];
    for (int i = 0; i < 4; ++i) {
      if (t.origin[i] < 0) continue;
      std::array<Index, 3> f{t.v[(i + 1) % 4], t.v[(i + 2) % 4], t.v[(i + 3) % 4]};
      const Index* g = facets + 3 * t.origin[i];
      double ng[3], nf3[3];
      auto normal = [&](const Index a, const Index b, const Index c, double* nn) {
        double u[3], v[3];
        for (int j = 0; j < 3; ++j) {
          u[j] = R.points[3 * b + j] - R.points[3 * a + j];
          v[j] = R.points[3 * c + j] - R.points[3 * a + j];
        }
        nn[0] = u[1] * v[2] - u[2] * v[1];
        nn[1] = u[2] * v[0] - u[0] * v[2];
        nn[2] = u[0] * v[1] - u[1] * v[0];
      };
      normal(g[0], g[1], g[2], ng);
      normal(f[0], f[1], f[2], nf3);
      if (ng[0] * nf3[0] + ng[1] * nf3[1] + ng[2] * nf3[2] < 0) std::swap(f[1], f[2]);
      ff.push_back({t.origin[i], face_key(f[0], f[1], f[2]), f});
    }
  }
  std::sort(ff.begin(), ff.end(), [](const FineFacet& a, const FineFacet& b) {
    return std::tie(a.origin, a.key) < std::tie(b.origin, b.key);
  });
  std::vector<std::pair<Index, Index>> bnodes;
  for (std::size_t i = 0; i < ff.size(); ++i) {
    if (i > 0 && ff[i].origin == ff[i - 1].origin && ff[i].key == ff[i - 1].key) continue;  // an inner facet, seen twice
    R.facets.insert(R.facets.end(), ff[i].nodes.begin(), ff[i].nodes.end());
    R.facet_tags.push_back(tags[ff[i].origin]);
    for (Index x : ff[i].nodes)
      if (x >= n) bnodes.push_back({x, tags[ff[i].origin]});
  }
  std::sort(bnodes.begin(), bnodes.end());
  for (std::size_t i = 0; i < bnodes.size(); ++i)
    if (i == 0 || bnodes[i].first != bnodes[i - 1].first) {
      R.boundary_nodes.push_back(bnodes[i].first);
      R.boundary_tags.push_back(bnodes[i].second);
    }
  return out;
}

}  // namespace cmg
