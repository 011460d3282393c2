// The storage order of the nodes of one level: a permutation applied once at setup (matrix, vectors,
// prolongations), undone on the way out, so that the user's numbering is all the caller sees. By colours
// (docs/dev/decisions/0003-coloured-gauss-seidel.md): the rows of one colour of the greedy colouring
// (sweep_order.hpp) become one contiguous range, in the level's locality order within a colour (below),
// so a coloured sweep streams the matrix and the iterate like a lexicographic one instead of gathering
// the rows of a colour from all over memory, and the neighbours it gathers are near in every colour's
// range. The colouring of the renumbered level is the colouring of the original one (greedy in
// colour-major order gives every row its colour again), so the method is unchanged; only round-off
// differs (sums run in another column order).
#pragma once
#include "base/block_matrix.hpp"
#include "mg/sweep_order.hpp"

namespace cmg {

// The locality order of a level (docs/dev/decisions/0015-locality-order.md). The user's numbering of a
// refined mesh is not local: every refinement appends its new nodes, so a row's neighbours lay all over
// the vector (19 MB at level 9 in 2D against 2 MB of L2) and every gather of a sweep, product or
// transfer missed the cache. Reverse Cuthill-McKee is a wavefront through the mesh: a row's neighbours
// lie within about one wavefront (~sqrt(n) nodes) of it, and so, within each colour's range sorted in
// that order, at about the same relative position as the row in its own range. It needs only the block
// graph (the core has no coordinates). Each component starts at a pseudo-peripheral node (George-Liu),
// so two bodies get a wavefront each.
template <int d>
std::vector<Index> reverse_cuthill_mckee(const BlockMatrix<d>& A) {
  const Index n = A.rows;
  std::vector<Index> order, level;
  order.reserve(n);
  std::vector<Index> mark(n, -1);  // the BFS that last reached a node (visited: -2)
  const auto degree = [&](Index i) { return A.indptr[i + 1] - A.indptr[i]; };
  Index run = 0;
  // the last level of a BFS from s over its component (nodes not yet placed), and its depth
  const auto last_level = [&](Index s, std::vector<Index>& last) {
    ++run;
    level.assign(1, s);
    mark[s] = run;
    Index depth = 0;
    while (true) {
      std::vector<Index> next;
      for (Index i : level)
        for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
          const Index j = A.indices[k];
          if (mark[j] != -2 && mark[j] != run) { mark[j] = run; next.push_back(j); }
        }
      if (next.empty()) break;
      level.swap(next);
      ++depth;
    }
    last = level;
    return depth;
  };
  std::vector<Index> last, nb;
  for (Index s0 = 0; s0 < n; ++s0) {
    if (mark[s0] == -2) continue;
    Index start = s0, depth = last_level(start, last);
    for (int it = 0; it < 8; ++it) {  // George-Liu: move to a far node of least degree while the depth grows
      Index x = last[0];
      for (Index j : last)
        if (degree(j) < degree(x) || (degree(j) == degree(x) && j < x)) x = j;
      std::vector<Index> lx;
      const Index dx = last_level(x, lx);
      if (dx <= depth) break;
      start = x, depth = dx, last.swap(lx);
    }
    const std::size_t first = order.size();
    order.push_back(start);
    mark[start] = -2;
    for (std::size_t q = first; q < order.size(); ++q) {
      const Index i = order[q];
      nb.clear();
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k)
        if (mark[A.indices[k]] != -2) { nb.push_back(A.indices[k]); mark[A.indices[k]] = -2; }
      std::sort(nb.begin(), nb.end(), [&](Index a, Index b) { return degree(a) != degree(b) ? degree(a) < degree(b) : a < b; });
      order.insert(order.end(), nb.begin(), nb.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

// The locality order of a coarse level from the finer one's: coarse node j where its heaviest
// child lies in the finer level's locality order (rank: position of each row of P there; ties: the
// first such row). On nested meshes that child is the coarse node itself, so both levels run
// through the mesh in the same wavefront, and the transfers between them stream too.
template <class M>
std::vector<Index> induced_locality_order(const M& P, const std::vector<Index>& rank) {
  std::vector<Index> key(P.cols, std::numeric_limits<Index>::max());
  std::vector<double> best(P.cols, -std::numeric_limits<double>::infinity());
  for (Index i = 0; i < P.rows; ++i)
    for (Index k = P.indptr[i]; k < P.indptr[i + 1]; ++k) {
      const Index j = P.indices[k];
      if (P.values[k] > best[j] || (P.values[k] == best[j] && rank[i] < key[j])) { best[j] = P.values[k]; key[j] = rank[i]; }
    }
  std::vector<Index> order(P.cols);
  for (Index j = 0; j < P.cols; ++j) order[j] = j;
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return key[a] < key[b]; });
  return order;
}

// rank[order[q]] = q
inline std::vector<Index> rank_of(const std::vector<Index>& order) {
  std::vector<Index> rank(order.size());
  for (std::size_t q = 0; q < order.size(); ++q) rank[order[q]] = (Index)q;
  return rank;
}

class Renumbering {
 public:
  Renumbering() = default;  // the identity
  // old_of_new[k]: the user's number of stored node k. Only this direction is kept (4 bytes a node).
  explicit Renumbering(const std::vector<Index>& old_of_new) : old_of_new_(old_of_new.begin(), old_of_new.end()) {}
  // The colour-major order of the greedy colouring of A's block graph (visiting the rows in the
  // user's order: the colouring, and so the method, is the one it always was; hashed: in the
  // hashed order of the user's numbers, the distributed solver's colours), each colour's rows in
  // the locality order `local` (a permutation; the user's order when empty).
  template <int d>
  static Renumbering by_colours(const BlockMatrix<d>& A, const std::vector<Index>& local = {}, bool hashed = false) {
    std::vector<Index> rows(A.rows);
    for (Index i = 0; i < A.rows; ++i) rows[i] = i;
    const SweepOrder S = (hashed ? SweepOrder().hashed_visit(A.rows, [](Index i) { return i; }) : SweepOrder(rows)).template coloured_by<d>(A);
    if (!S.contiguous()) rows = S.rows();  // else the colour-major order is the identity
    if (!local.empty()) {
      const std::vector<Index> rank = rank_of(local);
      const std::vector<Index>& ptr = S.colour_ptr();
      for (std::size_t c = 0; c + 1 < ptr.size(); ++c)
        std::sort(rows.begin() + ptr[c], rows.begin() + ptr[c + 1], [&](Index a, Index b) { return rank[a] < rank[b]; });
    }
    return Renumbering(rows);
  }
  // The user's number of every stored node (the identity: empty)
  const std::vector<ColIndex>& old_of_new() const { return old_of_new_; }

