// What every friction law shares at one contact node, in the node's frame (component 0 normal):
// its data, and -- given the law's friction bound -- its energy term, its state (free, stick,
// slip) and its linearization for the coarse problem (truncation mask, correction bounds, friction
// gradient and Hessian). A law (frictionless.hpp, tresca.hpp, coulomb.hpp) supplies the exact nodal
// solve and the bound s_p; nothing outside the laws asks which law it is.
#pragma once
#include <cmath>
#include "laws/nodal_solve.hpp"

namespace cmg {

struct ContactNode {
  double gap;         // g_p: u_n <= g_p
  double coef;        // friction coefficient F_p (Coulomb) or the given bound (Tresca)
  double bound;       // the Tresca bound in force (= coef, or F_p |s_n| inside Algorithm 1)
  TangentMask free;   // tangential frame components not fixed by a Dirichlet condition
};

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
template <int d>
Mat<d> friction_hessian(double s, const double* u, TangentMask free) {
  Mat<d> H = Mat<d>::Zero();
  int nfree = 0;
  for (int a = 1; a < d; ++a) nfree += free >> (a - 1) & 1u;
  const double ut = free_tangential_norm<d>(u, free);
  if (nfree < 2 || !(s > 0) || ut == 0) return H;
  for (int a = 1; a < d; ++a)
    for (int b = 1; b < d; ++b) H(a, b) = s * ((a == b ? 1.0 : 0.0) - u[a] * u[b] / (ut * ut)) / ut;
  return H;
}

// The law's energy term and state at the iterate u (frame); r_n = (f - A u)_n = -s_n.
template <class L, int d>
double friction_energy(const ContactNode& p, const double* u, double r_n) {
  const bool active = u[0] >= p.gap;
  return L::bound(p, active, r_n) * free_tangential_norm<d>(u, p.free);
}

// Stick and slip are decided by the free tangential components; a node in contact whose tangential
// components are all prescribed (2D with a roller along the obstacle) counts as sticking.
template <int d>
NodeState node_state(const ContactNode& p, const double* u) {
  if (!(u[0] >= p.gap)) return NodeState::Free;
  return free_tangential_norm<d>(u, p.free) == 0 ? NodeState::Stick : NodeState::Slip;
}

// The smooth neighbourhood of the smoothed iterate at one node: truncation mask (active normal,
// sticking tangentials; `base` keeps the Dirichlet dofs truncated), correction bounds (inactive
// normal, sign of sliding tangentials) and the friction gradient of a sliding node added to the
// residual r (r = f - A u on entry). Its Hessian goes to *hessian (left zero where there is none).
// Returns whether a bound is finite.
template <class L, int d>
bool linearize_node(const ContactNode& p, const double* u, double* r, std::uint8_t* mask, const std::uint8_t* base,
                    double* lo, double* hi, Mat<d>* hessian) {
  bool bounded = false;
  for (int a = 0; a < d; ++a) { mask[a] = base[a]; lo[a] = -kInf; hi[a] = kInf; }
  const bool active = u[0] >= p.gap;
  if (active) mask[0] = 0;
  else { hi[0] = p.gap - u[0]; bounded = true; }
  const double s = L::bound(p, active, r[0]);
  if (s <= 0) return bounded;
  const double ut = free_tangential_norm<d>(u, p.free);
  if (ut == 0) {
    for (int a = 1; a < d; ++a) mask[a] = 0;
    return bounded;
  }
  for (int a = 1; a < d; ++a) {
    if (!(p.free >> (a - 1) & 1u)) continue;
    r[a] -= s * u[a] / ut;
    if (u[a] > 0) { lo[a] = -u[a]; bounded = true; }
    else if (u[a] < 0) { hi[a] = -u[a]; bounded = true; }
  }
  if constexpr (d == 3)
    if (hessian) *hessian = friction_hessian<d>(s, u, p.free);
  return bounded;
}

}  // namespace cmg
