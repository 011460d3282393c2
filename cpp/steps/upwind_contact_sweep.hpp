// One more Gauss-Seidel visit of the contact nodes after every fine sweep of Algorithm 2, the sliding
// ones in the upwind order of the Coulomb Jacobian (docs/dev/decisions/0007-upwind-contact-sweep.md;
// SolverOptions::upwind_contact_sweep, off in the core; the Python problem turns it on for Coulomb
// friction on 2D adaptive hierarchies).
//
// Why: a sliding node's tangential row is that of J = K + w_p e_pn^T K (w_p = -F t, t the slip
// direction; contact_node.hpp's bound_coupling), and its normal row couples to the neighbours'
// tangentials with opposite signs on either side (+-0.09 K_TT at the contact edge of adaptive Hertz
// level 11). So F t K_n adds to the tangential coupling on one side and cancels it on the other: at
// F = 5 the row's coupling to its outer neighbour is -0.91 of the diagonal, to its inner one +0.07
// (the nodes slide inwards), nearly a one-sided recurrence along the chain of sliding nodes at the
// contact edge, as a convection-dominated row is. Visiting each sliding node before the neighbour
// its row leans on (upwind) keeps a change at the chain's outer end -- where nodes at nearly zero
// pressure and gap flip between free and sliding while the error is still large -- from being
// carried along the whole chain within one sweep: on adaptive level 11 at F = 5 (36 sliding nodes)
// 14-15 cycles against 18 without the visit and 17 downwind (prototypes ordered by position:
// outwards 15, inwards 18). The other contact nodes get one more visit in their stored order: at
// F <= 1, where the direction does not matter (inward and outward orders gave the same counts),
// that extra visit alone took level 11 from 13 to 12. All of them, not only the zone in contact and
// a ring around it: the zone alone cost levels 3-9 a cycle at 11 of the 50 (level, F) pairs of the
// adaptive Table 1. One visit, not a solve of the chain: two or three visits a sweep made F = 5 32
// and 200 cycles (with the bulk held the chain's own system is near-singular; an exact
// chain solve blew the error up).
//
// Where friction dominates a node's tangential row the visit is left out (friction_does_not_dominate:
// F times the normal-tangential couplings of the node and its contact neighbours against its
// tangential stiffness; at the Hertz contact edge F above about 4.8, so F = 5 and beyond keep the
// plain sweeps there and the gain at F = 5 above is not had by default). With those nodes visited,
// adaptive level 9 at F = 40 stopped at an iterate the cycle kept and one plain sweep moved (the
// stopping check's stall), with or without the second visit (the nodes taken out of the sweep and
// visited once instead: the same stall, and level 11 at F = 5 / 8 18 / 96 cycles).
//
// The order is that of the cycle's linearization (its sliding nodes and their w), so a cycle's
// pre-smoothing uses the last cycle's (the first: the stored order): the contact nodes that do not
// slide, in the stored order, then the sliding ones, each before its downstream neighbour -- the
// sliding neighbour q with the largest tangential coupling |J_pq(T, T)| = |K_pq(T, T) + w_p(T)
// K_pq(n, T)| (Frobenius; in 3D the 2 x 2 block). Contact nodes outside the fine sweep's rows (a
// local fine level) are not visited. Every visit is the sweep's own row update, so a solution is
// still a fixed point, and the visits are serial (the result does not depend on the thread count).
#pragma once
#include <algorithm>
#include <utility>
#include <vector>
#include "steps/nonlinear_gauss_seidel.hpp"

namespace cmg {

template <int d, class L>
class UpwindContactSweep {
 public:
  UpwindContactSweep(const ContactProblem<d>& P, const SweepOrder& fine_order, bool on) : on_(on && L::has_contact) {
    if (!on_) return;
    std::vector<std::uint8_t> swept(P.num_nodes(), fine_order.all() ? 1 : 0);
    if (!fine_order.all()) fine_order.visit(P.num_nodes(), true, [&](Index i) { swept[i] = 1; });
    in_.assign(P.num_contact(), 0);
    for (Index c = 0; c < P.num_contact(); ++c)
      if (swept[P.contact_node(c)] && friction_does_not_dominate(P, c)) nodes_.push_back(c);
    for (Index c : nodes_) in_[c] = 1;
    for (Index c : nodes_) order_.push_back(P.contact_node(c));
  }

  bool on() const { return on_; }
  const std::vector<Index>& order() const { return order_; }  // fine rows, in visiting order