  bool identity() const { return old_of_new_.empty(); }
  Index to_user(Index stored) const { return identity() ? stored : old_of_new_[stored]; }
  // new_of_old[i]: where the user's node i is stored (formed on demand: setup and diagnostics).
  std::vector<Index> new_of_old() const {
    std::vector<Index> v(old_of_new_.size());
    for (std::size_t k = 0; k < old_of_new_.size(); ++k) v[old_of_new_[k]] = (Index)k;
    return v;
  }
  // The renumbering that takes stored numbers back to the user's.
  Renumbering inverse() const { return identity() ? Renumbering() : Renumbering(new_of_old()); }
  std::size_t memory_bytes() const { return sizeof(ColIndex) * old_of_new_.size(); }

  // Node-wise arrays of `width` entries per node: stored[new] = user[old], and back.
  template <class T>
  std::vector<T> to_storage(const T* user, Index n, int width) const {
    std::vector<T> s(user, user + n * width);
    if (!identity())
      for (Index k = 0; k < n; ++k) std::copy(user + old_of_new_[k] * width, user + (old_of_new_[k] + 1) * width, s.data() + k * width);
    return s;
  }
  // user[old] = stored[new]: a copy in the user's numbering
  template <class T>
  std::vector<T> to_storage_inverse(const T* stored, Index n, int width) const {
    std::vector<T> u(stored, stored + (identity() ? n * width : 0));
    if (identity()) return u;
    u.resize(n * width);
    for (Index k = 0; k < n; ++k) std::copy(stored + k * width, stored + (k + 1) * width, u.data() + old_of_new_[k] * width);
    return u;
  }
  template <class T>
  void to_user_in_place(std::vector<T>& v, int width) const {
    if (identity()) return;
    std::vector<T> u(v.size());
    const Index n = (Index)old_of_new_.size();
    for (Index k = 0; k < n; ++k) std::copy(v.data() + k * width, v.data() + (k + 1) * width, u.data() + old_of_new_[k] * width);
    v.swap(u);
  }

  // A <- Q A Q^T (rows and columns renumbered, columns sorted again per row), in place: the
  // blocks move along the cycles of the permutation, so the fine matrix is never held twice (a
  // copy was 134 bytes per dof at level 9); the new pattern and the block destinations (4 bytes
  // a block each) are all that is allocated.
  template <int d>
  void permute_matrix(BlockMatrix<d>& A) const {
    if (identity()) return;
    if (A.nnz() < (Index)std::numeric_limits<std::int32_t>::max()) permute_matrix_in_place<d, std::int32_t>(A);
    else permute_matrix_in_place<d, Index>(A);
  }

