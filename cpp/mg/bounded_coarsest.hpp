// The coarsest level's correction under bounds, written once for the serial cycle (mg/cycle.hpp)
// and the distributed one's gathered coarsest level (the same code on every rank: the same bits).
//
// Given the exact solution x = A^{-1} b: where it leaves the bounds, projected Gauss-Seidel sweeps
// from the best start of energy below zero (the clamped solution, or the ray along the solution up
// to its first bound where the level has free motions), and where the level is semi-definite and the
// sweeps leave it moving, the exact box solve (mg/box_qp.hpp). Every step lowers the energy, so the
// coarse correction never raises it.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>
#include <Eigen/Core>
#include "base/block_matrix.hpp"
#include "base/solver_options.hpp"
#include "mg/box_qp.hpp"

namespace cmg {

// A coarsest solution that passes a bound by more than this factor is dominated by a motion its
// matrix hardly resists (a body not yet touching, whose solution along that motion is of the order
// of the load over round-off).
constexpr double kFreeMotionOvershoot = 1e4;

// The largest factor by which x passes a finite bound (0 where it passes none).
inline double bound_overshoot(Index n, const double* x, const double* lo, const double* hi) {
  double out = 0;
  for (Index k = 0; k < n; ++k) {
    if (x[k] > hi[k] && hi[k] > 0) out = std::max(out, x[k] / hi[k]);
    if (x[k] < lo[k] && lo[k] < 0) out = std::max(out, x[k] / lo[k]);
  }
  return out;
}

// alpha x for the solution x with alpha the energy's minimizer along it, cut at the first bound it
// meets (the bounds hold 0: the iterate is feasible), into `ray`; returns its energy. Ax: A x.
inline double ray_to_first_bound(Index n, const double* x, const double* Ax, const double* b, const double* lo,
                                 const double* hi, std::vector<double>& ray) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, n), Axv(Ax, n), bv(b, n);
  const double quad = xv.dot(Axv), slope = bv.dot(xv);
  // (along a null motion quad is round-off, of either sign: the energy falls all the way)
  double alpha = slope > 0 ? (quad > 0 ? std::min(1.0, slope / quad) : 1.0) : 0.0;
  for (Index k = 0; k < n && alpha > 0; ++k) {
    if (!(lo[k] <= 0 && hi[k] >= 0)) alpha = 0;
    else if (x[k] > 0 && alpha * x[k] > hi[k]) alpha = hi[k] / x[k];
    else if (x[k] < 0 && alpha * x[k] < lo[k]) alpha = lo[k] / x[k];
  }
  ray.resize(n);
  for (Index k = 0; k < n; ++k) ray[k] = std::max(lo[k], std::min(alpha * x[k], hi[k]));  // round-off at the bound
  return 0.5 * alpha * alpha * quad - alpha * slope;
}

// x: the exact solution on entry, the bounded correction on return; r: a workspace of n entries;
// shifted: the factorization had to shift A (semi-definite); sweep(forward): one projected
// Gauss-Seidel pass over every row on x.
template <int d, class Sweep>
void bound_coarsest_solution(const BlockMatrix<d>& A, const double* b, const double* lo, const double* hi, double* x,
                             double* r, bool shifted, Sweep&& sweep) {
  const Index n = A.rows * d;
  bool inside = true;
  for (Index k = 0; k < n; ++k) inside = inside && x[k] >= lo[k] && x[k] <= hi[k];
  if (inside) return;
  // Where the coarsest matrix is semi-definite (or nearly: coarse levels made from a mesh leave
  // its free motions at round-off, which the factorization's pivot test need not see), the
  // solution is huge along the motions nothing resists yet (a body its contacts hold, before it
  // touches): clamping it leaves a distorted field that x = 0 beats, and the sweeps then move the
  // body by its diagonal's share of the load a sweep (a block falling 0.5 onto its floor: 0.018 a
  // cycle). The ray from 0 along the solution up to the first bound it meets moves it as a whole
  // onto the obstacle.
  std::vector<double> ray;
  double ray_energy = 0;
  if (shifted || bound_overshoot(n, x, lo, hi) > kFreeMotionOvershoot) {
    A.multiply(x, r);
    ray_energy = ray_to_first_bound(n, x, r, b, lo, hi, ray);
  }
  // Start projected Gauss-Seidel from the clamped solution (or that ray's end) only if that beats
  // x = 0 in energy, so that the coarse correction never raises the energy.
  for (Index k = 0; k < n; ++k) x[k] = std::max(lo[k], std::min(x[k], hi[k]));
  A.multiply(x, r);
  double e = 0;
  for (Index k = 0; k < n; ++k) e += 0.5 * x[k] * r[k] - b[k] * x[k];
  if (!ray.empty() && ray_energy < e) {
    std::copy(ray.begin(), ray.end(), x);
    e = ray_energy;
  }
  if (!(e < 0)) std::fill(x, x + n, 0.0);
  bool settled = false;
  for (int s = 0; s < kCoarsestMaxSweeps && !settled; ++s) {
    std::copy(x, x + n, r);
    sweep(s % 2 == 0);
    double change = 0, scale = 0;
    for (Index k = 0; k < n; ++k) {
      change = std::max(change, std::abs(x[k] - r[k]));
      scale = std::max(scale, std::abs(x[k]));
    }
    settled = change <= 1e-14 * scale;
  }
  // On a semi-definite level (free motions) the sweeps contract at the rate of its smallest
  // eigenvalue: what they leave undone, Newton steps on the free dofs finish. Not on a definite
  // level whose solution merely overshoots a tiny bound (Hertz's first cycles), so that the
  // paper's cases keep their bits.
  if (shifted && !settled) minimize_box_qp<d>(A, b, lo, hi, x, kCoarsestNewtonSteps, 1e-14);
}

}  // namespace cmg
