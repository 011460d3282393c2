// No contact law: linear elasticity (contact nodes, if any, only carry their frames).
#pragma once
#include "laws/contact_node.hpp"

namespace cmg::law {

struct Linear {
  // whether the coarse problem freezes a bound that depends on the iterate (Coulomb's F |s_n|):
  // then the settled cycle contracts slowly and is Anderson-accelerated (steps/settled_anderson.hpp)
  static constexpr bool coarse_freezes_bound = false;
  static constexpr bool has_contact = false;
  template <int d>
  static Vec<d> solve(const Mat<d>&, const Vec<d>& b, const ContactNode&, const Vec<d>&) { return b; }  // never called
  static double bound(const ContactNode&, bool, double) { return 0.0; }
};

}  // namespace cmg::law
