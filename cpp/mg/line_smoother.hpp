// Algebraic line Gauss-Seidel: lines of strongly coupled nodes found from a level matrix (as AMG
// line relaxation finds them, from the matrix alone), and an exact block-tridiagonal solve per line.
// Where the matrix shows no anisotropy every line is a single node and the sweep is the point-block
// Gauss-Seidel of level_smoothers.hpp; along a direction of strong coupling (stretched elements:
// the short direction) one line is solved at once, which is what point smoothing cannot do.
//
// Strength of a coupling: the negative trace -tr(A_ij) of the off-diagonal block (classical AMG's
// -a_ij on the displacement components). Its Frobenius norm does not separate the cases: stretched
// Q1 elements couple along the long direction through a mass-like block of positive trace, so the
// norm ratio of the strong to the next coupling tends to 2 for any aspect (2.02 at aspect 8, 2.00 at
// 32), while isotropic structured P1 meshes reach 2.2; by the negative trace stretched Q1 gives 3.9
// (aspect 8) to 4.0, stretched P1 4-16, isotropic Q1 1.0 and the Hertz triangles 2.0 (median; 3.45 at
// the 95th percentile). A node proposes its (at most two) strongest neighbours whose strength is at
// least kLineRatio times that of its third strongest; a link needs both ends to propose it, so every
// node has at most two links and the links form chains (a closed ring is cut once).
#pragma once
#include <algorithm>
#include <array>
#include "mg/level_smoothers.hpp"

namespace cmg {

constexpr double kLineRatio = 3.5;

// The lines of a level: line k holds the nodes nodes[ptr[k] .. ptr[k+1]) in chain order.
struct LineSet {
  std::vector<Index> ptr{0}, nodes;
  Index num_lines() const { return (Index)ptr.size() - 1; }
  Index longest() const {
    Index m = 0;
    for (Index k = 0; k + 1 < (Index)ptr.size(); ++k) m = std::max(m, ptr[k + 1] - ptr[k]);
    return m;
  }
  Index nodes_on_lines() const {  // nodes on lines of two or more nodes
    Index m = 0;
    for (Index k = 0; k + 1 < (Index)ptr.size(); ++k) m += ptr[k + 1] - ptr[k] > 1 ? ptr[k + 1] - ptr[k] : 0;
    return m;
  }
};

template <int d>
double coupling_strength(const CMatMap<d>& B) {
  return std::max(0.0, -B.trace());
}

// Lines of A (square, symmetric pattern). Every row lies on exactly one line. frame(i): the
// orthogonal block Q_i of a node whose dofs A holds in a local frame (contact nodes, x = Q_i x_local),
// or nullptr: the strengths are taken of the canonical blocks Q_i A_ij Q_j^T, since the trace is not
// invariant under a rotation of one side (along a contact boundary the frames would otherwise turn
// the couplings into the body weak and make a false line of the boundary).
template <int d, class Frame>
LineSet find_lines(const BlockMatrix<d>& A, Frame&& frame) {
  const Index n = A.rows;
  std::vector<std::array<Index, 2>> prop(n, {-1, -1});
  for (Index i = 0; i < n; ++i) {
    Index j1 = -1, j2 = -1;
    double s1 = 0, s2 = 0, s3 = 0;
    for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
      const Index j = A.indices[k];
      if (j == i) continue;
      const Mat<d>* Qi = frame(i), *Qj = frame(j);
      double s;
      if (!Qi && !Qj) {
        s = coupling_strength<d>(A.block(k));
      } else {
        Mat<d> B = A.block(k);
        if (Qi) B = *Qi * B;
        if (Qj) B = B * Qj->transpose();
        s = std::max(0.0, -B.trace());
      }
      if (s > s1) { s3 = s2; s2 = s1; j2 = j1; s1 = s; j1 = j; }
      else if (s > s2) { s3 = s2; s2 = s; j2 = j; }
      else if (s > s3) s3 = s;
    }
    if (j1 >= 0 && s1 > 0 && s1 >= kLineRatio * s3) prop[i][0] = j1;
    if (j2 >= 0 && s2 > 0 && s2 >= kLineRatio * s3) prop[i][1] = j2;
  }
  auto proposes = [&](Index i, Index j) { return prop[i][0] == j || prop[i][1] == j; };
  std::vector<std::array<Index, 2>> link(n, {-1, -1});
  for (Index i = 0; i < n; ++i)
    for (Index j : prop[i])
      if (j > i && proposes(j, i)) {
        (link[i][0] < 0 ? link[i][0] : link[i][1]) = j;
        (link[j][0] < 0 ? link[j][0] : link[j][1]) = i;
      }
  LineSet L;
  std::vector<std::uint8_t> done(n, 0);
  auto walk = [&](Index start) {  // from an end of a chain (or any node of a ring) along its links
    Index prev = -1, cur = start;
    while (cur >= 0 && !done[cur]) {
      done[cur] = 1;
      L.nodes.push_back(cur);
      const Index next = link[cur][0] != prev && link[cur][0] >= 0 ? link[cur][0] : (link[cur][1] != prev ? link[cur][1] : -1);
      prev = cur;
      cur = next;
    }
    L.ptr.push_back((Index)L.nodes.size());
  };
  for (Index i = 0; i < n; ++i)  // chains from their ends first, in the order of their lowest end
    if (!done[i] && (link[i][0] < 0 || link[i][1] < 0)) walk(i);
  for (Index i = 0; i < n; ++i)  // what is left are rings
    if (!done[i]) walk(i);
  return L;
}

