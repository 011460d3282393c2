// Frictionless contact: the nodal solve is the projection of the free minimizer onto u_n <= g.
#pragma once
#include "laws/contact_node.hpp"

namespace cmg::law {

struct Frictionless {
  // whether the coarse problem freezes a bound that depends on the iterate (Coulomb's F |s_n|):
  // then the settled cycle contracts slowly and is Anderson-accelerated (steps/settled_anderson.hpp)
  static constexpr bool coarse_freezes_bound = false;
  static constexpr bool has_contact = true;
  template <int d>
  static Vec<d> solve(const Mat<d>& B, const Vec<d>& b, const ContactNode& p, const Vec<d>&) {
    return solve_node_tresca<d>(B, b, p.gap, 0.0, p.free);
  }
  static double bound(const ContactNode&, bool, double) { return 0.0; }
  static double bound_slope(const ContactNode&, bool, double) { return 0.0; }
};

}  // namespace cmg::law