  // the visit after a sweep, over-relaxed as the sweep (its rows are contact rows: exact nodal solves)
  void visit(const ContactProblem<d>& P, double* u, double omega) const {
    for (Index i : order_) NonlinearGaussSeidel<d, L>::row_update(P, u, i, omega);
  }

  // The order of the linearization whose sliding nodes are `coupling` (fine node -> w_p).
  void order_from(const ContactProblem<d>& P, const std::vector<std::pair<Index, Vec<d>>>& coupling) {
    if (!on_) return;
    const BlockMatrix<d>& A = P.matrix();
    const Index nc = P.num_contact();
    slide_.assign(nc, -1);
    for (std::size_t k = 0; k < coupling.size(); ++k) {
      const Index c = visited(P, coupling[k].first);
      if (c >= 0) slide_[c] = (Index)k;
    }
    order_.clear();
    for (Index c : nodes_)
      if (slide_[c] < 0) order_.push_back(P.contact_node(c));
    // down_[k]: the sliding neighbour the row of sliding node k leans on most
    down_.assign(coupling.size(), -1);
    const auto tangential = [](const Mat<d>& K, const Vec<d>& w) {
      Mat<d> J = K;
      J.template bottomRows<d - 1>() += w.template tail<d - 1>() * K.row(0);
      return J.template bottomRightCorner<d - 1, d - 1>().norm();
    };
    for (std::size_t k = 0; k < coupling.size(); ++k) {
      const auto& [p, w] = coupling[k];
      if (visited(P, p) < 0) continue;
      double best = -1;
      for (Index q = A.indptr[p]; q < A.indptr[p + 1]; ++q) {
        const Index j = visited(P, A.indices[q]);
        if (A.indices[q] == p || j < 0 || slide_[j] < 0) continue;
        const double s = tangential(A.block(q), w);
        if (s > best) { best = s; down_[k] = slide_[j]; }
      }
    }
    // each sliding node before the one it leans on: chains followed from their upwind ends (a node
    // no other leans on first), a closed loop of links cut where it closes
    leaned_.assign(coupling.size(), 0);
    for (Index k : down_)
      if (k >= 0) leaned_[k] = 1;
    mark_.assign(coupling.size(), 0);
    const auto follow = [&](Index k) {
      for (; k >= 0 && !mark_[k]; k = down_[k]) { mark_[k] = 1; order_.push_back(coupling[k].first); }
    };
    for (int pass = 0; pass < 2; ++pass)  // upwind ends first, then what is left (loops)
      for (std::size_t k = 0; k < coupling.size(); ++k)
        if (visited(P, coupling[k].first) >= 0 && (pass == 1 || !leaned_[k])) follow((Index)k);
  }

 private:
  // the contact index of fine node i where it is one of nodes_, else -1
  Index visited(const ContactProblem<d>& P, Index i) const {
    const Index c = P.contact_of_node(i);
    return c >= 0 && in_[c] ? c : -1;
  }

  // Whether the node's tangential stiffness exceeds what friction couples into its row: F_p (the
  // bound's slope, law::bound_slope) times |K_pq(n, T)| summed over the node itself and its contact
  // neighbours, against lambda_min(K_pp(T, T)). Where friction dominates, the nodal rule lags its
  // bound (the self term alone: q >= 1 in coulomb_on_gap) or the sliding chain's rows lean on their
  // neighbours by more than their diagonal, and the visits' iteration need not contract.
  static bool friction_does_not_dominate(const ContactProblem<d>& P, Index c) {
    if constexpr (!L::coarse_freezes_bound) return true;  // no bound that moves with r_n
    const BlockMatrix<d>& A = P.matrix();
    const Index i = P.contact_node(c);
    double F = 0;
    if constexpr (L::coarse_freezes_bound) F = L::bound_slope(P.node(c), true, 1.0);
    if (!(F > 0)) return true;
    double coupling = 0, stiffness, self;
    free_tangential_coupling<d>(A.block(A.diag[i]), P.node(c).free, stiffness, self);
    for (Index q = A.indptr[i]; q < A.indptr[i + 1]; ++q)
      if (P.contact_of_node(A.indices[q]) >= 0) coupling += A.block(q).template block<1, d - 1>(0, 1).norm();
    return stiffness > 0 && F * coupling < stiffness;
  }

  bool on_;
  std::vector<Index> nodes_;    // the contact indices the fine sweeps visit
  std::vector<std::uint8_t> in_;  // per contact index: one of nodes_
  std::vector<Index> order_;    // this cycle's order (fine rows)
  std::vector<Index> slide_, down_;
  std::vector<std::uint8_t> leaned_, mark_;
};

}  // namespace cmg