template <int d>
LineSet find_lines(const BlockMatrix<d>& A) {
  return find_lines<d>(A, [](Index) -> const Mat<d>* { return nullptr; });
}

// Line Gauss-Seidel for the matrix K = M (A + H) M + (I - M) of the active dofs (M = diag(active):
// the truncation mask, or the non-inert dofs of a coarse level; H block-diagonal, the friction
// Hessian of 3D sliding nodes): lines visited in order (backwards for a backward sweep), each
// solved exactly for the current values off the line. Inactive dofs keep x = 0 when b = 0 there.
template <int d>
class LineGaussSeidel {
 public:
  LineGaussSeidel() = default;
  explicit LineGaussSeidel(LineSet lines) : lines_(std::move(lines)) {}

  const LineSet& lines() const { return lines_; }
  // whether any line has two or more nodes (otherwise the point sweep is the same and cheaper)
  bool has_lines() const { return lines_.num_lines() < (Index)lines_.nodes.size(); }
  std::size_t memory_bytes() const {
    return sizeof(Index) * (lines_.ptr.size() + lines_.nodes.size() * 3) + sizeof(double) * (Ginv_.size() + lower_.size());
  }

  // Block LU of every line: G_0 = D_0, G_k = D_k - L_k G_{k-1}^{-1} L_k^T (L_k the block of the
  // node k in column k-1), G^{-1} through the pseudo-inverse where singular (block_inverse).
  void factor(const BlockMatrix<d>& A, const std::uint8_t* active, const std::vector<std::pair<Index, Mat<d>>>& hessian = {}) {
    const Index n = A.rows;
    if ((Index)lines_.nodes.size() != n) throw InputError("line smoother: the lines do not cover the level");
    Ginv_.assign(n * d * d, 0.0);
    lower_.assign(n * d * d, 0.0);
    prev_.assign(n, -1);
    next_.assign(n, -1);
    std::vector<const Mat<d>*> extra(n, nullptr);
    for (const auto& [i, H] : hessian) extra[i] = &H;
    for (Index l = 0; l < lines_.num_lines(); ++l) {
      Mat<d> Gprev_inv = Mat<d>::Zero();
      for (Index q = lines_.ptr[l]; q < lines_.ptr[l + 1]; ++q) {
        const Index i = lines_.nodes[q];
        Mat<d> D = A.diag[i] >= 0 ? Mat<d>(A.block(A.diag[i])) : Mat<d>::Zero();
        if (extra[i]) D += *extra[i];
        mask(D, active, i, i);
        if (q > lines_.ptr[l]) {
          const Index j = lines_.nodes[q - 1];
          prev_[i] = j;
          next_[j] = i;
          const Index pos = A.find(i, j);
          Mat<d> Lk = pos >= 0 ? Mat<d>(A.block(pos)) : Mat<d>::Zero();
          mask(Lk, active, i, j);
          MatMap<d>(lower_.data() + i * d * d) = Lk;
          D -= Lk * Gprev_inv * Lk.transpose();
        }
        for (int c = 0; c < d; ++c)
          if (!is_active(active, i, c)) D(c, c) = 1;
        Gprev_inv = block_inverse<d>(0.5 * (D + D.transpose()));
        MatMap<d>(Ginv_.data() + i * d * d) = Gprev_inv;
      }
    }
    longest_ = lines_.longest();
    factored_ = true;
  }
  bool factored() const { return factored_; }

