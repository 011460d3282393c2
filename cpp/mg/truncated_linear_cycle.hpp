// The truncated linear multigrid cycle on the fine level, the linear correction of a TNNMG step:
// for the truncated Newton system
//   K w = M r,   K = M (A + H) M + (I - M)     (M = diag(mask): 0 on frozen and Dirichlet dofs,
//                                               H the friction Hessian blocks of 3D sliding nodes)
// one cycle from w = 0: nu1 forward Gauss-Seidel sweeps of K (line sweeps where the fine matrix has
// lines, mg/line_smoother.hpp; point-block sweeps otherwise), the coarse correction of the
// remaining residual by CoarseCycle (its hierarchy is built for the same truncation and Hessian,
// so its levels are the Galerkin matrices of K), nu2 backward sweeps. Truncated rows stay
// truncated: w = 0 there. With nu1 = nu2 and a V-cycle the cycle is a symmetric operator (the
// preconditioner of pcg.hpp); other choices are only nearly symmetric, which the flexible PCG takes.
#pragma once
#include "model/basis_transform.hpp"
#include "mg/cycle.hpp"
#include "mg/line_smoother.hpp"

namespace cmg {

template <int d>
class TruncatedLinearCycle {
 public:
  // A in the nodal frames of `basis` (the lines are found from its canonical blocks)
  TruncatedLinearCycle(const BlockMatrix<d>& A, const BasisTransform<d>& basis) : A_(A), basis_(basis) {}

  // K for this truncation and Hessian; the fine lines are found once, from A.
  void set_linearization(const std::uint8_t* mask, const std::vector<std::pair<Index, Mat<d>>>& hessian, bool lines) {
    const Index n = A_.rows;
    if (lines != use_lines_ || !gs_.factored()) {
      use_lines_ = lines;
      LineSet L;
      if (lines) {
        if (fine_lines_.nodes.empty()) fine_lines_ = find_lines<d>(A_, [&](Index i) { return basis_.block_of(i); });
        L = fine_lines_;
      } else {  // every node a line of its own: the point-block Gauss-Seidel of K
        L.nodes.resize(n);
        L.ptr.resize(n + 1);
        for (Index i = 0; i < n; ++i) { L.nodes[i] = i; L.ptr[i + 1] = i + 1; }
      }
      gs_ = LineGaussSeidel<d>(std::move(L));
      mask_.clear();
    }
    if (gs_.factored() && mask_.size() == (std::size_t)(n * d) && std::equal(mask_.begin(), mask_.end(), mask) &&
        same_hessian(hessian))
      return;
    mask_.assign(mask, mask + n * d);
    hessian_ = hessian;
    gs_.factor(A_, mask_.data(), hessian_);
    r_.assign(n * d, 0.0);
    t_.assign(n * d, 0.0);
  }
  const LineSet& lines() const { return gs_.lines(); }
  const std::uint8_t* mask() const { return mask_.data(); }

  // y = K x on the active dofs (x = 0 on the truncated ones: y is 0 there)
  void multiply(const double* x, double* y) const {
    A_.multiply(x, y);
    const Index n = (Index)mask_.size();
    parallel_for(n, [&](Index k) { y[k] *= mask_[k]; });
    for (const auto& [i, H] : hessian_) {
      Vec<d> hx = H * CVecMap<d>(x + d * i);
      for (int c = 0; c < d; ++c) y[d * i + c] += mask_[d * i + c] * hx[c];
    }
  }

  // w = B r (r: the masked residual), one cycle from w = 0
  void apply(CoarseCycle<d>& C, const SolverOptions& opt, const double* r, double* w) {
    const Index n = (Index)mask_.size();
    std::fill(w, w + n, 0.0);
    for (int s = 0; s < opt.nu1; ++s) gs_.sweep(A_, mask_.data(), r, w, true);
    multiply(w, t_.data());
    parallel_for(n, [&](Index k) { r_[k] = r[k] - t_[k]; });
    C.correction(opt, r_.data(), mask_.data(), NodeBounds{}, false, t_.data(), A_.rows, false, use_lines_);
    parallel_for(n, [&](Index k) { w[k] += t_[k]; });
    for (int s = 0; s < opt.nu2; ++s) gs_.sweep(A_, mask_.data(), r, w, false);
  }

  std::size_t memory_bytes() const {
    return gs_.memory_bytes() + sizeof(double) * (r_.size() + t_.size()) + mask_.size() +
           sizeof(Index) * (fine_lines_.nodes.size() + fine_lines_.ptr.size());
  }

 private:
  bool same_hessian(const std::vector<std::pair<Index, Mat<d>>>& h) const {
    if (h.size() != hessian_.size()) return false;
    for (std::size_t k = 0; k < h.size(); ++k)
      if (h[k].first != hessian_[k].first || h[k].second != hessian_[k].second) return false;
    return true;
  }

  const BlockMatrix<d>& A_;
  const BasisTransform<d>& basis_;
  LineSet fine_lines_;
  LineGaussSeidel<d> gs_;
  bool use_lines_ = false;
  std::vector<std::uint8_t> mask_;
  std::vector<std::pair<Index, Mat<d>>> hessian_;
  std::vector<double> r_, t_;
};

}  // namespace cmg
