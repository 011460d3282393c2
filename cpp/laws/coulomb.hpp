// Coulomb friction: the bound F_p |s_n| of a node in contact, taken from the iterate (r_n = -s_n);
// the nodal rule of solve_node_coulomb keeps every local solution a fixed point (nodal_solve.hpp).
#pragma once
#include <algorithm>
#include "laws/contact_node.hpp"

namespace cmg::law {

struct Coulomb {
  // whether the coarse problem freezes a bound that depends on the iterate (Coulomb's F |s_n|):
  // then the settled cycle contracts slowly and is Anderson-accelerated (steps/settled_anderson.hpp)
  static constexpr bool coarse_freezes_bound = true;
  static constexpr bool has_contact = true;
  template <int d>
  static Vec<d> solve(const Mat<d>& B, const Vec<d>& b, const ContactNode& p, const Vec<d>& old) {
    return solve_on_increment<d>(B, b, p, old, [&](const Vec<d>& bb, const Vec<d>& oo) {
      return solve_node_coulomb<d>(B, bb, p.gap, p.coef, oo, p.free);
    });
  }
  static double bound(const ContactNode& p, bool active, double r_n) { return active ? p.coef * std::max(0.0, r_n) : 0.0; }
  // d bound / d r_n: what the frozen bound leaves out of the coarse problem (bound_coupling)
  static double bound_slope(const ContactNode& p, bool active, double r_n) { return active && r_n > 0 ? p.coef : 0.0; }
};

}  // namespace cmg::law
