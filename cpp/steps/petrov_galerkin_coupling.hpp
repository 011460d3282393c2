// The Petrov-Galerkin coupling of the sliding nodes on the top coarse level, in every cycle of Algorithm
// 2 but the first (docs/dev/decisions/0006-petrov-galerkin-coupling.md; SolverOptions::petrov_galerkin,
// off in the core; the Python problem turns it on for Coulomb friction on 2D adaptive hierarchies). Waiting
// for a settled contact state (the truncation of the cycle before) instead leaves the
// settling cycles at the frozen bound's slow rate (adaptive level 11, F = 2: 16 cycles against 13 in
// every cycle).
//
// Why: Algorithm 2's coarse problem freezes the bound F |s_n| of a sliding node, so its matrix is the
// symmetric P~^T K P~, while the Jacobian of the settled state has the tangential rows K_T - F t K_n
// there (contact_node.hpp, bound_coupling: J = K + sum_p w_p e_pn^T K). On adaptive Hertz level 11 that
// is the settled cycle's growth with F (docs/dev/decisions/0006-petrov-galerkin-coupling.md): in a
// three-grid model the term P~^T (J - K) P~ added on level L-1 alone -- the levels below stay symmetric
// -- takes the settled rate at F = 2 / 5 from 0.435 / 0.537 to 0.287 / 0.353. The term has rank k = the
// sliding nodes: (P~^T w_p) (e_pn^T K P~), the parents of p times the parents of p's neighbours, blocks
// inside the Galerkin pattern of P^T K P (GalerkinHierarchy::set_top_overlay).
//
// What it gives up: the coarse correction is no longer the minimization of the frozen energy, so it
// need not lower the energy (the bounds of the correction, hence feasibility, are kept as they are).
// Hence the fallback: a cycle with the term whose correction |u^{k+1} - u^k|_A is no smaller than
// every correction of the solve before (the measure of the settled Anderson mixing's restart test)
// is refused -- the iterate goes back to the cycle's start, the cycle still counts -- and the term
// is off for the rest of the solve; the model has unstable cases (L7 F = 8, L11 F = 8). From there on
// the cycles are today's monotone ones from a feasible iterate.
#pragma once
#include <tuple>
#include "mg/hierarchy.hpp"

namespace cmg {

// The blocks (I, J, M) of P~^T (sum_p w_p e_pn^T K) P~ on the coarse level of P (fine node p ->
// w_p, in its frame; P~ = diag(mask) P). Repeated positions are summed by set_top_overlay.
template <int d>
std::vector<std::tuple<Index, Index, Mat<d>>> coupling_blocks(const BlockMatrix<d>& A, const Prolongation<d>& P, const std::uint8_t* mask,
                                                              const std::vector<std::pair<Index, Vec<d>>>& coupling) {
  std::vector<std::tuple<Index, Index, Mat<d>>> out;
  std::vector<std::pair<Index, Vec<d>>> left, right;
  for (const auto& [p, w] : coupling) {
    left.clear();
    right.clear();
    Vec<d> wm = w;
    for (int a = 0; a < d; ++a) wm[a] *= mask[p * d + a];
    for (Index b = P.indptr[p]; b < P.indptr[p + 1]; ++b) left.emplace_back(P.indices[b], P.block(p, b).transpose() * wm);
    for (Index q = A.indptr[p]; q < A.indptr[p + 1]; ++q) {  // the normal row of K at p, on the free columns
      const Index j = A.indices[q];
      Eigen::Matrix<double, 1, d> k = A.block(q).row(0);
      for (int c = 0; c < d; ++c) k[c] *= mask[j * d + c];
      if (k.isZero(0.0)) continue;
      for (Index b = P.indptr[j]; b < P.indptr[j + 1]; ++b) right.emplace_back(P.indices[b], (k * P.block(j, b)).transpose());
    }
    for (const auto& [I, u] : left) {
      if (u.isZero(0.0)) continue;
      for (const auto& [J, v] : right) out.emplace_back(I, J, u * v.transpose());
    }
  }
  return out;
}

// When a cycle's top coarse level carries the coupling, and the fallback. Holds the hierarchy's
// overlay for one solve (removed when it ends, so the next solve starts from the symmetric levels).
template <int d>
class PetrovGalerkinCoupling {
 public:
  PetrovGalerkinCoupling(GalerkinHierarchy<d>& H, bool on) : H_(H), on_(on) {}
  ~PetrovGalerkinCoupling() { H_.clear_top_overlay(); }
  PetrovGalerkinCoupling(const PetrovGalerkinCoupling&) = delete;
  PetrovGalerkinCoupling& operator=(const PetrovGalerkinCoupling&) = delete;

  // whether this solve still wants the coupling (the caller then collects it)
  bool wanted() const { return on_ && !fallen_back_; }

  // Brings the top coarse level to this cycle's coarse problem, after the coarse update for its
  // truncation: the coupling of the sliding nodes `coupling` where the cycle `takes` it (all but a
  // solve's first) and something slides, else the symmetric matrix. Returns whether the coupling is
  // on (not where set_top_overlay refuses it).
  bool bring(const BlockMatrix<d>& A, const std::uint8_t* mask, const std::vector<std::pair<Index, Vec<d>>>& coupling, bool takes) {
    used_ = refused_ = false;
    if (!wanted() || !takes || coupling.empty() || H_.num_coarse_levels() < 2) {
      H_.clear_top_overlay();
      return false;
    }
    if (!H_.has_top_overlay() || coupling != applied_) {  // an update of the levels removes the overlay
      applied_.clear();
      if (!H_.set_top_overlay(coupling_blocks<d>(A, H_.prolongation(H_.num_coarse_levels() - 1), mask, coupling))) return false;
      applied_ = coupling;
    }
    used_ = true;
    return true;
  }

  // After the cycle: its correction |u^{k+1} - u^k|_A and the smallest of the solve before. Returns
  // whether the cycle carried the coupling and its step was no smaller: then the coupling is off for
  // the rest of the solve and the caller refuses the step (the iterate goes back to x).
  bool judge(double step, double best) {
    if (!used_ || step < best) return false;
    fallen_back_ = refused_ = true;
    H_.clear_top_overlay();
    applied_.clear();
    return true;
  }

  // the last cycle: 0 symmetric coarse problem, 1 with the coupling, 2 with it, refused and switched off
  int state() const { return used_ ? (refused_ ? 2 : 1) : 0; }

 private:
  GalerkinHierarchy<d>& H_;
  bool on_;
  bool fallen_back_ = false, used_ = false, refused_ = false;
  std::vector<std::pair<Index, Vec<d>>> applied_;
};

}  // namespace cmg
