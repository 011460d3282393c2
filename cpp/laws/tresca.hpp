// Tresca friction: a given bound s_p, acting at every contact node whether it touches or not
// (the problem of the seed paper's Algorithm 1). Algorithm 1 solves a sequence of these with s_p = F_p |s_n(u^{k-1})|.
#pragma once
#include "laws/contact_node.hpp"

namespace cmg::law {

struct Tresca {
  // whether the coarse problem freezes a bound that depends on the iterate (Coulomb's F |s_n|):
  // then the settled cycle contracts slowly and is Anderson-accelerated (steps/settled_anderson.hpp)
  static constexpr bool coarse_freezes_bound = false;
  static constexpr bool has_contact = true;
  template <int d>
  static Vec<d> solve(const Mat<d>& B, const Vec<d>& b, const ContactNode& p, const Vec<d>& old) {
    return solve_on_increment<d>(B, b, p, old, [&](const Vec<d>& bb, const Vec<d>&) {
      return solve_node_tresca<d>(B, bb, p.gap, p.bound, p.free);
    });
  }
  static double bound(const ContactNode& p, bool, double) { return p.bound; }
  static double bound_slope(const ContactNode&, bool, double) { return 0.0; }  // a given bound
};

}  // namespace cmg::law