  void sweep(const BlockMatrix<d>& A, const std::uint8_t* active, const double* b, double* x, bool forward) const {
    const Index nl = lines_.num_lines();
    y_.resize(longest_ * d);
    for (Index ll = 0; ll < nl; ++ll) solve_line(A, active, b, x, forward ? ll : nl - 1 - ll);
  }

 private:
  static bool is_active(const std::uint8_t* active, Index i, int c) { return !active || active[i * d + c]; }
  static void mask(Mat<d>& B, const std::uint8_t* active, Index i, Index j) {
    if (!active) return;
    for (int a = 0; a < d; ++a)
      for (int c = 0; c < d; ++c)
        if (!active[i * d + a] || !active[j * d + c]) B(a, c) = 0;
  }

  void solve_line(const BlockMatrix<d>& A, const std::uint8_t* active, const double* b, double* x, Index l) const {
    const Index q0 = lines_.ptr[l], q1 = lines_.ptr[l + 1];
    // forward elimination: y_k = s_k - L_k G_{k-1}^{-1} y_{k-1}, s_k the right-hand side with the
    // couplings off the line moved over
    for (Index q = q0; q < q1; ++q) {
      const Index i = lines_.nodes[q], ip = prev_[i], in = next_[i];
      Vec<d> s = CVecMap<d>(b + d * i);
      for (Index k = A.indptr[i]; k < A.indptr[i + 1]; ++k) {
        const Index j = A.indices[k];
        if (j != i && j != ip && j != in) s.noalias() -= A.block(k) * CVecMap<d>(x + d * j);
      }
      if (active)
        for (int c = 0; c < d; ++c) s[c] *= active[i * d + c];
      if (q > q0) s.noalias() -= CMatMap<d>(lower_.data() + i * d * d) * (CMatMap<d>(Ginv_.data() + ip * d * d) * VecMap<d>(y_.data() + d * (q - 1 - q0)));
      VecMap<d>(y_.data() + d * (q - q0)) = s;
    }
    // back substitution: x_k = G_k^{-1} (y_k - L_{k+1}^T x_{k+1})
    for (Index q = q1 - 1; q >= q0; --q) {
      const Index i = lines_.nodes[q], in = next_[i];
      Vec<d> y = VecMap<d>(y_.data() + d * (q - q0));
      if (q + 1 < q1) y.noalias() -= CMatMap<d>(lower_.data() + in * d * d).transpose() * CVecMap<d>(x + d * in);
      VecMap<d>(x + d * i) = CMatMap<d>(Ginv_.data() + i * d * d) * y;
    }
  }

  LineSet lines_;
  std::vector<double> Ginv_, lower_;  // per node: G_k^{-1}; the masked block to the previous node of its line
  std::vector<Index> prev_, next_;    // neighbours on the line (-1 at the ends)
  mutable std::vector<double> y_;  // scratch of one line's forward elimination
  Index longest_ = 0;
  bool factored_ = false;
};

}  // namespace cmg
