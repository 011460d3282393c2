// The nodal contact frames Q_p = [n, t(, s)] (columns, canonical coordinates), built in this one
// place, and what a Dirichlet condition on some canonical components of a contact node means:
//  - a fixed axis orthogonal to n is made a frame tangent (in 2D it is one anyway; in 3D t is
//    chosen along it), and the component is eliminated there: the node keeps its contact
//    condition, and friction acts on its free tangential components;
//  - a fixed axis along n prescribes u_n: the node is no contact node, and the prescribed value
//    must be admissible (u_n <= g);
//  - a fixed axis neither along n nor orthogonal to it (a roller on a curved contact boundary)
//    is refused.
#pragma once
#include <cmath>
#include <cstdio>
#include "laws/nodal_solve.hpp"

namespace cmg {

// A fixed canonical axis counts as tangential (normal) when |n_a| (the rest of n) is below this.
constexpr double kAxisAlignment = 1e-8;

enum class ContactDirichlet : std::int8_t {
  Free = 0,         // no component fixed: an ordinary contact node
  Tangential = 1,   // some tangential components fixed: a contact node
  Normal = 2,       // u_n prescribed (admissibly): not a contact node
  Clamped = 3,      // every component fixed: not a contact node
};

inline std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

template <int d>
Vec<d> unit_normal(const double* nrm, Index node) {
  Vec<d> n = CVecMap<d>(nrm);
  const double len = n.norm();
  if (!(len > 1e-12) || !std::isfinite(len))
    throw InputError("the contact normal of node " + std::to_string(node) + " is zero or not finite");
  return n / len;
}

// Classifies the Dirichlet components of contact node `node` (fixed/values: its d canonical
// components); throws for a misaligned roller and for a prescribed penetration.
template <int d>
ContactDirichlet classify_contact_dirichlet(const double* nrm, double gap, const std::uint8_t* fixed, const double* values,
                                            Index node) {
  int nfixed = 0;
  for (int a = 0; a < d; ++a) nfixed += fixed[a] != 0;
  if (nfixed == 0) return ContactDirichlet::Free;
  if (nfixed == d) return ContactDirichlet::Clamped;
  const Vec<d> n = unit_normal<d>(nrm, node);
  static const char* axis = "xyz";
  bool normal = false;
  for (int a = 0; a < d; ++a) {
    if (!fixed[a]) continue;
    const double rest = std::sqrt(std::max(0.0, n.squaredNorm() - n[a] * n[a]));
    if (std::abs(n[a]) <= kAxisAlignment) continue;
    if (rest <= kAxisAlignment) {
      const double un = n[a] * values[a];
      if (un > gap + 1e-12 * std::max(std::abs(gap), std::abs(un)))
        throw InputError("the Dirichlet condition of contact node " + std::to_string(node) + " prescribes penetration: u_n = " +
                         fmt_num(un) + " exceeds the gap " + fmt_num(gap));
      normal = true;
      continue;
    }
    throw InputError("contact node " + std::to_string(node) + " has a fixed " + axis[a] +
                     " component that is neither normal nor tangential to its contact normal (" + fmt_num(n[0]) + ", " +
                     fmt_num(n[1]) + (d == 3 ? ", " + fmt_num(n[d - 1]) : std::string()) +
                     "): a roller on a curved contact boundary is not supported");
  }
  return normal ? ContactDirichlet::Normal : ContactDirichlet::Tangential;
}

// The frame of a contact node: 2D t = n rotated by +90 degrees; 3D t along the first fixed axis
// orthogonal to n if there is one, else orthogonal to n from the canonical axis least aligned
// with n; s = n x t.
template <int d>
Mat<d> contact_frame(const double* nrm, const std::uint8_t* fixed, Index node) {
  const Vec<d> n = unit_normal<d>(nrm, node);
  Mat<d> Q;
  Q.col(0) = n;
  if constexpr (d == 2) {
    Q(0, 1) = -n[1];
    Q(1, 1) = n[0];
  } else {
    Index k;
    n.cwiseAbs().minCoeff(&k);
    Vec<d> t;
    bool along_fixed = false;
    for (int a = 0; a < d && !along_fixed; ++a)
      if (fixed && fixed[a] && std::abs(n[a]) <= kAxisAlignment) {
        Vec<d> e = Vec<d>::Zero();
        e[a] = 1;
        t = (e - n[a] * n).normalized();
        along_fixed = true;
      }
    if (!along_fixed) {
      Vec<d> e = Vec<d>::Zero();
      e[k] = 1;
      t = n.cross(e).normalized();
    }
    Q.col(1) = t;
    Q.col(2) = n.cross(t);
  }
  return Q;
}

// The fixed canonical components of a contact node (of kind Tangential) in its frame Q: the
// frame tangent along a fixed axis a is fixed at value_a / Q(a, k). Returns the free mask.
template <int d>
TangentMask frame_dirichlet(const Mat<d>& Q, const std::uint8_t* fixed, const double* values, std::uint8_t* local_fixed,
                            double* local_values) {
  TangentMask free = all_tangents<d>();
  for (int k = 0; k < d; ++k) local_fixed[k] = 0;
  for (int a = 0; a < d; ++a) {
    if (!fixed[a]) continue;
    for (int k = 1; k < d; ++k)
      if (std::abs(Q(a, k)) >= 1 - kAxisAlignment) {
        local_fixed[k] = 1;
        local_values[k] = values[a] / Q(a, k);
        free &= ~(1u << (k - 1));
      }
  }
  return free;
}

}  // namespace cmg
