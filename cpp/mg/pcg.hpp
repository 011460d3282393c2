// Preconditioned conjugate gradients for K w = r from w = 0, K symmetric positive definite on the
// active dofs, B a preconditioner (a truncated linear multigrid cycle). Flexible form: the step
// length is the exact minimizer of the energy E(w) = 1/2 w^T K w - r^T w along each direction
// (alpha = p^T res / p^T K p) and beta is Polak-Ribiere's, z_{k+1}^T (res_{k+1} - res_k) / z_k^T res_k,
// so a preconditioner that is only nearly symmetric (an F-cycle, nu1 != nu2) keeps the method
// sound, and every iteration lowers E -- by (p^T res)^2 / (2 p^T K p) >= 0, whatever B is.
// Stops when an iteration's energy decrease has fallen to reduction^2 times the first one's (for a
// contraction by `reduction` of the energy norm of the correction; measured before B is applied
// again, so no cycle is wasted), or after max_iterations applications of B.
#pragma once
#include <cmath>
#include <vector>
#include "base/parallel.hpp"

namespace cmg {

struct PcgReport {
  int iterations = 0;          // applications of the preconditioner
  std::vector<double> energy;  // E(w) after each iteration (E(0) = 0 first)
};

// K(x, y): y = K x; B(res, z): z ~ K^{-1} res. n the vector length.
template <class Op, class Prec>
PcgReport pcg(Index n, Op&& K, Prec&& B, const double* r, double* w, int max_iterations, double reduction,
              bool record_energy = false) {
  PcgReport rep;
  std::vector<double> res(r, r + n), z(n), p(n), q(n), res_old(n);
  std::fill(w, w + n, 0.0);
  if (record_energy) rep.energy.push_back(0.0);
  B(res.data(), z.data());
  rep.iterations = 1;
  double rz = parallel_sum(n, [&](Index k) { return res[k] * z[k]; });
  if (!(rz > 0)) return rep;
  p = z;
  double first_decrease = -1;
  for (;;) {
    K(p.data(), q.data());
    const double pq = parallel_sum(n, [&](Index k) { return p[k] * q[k]; });
    const double pr = parallel_sum(n, [&](Index k) { return p[k] * res[k]; });
    if (!(pq > 0)) break;
    const double alpha = pr / pq;
    res_old = res;
    parallel_for(n, [&](Index k) { w[k] += alpha * p[k]; res[k] -= alpha * q[k]; });
    const double decrease = 0.5 * pr * pr / pq;
    if (first_decrease < 0) first_decrease = decrease;
    if (record_energy)  // from the vectors, not from the formula: E(w) = -1/2 w^T (r + res)
      rep.energy.push_back(-0.5 * parallel_sum(n, [&](Index k) { return w[k] * (r[k] + res[k]); }));
    if (rep.iterations >= max_iterations || !(decrease > reduction * reduction * first_decrease)) break;
    B(res.data(), z.data());
    ++rep.iterations;
    const double rz_new = parallel_sum(n, [&](Index k) { return res[k] * z[k]; });
    if (!(rz_new > 0)) break;
    const double beta = std::max(0.0, parallel_sum(n, [&](Index k) { return z[k] * (res[k] - res_old[k]); }) / rz);
    rz = rz_new;
    parallel_for(n, [&](Index k) { p[k] = z[k] + beta * p[k]; });
  }
  return rep;
}

}  // namespace cmg
