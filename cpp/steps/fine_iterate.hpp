// The fine-level iterate (local frames, Dirichlet values in place) with its tracked product A u.
#pragma once
#include "model/contact_problem.hpp"

namespace cmg {

template <int d>
struct FineIterate {
  std::vector<double> u, Au;

  // u0 canonical (nullptr: zero); the Dirichlet values are put in place.
  void start(const ContactProblem<d>& P, const double* u0) {
    const Index n = P.num_nodes();
    if (u0) {
      for (Index k = 0; k < n * d; ++k)
        if (!std::isfinite(u0[k])) throw InputError("the initial guess has a non-finite entry");
      u.assign(u0, u0 + n * d);
      P.basis().to_local(u.data());
    } else {
      u.assign(n * d, 0.0);
    }
    const auto& dofs = P.fixed_dofs();
    const auto& values = P.fixed_dof_values();
    for (std::size_t m = 0; m < dofs.size(); ++m) u[dofs[m]] = values[m];
    Au.assign(n * d, 0.0);
    P.matrix().multiply(u.data(), Au.data());
  }
};

}  // namespace cmg
