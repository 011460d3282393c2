// The multigrid recursion of the coarse correction, written once: the serial cycle (mg/cycle.hpp)
// runs it over its Galerkin levels, the distributed one (python/contactmg/distributed/cycle.py)
// over one rank's part of every level, each giving its level operations as a policy.
//
// Levels provides, for a level l >= 1 (0 is the coarsest):
//   pre_smooth(l), post_smooth(l)   one sweep (projected where the level has bounds),
//   restrict_down(l)                level l - 1's right-hand side b - A x and bounds (the slack that
//                                   remains on level l) restricted, its x zeroed,
//   prolong_up(l)                   x_l += P x_{l-1},
//   solve_coarsest()                the coarsest level's correction (mg/bounded_coarsest.hpp),
//   enter(l, body)                  runs body() for level l (the serial levels choose their threads).
#pragma once
#include "base/solver_options.hpp"

namespace cmg {

// One cycle of `type` from level l down: nu1 sweeps, one visit of the level below (V) or two
// (W; F: the second one a V), nu2 sweeps back.
template <class Levels>
void multigrid_cycle(Levels& L, int nu1, int nu2, int l, CycleType type) {
  L.enter(l, [&] {
    if (l == 0) {
      L.solve_coarsest();
      return;
    }
    for (int s = 0; s < nu1; ++s) L.pre_smooth(l);
    const int visits = type == CycleType::V ? 1 : 2;
    for (int v = 0; v < visits; ++v) {
      L.restrict_down(l);
      multigrid_cycle(L, nu1, nu2, l - 1, (type == CycleType::F && v == 1) ? CycleType::V : type);
      L.prolong_up(l);
    }
    for (int s = 0; s < nu2; ++s) L.post_smooth(l);
  });
}

// The correction from the top coarse level, whose right-hand side the fine residual gave. A W- or
// F-cycle visits it twice from the fine level too, as from every other level: the fine level has
// no smoothing between the visits, so the second visit is one more cycle on level `top` from the
// correction already made (its residual b - A c is the restricted fine residual after w = P~ c,
// Galerkin). One visit left the error of a single coarse cycle in every fine correction: on Kuhn
// tetrahedra the linear rate then saturates at 0.52 (V) or 0.40 (W below the fine level only)
// instead of the two-grid 0.31 (tests/core/test_tet_two_grid.py).
template <class Levels>
void top_level_cycles(Levels& L, int nu1, int nu2, int top, CycleType type) {
  multigrid_cycle(L, nu1, nu2, top, type);
  if (type != CycleType::V) multigrid_cycle(L, nu1, nu2, top, type == CycleType::F ? CycleType::V : CycleType::W);
}

}  // namespace cmg
