// The exact line search of TNNMG: along a correction w from the iterate u, minimize
//   phi(a) = J(u + a w) - J(u) = a^2/2 w^T A w - a w^T (f - A u) + sum_p s_p (|u_T + a w_T| - |u_T|)
// over a in [0, a_max], with the friction bounds s_p frozen (given per contact node) and a_max the
// largest step that keeps every normal displacement on the admissible side (u_n + a w_n <= g_p).
// phi is convex and piecewise smooth (a quadratic plus norms of affine functions), so its
// one-sided derivatives are nondecreasing and bisection on them finds the minimizer to round-off
// without any step-length parameter.
#pragma once
#include <algorithm>
#include <cmath>
#include "laws/contact_node.hpp"

namespace cmg {

template <int d>
class FrozenLineSearch {
 public:
  // One friction term s |u_T + a w_T| (free tangential components only; the rest zeroed).
  struct Term {
    double s;
    Vec<d> u, w;
  };

  void clear(double quad, double slope) {
    quad_ = quad;
    slope_ = slope;
    terms_.clear();
    a_max_ = kInf;
  }
  // s |u_T + a w_T| of one node (u, w in the node's frame)
  void add_friction(double s, const double* u, const double* w, TangentMask free) {
    if (!(s > 0)) return;
    Term t{s, Vec<d>::Zero(), Vec<d>::Zero()};
    bool moves = false;
    for (int a = 1; a < d; ++a)
      if (free >> (a - 1) & 1u) { t.u[a] = u[a]; t.w[a] = w[a]; moves = moves || w[a] != 0; }
    if (moves) terms_.push_back(t);
  }
  // u_n + a w_n <= g for all admissible a (u_n <= g holds)
  void add_normal_limit(double room, double wn) {
    if (wn > 0) a_max_ = std::min(a_max_, std::max(0.0, room) / wn);
  }

  // phi(a) (relative to a = 0)
  double value(double a) const {
    double v = 0.5 * a * a * quad_ - a * slope_;
    for (const Term& t : terms_) v += t.s * ((t.u + a * t.w).norm() - t.u.norm());
    return v;
  }

  // The minimizer over [0, a_max]; 0 when w is no descent direction.
  double minimize() const {
    if (!(quad_ > 0) && terms_.empty()) return 0.0;
    if (right_derivative(0.0) >= 0) return 0.0;
    double lo = 0, hi = a_max_;
    if (!std::isfinite(hi)) {  // bracket: phi' grows at least like a w^T A w (or the terms' slopes)
      hi = 1;
      for (int k = 0; k < 200 && right_derivative(hi) < 0; ++k) { lo = hi; hi *= 2; }
    }
    if (left_derivative(hi) <= 0) return hi;
    for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
      const double m = 0.5 * (lo + hi);
      if (right_derivative(m) < 0) lo = m;
      else if (left_derivative(m) > 0) hi = m;
      else return m;  // 0 lies in the subdifferential at a kink
    }
    // without friction terms the minimizer is explicit; otherwise the bracket is at round-off
    if (terms_.empty()) return std::min(slope_ / quad_, a_max_);
    return 0.5 * (lo + hi);
  }
  double a_max() const { return a_max_; }

 private:
  double derivative(double a, double side) const {
    double g = a * quad_ - slope_;
    for (const Term& t : terms_) {
      const Vec<d> v = t.u + a * t.w;
      const double n = v.norm();
      // at a kink (v = 0) the one-sided derivative of s |v| is +-s |w|
      g += n > 0 ? t.s * v.dot(t.w) / n : side * t.s * t.w.norm();
    }
    return g;
  }
  double right_derivative(double a) const { return derivative(a, 1.0); }
  double left_derivative(double a) const { return derivative(a, -1.0); }

  double quad_ = 0, slope_ = 0, a_max_ = kInf;
  std::vector<Term> terms_;
};

}  // namespace cmg
