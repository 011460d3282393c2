// What every friction law shares at one contact node, in the node's frame (component 0 normal):
// its data, and -- given the law's friction bound -- its energy term, its state (free, stick,
// slip) and its linearization for the coarse problem (truncation mask, correction bounds, friction
// gradient and Hessian). A law (frictionless.hpp, tresca.hpp, coulomb.hpp) supplies the exact nodal
// solve and the bound s_p; nothing outside the laws asks which law it is.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>
#include "laws/nodal_solve.hpp"

namespace cmg {

struct ContactNode {
  double gap;         // g_p: u_n <= g_p
  double coef;        // friction coefficient F_p (Coulomb) or the given bound (Tresca)
  double bound;       // the Tresca bound in force (= coef, or F_p |s_n| inside Algorithm 1)
  TangentMask free;   // tangential frame components not fixed by a Dirichlet condition
  // Load paths: the previous step's displacement in the frame (d values; only
  // its free tangential components are read), or nullptr for the first step from u = 0. Friction
  // then acts on the slip increment u_T - origin_T, and "stick" means no slip in this step.
  const double* origin = nullptr;
};

// u_T - origin_T on the free tangential components (component 0 and fixed components: 0). Without
// an origin this is u itself, so the single-step path computes exactly what it did before.
template <int d>
Vec<d> slip_increment(const ContactNode& p, const double* u) {
  Vec<d> v = CVecMap<d>(u);
  if (p.origin)
    for (int a = 1; a < d; ++a)
      if (p.free >> (a - 1) & 1u) v[a] -= p.origin[a];
  return v;
}

// The nodal minimizer of a law with friction on the slip increment: 1/2 x^T B x - b^T x + s|x_T - z_T|
// is, for y = x - z (z = (0, z_T)), the same problem in y with b - B z (z has no normal component, so
// the constraint y_n <= g is unchanged and stick is y_T == 0, i.e. x_T == z_T exactly).
template <int d, class Solve>
Vec<d> solve_on_increment(const Mat<d>& B, const Vec<d>& b, const ContactNode& p, const Vec<d>& old, Solve&& solve) {
  if (!p.origin) return solve(b, old);
  Vec<d> z = Vec<d>::Zero();
  for (int a = 1; a < d; ++a)
    if (p.free >> (a - 1) & 1u) z[a] = p.origin[a];
  Vec<d> x = solve(Vec<d>(b - B * z), Vec<d>(old - z));
  return x + z;
}

enum class NodeState : std::int8_t { Free = 0, Stick = 1, Slip = 2 };

// |u_T| over the free tangential components (a fixed one takes no part in friction).
template <int d>
double free_tangential_norm(const double* u, TangentMask free) {
  double ut = 0;
  for (int a = 1; a < d; ++a)
    if (free >> (a - 1) & 1u) ut += u[a] * u[a];
  return std::sqrt(ut);
}

// Hessian of s |u_T| at a sliding node, s (I - t t^T) / |u_T| with t = u_T / |u_T| on the free
// tangential components. With one free tangential direction (2D, or 3D with one fixed) it is zero.
//
// Its curvature s / |u_T| is capped at stiffness / sqrt(eps), stiffness the node's own tangential
// stiffness (largest tangential diagonal entry of its block): a node that only just slides (a load
// step's slip increment at round-off, 1e-17) had s / |u_T| = 1e17 against elastic entries of 1e2,
// and the coarse matrices, updated incrementally by - H_old + H_new, kept the elastic entries only
// to +-10: an indefinite coarsest matrix (the 8-layer cork pulled back, refused as "singular").
// Below the cap a removed Hessian leaves at least half the digits of the elastic entries. The cap
// changes the coarse problem's model only where it already holds the node's perpendicular motion
// to 1e-8 of its unconstrained size; the fine smoother, which decides the solution, has no cap.
template <int d>
Mat<d> friction_hessian(double s, const double* u, TangentMask free, double stiffness = kInf) {
  Mat<d> H = Mat<d>::Zero();
  int nfree = 0;
  for (int a = 1; a < d; ++a) nfree += free >> (a - 1) & 1u;
  const double ut = free_tangential_norm<d>(u, free);
  if (nfree < 2 || !(s > 0) || ut == 0) return H;
  const double cap = stiffness / std::sqrt(std::numeric_limits<double>::epsilon());
  const bool capped = s / ut > cap;
  for (int a = 1; a < d; ++a)
    for (int b = 1; b < d; ++b) {
      const double t = (a == b ? 1.0 : 0.0) - u[a] * u[b] / (ut * ut);
      H(a, b) = capped ? cap * t : s * t / ut;
    }
  return H;
}

// The law's energy term and state at the iterate u (frame); r_n = (f - A u)_n = -s_n.
template <class L, int d>
double friction_energy(const ContactNode& p, const double* u, double r_n) {
  const bool active = u[0] >= p.gap;
  const Vec<d> v = slip_increment<d>(p, u);
  return L::bound(p, active, r_n) * free_tangential_norm<d>(v.data(), p.free);
}

// Stick and slip are decided by the free tangential components; a node in contact whose tangential
// components are all prescribed (2D with a roller along the obstacle) counts as sticking.
template <int d>
NodeState node_state(const ContactNode& p, const double* u) {
  if (!(u[0] >= p.gap)) return NodeState::Free;
  const Vec<d> v = slip_increment<d>(p, u);
  return free_tangential_norm<d>(v.data(), p.free) == 0 ? NodeState::Stick : NodeState::Slip;
}

// The mixed iterate y of an Anderson step (steps/settled_anderson.hpp) at one node, given the plain
// cycle's result u there: y takes u's contact state exactly (on the gap exactly g, sticking
// tangentials at u's values), or the node refuses it (an inactive node y puts onto or past the
// obstacle, a sliding node it stops or turns). Returns whether the node admits y.
template <int d>
bool admit_mixed_node(const ContactNode& p, double* y, const double* u) {
  const NodeState s = node_state<d>(p, u);
  if (s == NodeState::Free) return y[0] < p.gap;
  y[0] = p.gap;
  if (s == NodeState::Stick) {
    for (int a = 1; a < d; ++a) y[a] = u[a];
    return true;
  }
  if (node_state<d>(p, y) != NodeState::Slip) return false;
  const Vec<d> vu = slip_increment<d>(p, u), vy = slip_increment<d>(p, y);
  for (int a = 1; a < d; ++a)
    if ((vu[a] > 0) != (vy[a] > 0) || (vu[a] < 0) != (vy[a] < 0)) return false;
  return true;
}

// The smooth neighbourhood of the smoothed iterate at one node: truncation mask (active normal,
// sticking tangentials; `base` keeps the Dirichlet dofs truncated), correction bounds (inactive
// normal, sign of sliding tangentials) and the friction gradient of a sliding node added to the
// residual r (r = f - A u on entry). Its Hessian goes to *hessian (left zero where there is none;
// B the node's diagonal block, for the Hessian's cap). Returns whether a bound is finite.
template <class L, int d>
bool linearize_node(const ContactNode& p, const double* u, double* r, std::uint8_t* mask, const std::uint8_t* base,
                    double* lo, double* hi, Mat<d>* hessian, const Mat<d>& B) {
  bool bounded = false;
  for (int a = 0; a < d; ++a) { mask[a] = base[a]; lo[a] = -kInf; hi[a] = kInf; }
  const bool active = u[0] >= p.gap;
  if (active) mask[0] = 0;
  else { hi[0] = p.gap - u[0]; bounded = true; }
  const double s = L::bound(p, active, r[0]);
  if (s <= 0) return bounded;
  // sign bounds, gradient and Hessian of the friction term on the slip increment v_T = u_T - origin_T
  const Vec<d> v = slip_increment<d>(p, u);
  const double ut = free_tangential_norm<d>(v.data(), p.free);
  if (ut == 0) {
    for (int a = 1; a < d; ++a) mask[a] = 0;
    return bounded;
  }
  for (int a = 1; a < d; ++a) {
    if (!(p.free >> (a - 1) & 1u)) continue;
    r[a] -= s * v[a] / ut;
    if (v[a] > 0) { lo[a] = -v[a]; bounded = true; }
    else if (v[a] < 0) { hi[a] = -v[a]; bounded = true; }
  }
  if constexpr (d == 3)
    if (hessian) {
      double stiffness = 0;
      for (int a = 1; a < d; ++a) stiffness = std::max(stiffness, B(a, a));
      *hessian = friction_hessian<d>(s, v.data(), p.free, stiffness);
    }
  return bounded;
}

// What the coarse problem's frozen bound leaves out at a sliding node
// (docs/dev/decisions/0006-petrov-galerkin-coupling.md): the friction force s t (t = v_T / |v_T|) moves
// with the normal residual r_n by s'(r_n) t, so the Jacobian's tangential rows are K_T - s' t K_n, i.e.
// J = K + w e_n^T K with w = -s' t (zero normal component). Returns w, zero where the node does not
// slide or its bound does not move with r_n.
template <class L, int d>
Vec<d> bound_coupling(const ContactNode& p, const double* u, double r_n) {
  Vec<d> w = Vec<d>::Zero();
  const bool active = u[0] >= p.gap;
  const double slope = L::bound_slope(p, active, r_n);
  if (!(slope > 0) || !(L::bound(p, active, r_n) > 0)) return w;
  const Vec<d> v = slip_increment<d>(p, u);
  const double ut = free_tangential_norm<d>(v.data(), p.free);
  if (ut == 0) return w;
  for (int a = 1; a < d; ++a)
    if (p.free >> (a - 1) & 1u) w[a] = -slope * v[a] / ut;
  return w;
}

}  // namespace cmg
