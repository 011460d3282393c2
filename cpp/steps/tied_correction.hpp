// A second coarse correction in the space where every contact dof is frozen
// (docs/dev/decisions/0009-tied-correction.md; two bodies): for a mortar-transformed problem the contact
// dofs are the relative displacements of the nonmortar nodes, so this space holds the common motions of
// touching bodies -- the interface moving as one, as it must where the stiffer body pushes it -- which
// leave every gap, every slip and so the friction term unchanged: a plain linear coarse cycle without
// bounds, energy decreasing and feasible by construction. Algorithm 2's own coarse correction bounds
// each body's coarse unknowns by a part of every nearby slack (mg/bound_restriction.hpp), which cuts
// such a motion as if it closed the gap; with unequal materials its cycle count then grew with the
// level. The truncation is fixed, so the hierarchy is built once.
#pragma once
#include "model/contact_problem.hpp"
#include "mg/cycle.hpp"

namespace cmg {

template <int d>
class TiedCorrection {
 public:
  TiedCorrection(const ContactProblem<d>& P, std::vector<Prolongation<d>> prolongations)
      : H_(std::move(prolongations)), C_(H_), mask_(P.base_mask()) {
    for (Index c = 0; c < P.num_contact(); ++c)
      for (int a = 0; a < d; ++a) mask_[P.contact_node(c) * d + a] = 0;
    H_.rebuild(P.matrix(), mask_.data());
    r_.assign(mask_.size(), 0.0);
    w_.assign(mask_.size(), 0.0);
  }

  // u <- u + P~ c for the residual of u (one fine product), c one coarse cycle of `opt`.
  void apply(const ContactProblem<d>& P, const SolverOptions& opt, double* u) {
    const std::vector<double>& f = P.load();
    P.matrix().multiply(u, r_.data());
    parallel_for((Index)r_.size(), [&](Index k) { r_[k] = f[k] - r_[k]; });
    C_.correction(opt, r_.data(), mask_.data(), NodeBounds{}, false, w_.data(), P.num_nodes());
    parallel_for((Index)r_.size(), [&](Index k) { u[k] += w_[k]; });
  }

  std::size_t memory_bytes() const { return H_.memory_bytes() + C_.memory_bytes() + sizeof(double) * 2 * r_.size(); }

 private:
  GalerkinHierarchy<d> H_;
  CoarseCycle<d> C_;
  std::vector<std::uint8_t> mask_;
  std::vector<double> r_, w_;
};

}  // namespace cmg
