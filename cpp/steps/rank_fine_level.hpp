// One rank's fine level of the distributed cycle (python/contactmg/distributed/cycle.py): a
// ContactProblem over the rank's nodes and one layer of ghosts (owned rows complete, ghost rows
// partial and never swept), and the steps of the cycle on it, each the serial step's at every row:
// the nonlinear sweep over a list of rows (one colour between two ghost exchanges), the residual,
// the fused difference-norm pass with its exact sum, the law's linearization, the contact state
// and the Anderson step's admission test.
#pragma once
#include <algorithm>
#include <vector>
#include "base/block_matrix.hpp"
#include "base/exact_sum.hpp"
#include "base/parallel.hpp"
#include "laws/law.hpp"
#include "model/contact_problem.hpp"
#include "steps/nonlinear_gauss_seidel.hpp"

namespace cmg {

template <int d>
struct RankFineLevel {
  Law law;
  ContactProblem<d> P;

  RankFineLevel(ContactProblem<d> problem, Law l) : law(l), P(std::move(problem)) {
    if (law == Law::Tresca) P.set_bounds_to_coefficients();
  }

  Index n() const { return P.num_nodes(); }

  // One nonlinear Gauss-Seidel pass over rows[0..count) (reversed where !forward), x in place.
  // threads > 1: the rows are one colour (no two coupled), updated on that many threads; a row's
  // update reads no row of its own colour, so the bits are those of one thread.
  void sweep(double* x, const Index* rows, Index count, bool forward, double omega, int threads) {
    if (threads == 1) {
      with_law(law, [&](auto L) { NonlinearGaussSeidel<d, decltype(L)>::sweep_list(P, x, rows, count, forward, omega); });
      return;
    }
    const Index chunk = (count + threads - 1) / threads;  // the list in one chunk per thread
    ThreadScope team(threads);
    with_law(law, [&](auto L) {
      parallel_for(threads, [&](Index t) {
        const Index b = std::min(count, t * chunk), e = std::min(count, b + chunk);
        NonlinearGaussSeidel<d, decltype(L)>::sweep_list(P, x, rows + b, e - b, true, omega);
      }, count >= kSerialColourRows ? 1 : threads + 1);
    });
  }

  // out = f - A u on rows[0..count), zero elsewhere, with the row passes' prefetches
  void residual(const double* u, const Index* rows, Index count, double* out) const {
    const BlockMatrix<d>& A = P.matrix();
    std::fill(out, out + n() * d, 0.0);
    for (Index q = 0; q < count; ++q) A.residual_row(A.values.data(), u, P.load().data(), rows[q], kPrefetchValueRows, out + d * rows[q]);
  }

  // y = A (u - old) on the rows flagged in `flag`: written into y there (add: added to it), and the
  // exact sum of the node values (u - old)_i . y_i (the products of a node summed left to right):
  // |u - old|_A^2 over these rows from one pass over the matrix, beside the kept A u it updates
  // (the serial step's fused norm pass).
  ExactAccumulator difference_product(const double* x, const double* z, double* y, const std::uint8_t* flag, bool add) const {
    const BlockMatrix<d>& A = P.matrix();
    const double* vals = A.values.data();
    ExactBins bins;
    return exact_detail::sum_items(bins, A.rows, [&](Index i) {
      if (!flag[i]) return;
      A.prefetch_ahead(i, x, z);
      prefetch_row_values<d>(vals, A.indptr.data(), i, kPrefetchValueRows, A.rows);
      double w[d] = {};
      accumulate_block_differences<d>(vals, A.indices.data(), A.indptr[i], A.indptr[i + 1], x, z, w);
      double s = (x[d * i] - z[d * i]) * w[0];
      for (int a = 1; a < d; ++a) s += (x[d * i + a] - z[d * i + a]) * w[a];
      for (int a = 0; a < d; ++a) y[d * i + a] = add ? y[d * i + a] + w[a] : w[a];
      if (!exact_detail::add_double(bins, s))
        throw InputError("|u - old|_A^2 has a non-finite term at row " + std::to_string(i) + ": the iterate is no longer finite");
    });
  }

  // The law's linearization at the contact nodes `contacts` (indices into the contact list): the
  // truncation mask (n * d: the Dirichlet mask, the contact rows' own where linearized), the
  // correction bounds lo/hi (nc * d) and Hessian blocks H (nc * d * d) per contact node, the
  // friction gradient added into r; returns whether any bound is finite.
  bool linearize(const double* u, double* r, const std::vector<Index>& contacts, std::uint8_t* mask, double* lo, double* hi,
                 double* H) const {
    std::copy(P.base_mask().begin(), P.base_mask().end(), mask);
    bool bounded = false;
    if (law == Law::Linear) return false;
    for (Index c : contacts) {
      const Index k = P.contact_node(c) * d;
      Mat<d> Hc = Mat<d>::Zero();
      const auto body = [&](auto L) {
        return linearize_node<decltype(L), d>(P.node(c), u + k, r + k, mask + k, P.base_mask().data() + k, lo + c * d, hi + c * d,
                                              &Hc, P.matrix().block(P.matrix().diag[P.contact_node(c)]));
      };
      if (with_law(law, body)) bounded = true;
      std::copy(Hc.data(), Hc.data() + d * d, H + c * d * d);
    }
    return bounded;
  }

  // Per contact node of `contacts`: state (0 free, 1 stick, 2 slip) and, given A u (else nullptr),
  // the friction energy from its residual f - A u at the node.
  void contact_state(const double* u, const std::vector<Index>& contacts, const double* Au, std::int8_t* state,
                     double* energy) const {
    for (std::size_t m = 0; m < contacts.size(); ++m) {
      const Index c = contacts[m], k = P.contact_node(c) * d;
      state[m] = (std::int8_t)node_state<d>(P.node(c), u + k);
      energy[m] = 0.0;
      if (!Au) continue;
      const double r = P.load()[k] - Au[k];
      energy[m] = with_law(law, [&](auto L) -> double {
        if constexpr (decltype(L)::has_contact) return friction_energy<decltype(L), d>(P.node(c), u + k, r);
        else return 0.0;
      });
    }
  }

  // The Anderson step's mixed iterate y at the contact nodes `contacts`, given the plain cycle's
  // result u (laws/contact_node.hpp admit_mixed_node): y adjusted in place, ok[m] whether node m
  // admits it (the step is taken where every owned node on every rank does).
  void admit_mixed(double* y, const double* u, const std::vector<Index>& contacts, std::uint8_t* ok) const {
    for (std::size_t m = 0; m < contacts.size(); ++m) {
      const Index k = P.contact_node(contacts[m]) * d;
      ok[m] = admit_mixed_node<d>(P.node(contacts[m]), y + k, u + k);
    }
  }
};

}  // namespace cmg
