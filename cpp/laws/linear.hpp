// No contact law: linear elasticity (contact nodes, if any, only carry their frames).
#pragma once
#include "laws/contact_node.hpp"

namespace cmg::law {

struct Linear {
  static constexpr bool has_contact = false;
  template <int d>
  static Vec<d> solve(const Mat<d>&, const Vec<d>& b, const ContactNode&, const Vec<d>&) { return b; }  // never called
  static double bound(const ContactNode&, bool, double) { return 0.0; }
};

}  // namespace cmg::law