  // The rows of A (a prolongation onto this level: its fine rows) in storage order.
  template <class M>
  void permute_rows(M& A) const {
    if (identity()) return;
    constexpr int bs = M::bs;
    M B;
    B.rows = A.rows;
    B.cols = A.cols;
    B.indptr.assign(A.rows + 1, 0);
    for (Index k = 0; k < A.rows; ++k) B.indptr[k + 1] = B.indptr[k] + (A.indptr[old_of_new_[k] + 1] - A.indptr[old_of_new_[k]]);
    B.indices.resize(A.indices.size());
    B.values.resize(A.values.size());
    for (Index k = 0; k < A.rows; ++k) {
      const Index i = old_of_new_[k], b = A.indptr[i], e = A.indptr[i + 1];
      std::copy(A.indices.begin() + b, A.indices.begin() + e, B.indices.begin() + B.indptr[k]);
      if (!A.values.empty()) std::copy(A.values.begin() + b * bs, A.values.begin() + e * bs, B.values.begin() + B.indptr[k] * bs);
    }
    A = std::move(B);
  }
  // The columns of A (a prolongation from this level: its coarse columns) in storage order.
  template <class M>
  void permute_columns(M& A) const {
    if (!identity()) permute_columns(A, new_of_old());
  }
  template <class M>
  static void permute_columns(M& A, const std::vector<Index>& new_of_old_) {
    constexpr int bs = M::bs;
    std::vector<std::pair<ColIndex, Index>> row;
    std::vector<double> vals;
    for (Index i = 0; i < A.rows; ++i) {
      const Index b = A.indptr[i], e = A.indptr[i + 1];
      row.clear();
      for (Index k = b; k < e; ++k) row.emplace_back((ColIndex)new_of_old_[A.indices[k]], k);
      std::sort(row.begin(), row.end());
      if (!A.values.empty()) vals.assign(A.values.begin() + b * bs, A.values.begin() + e * bs);
      for (Index m = 0; m < e - b; ++m) {
        A.indices[b + m] = row[m].first;
        if (!A.values.empty())
          std::copy(vals.begin() + (row[m].second - b) * bs, vals.begin() + (row[m].second - b + 1) * bs, A.values.begin() + (b + m) * bs);
      }
    }
  }

 private:
  template <int d, class Pos>
  void permute_matrix_in_place(BlockMatrix<d>& A) const {
    constexpr int bs = BlockMatrix<d>::bs;
    const Index n = A.rows, nnz = A.nnz();
    const std::vector<Index> where = new_of_old();
    std::vector<Index> indptr(n + 1, 0);
    for (Index k = 0; k < n; ++k) indptr[k + 1] = indptr[k] + (A.indptr[old_of_new_[k] + 1] - A.indptr[old_of_new_[k]]);
    std::vector<ColIndex> indices(nnz);
    std::vector<Pos> dest(nnz);  // new position of the block at old position m
    std::vector<std::pair<ColIndex, Index>> row;
    for (Index k = 0; k < n; ++k) {
      const Index i = old_of_new_[k];
      row.clear();
      for (Index m = A.indptr[i]; m < A.indptr[i + 1]; ++m) row.emplace_back((ColIndex)where[A.indices[m]], m);
      std::sort(row.begin(), row.end());
      for (std::size_t q = 0; q < row.size(); ++q) {
        indices[indptr[k] + q] = row[q].first;
        dest[row[q].second] = (Pos)(indptr[k] + q);
      }
    }
    A.indptr.swap(indptr);
    std::vector<Index>().swap(indptr);
    A.indices.swap(indices);
    std::vector<ColIndex>().swap(indices);
    if (!A.values.empty()) {
      double tmp[bs], next[bs];
      for (Index s = 0; s < nnz; ++s) {
        if (dest[s] < 0) continue;
        std::copy(A.values.data() + s * bs, A.values.data() + (s + 1) * bs, tmp);
        Index cur = s;
        while (true) {
          const Index t = dest[cur];
          dest[cur] = -1;
          if (t == s) { std::copy(tmp, tmp + bs, A.values.data() + s * bs); break; }
          std::copy(A.values.data() + t * bs, A.values.data() + (t + 1) * bs, next);
          std::copy(tmp, tmp + bs, A.values.data() + t * bs);
          std::copy(next, next + bs, tmp);
          cur = t;
        }
      }
    }
    A.find_diagonal();
  }

  std::vector<ColIndex> old_of_new_;  // empty: the identity
};

}  // namespace cmg
