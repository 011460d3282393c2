// The fine level of a contact problem as the steps see it: the stiffness matrix and load in the
// basis of the nodal contact frames (BasisTransform), the Dirichlet dofs eliminated (identity rows
// and columns, the value on the right), and the data of every contact node. Built once; the
// iteration steps read it, the Tresca bounds of Algorithm 1 are the only thing that changes.
#pragma once
#include "basis_transform.hpp"
#include "contact_frames.hpp"
#include "laws/contact_node.hpp"
#include "mg/level_smoothers.hpp"

namespace cmg {

template <int d>
class ContactProblem {
 public:
  // fixed, fixed_values: canonical components (n * d). frame_fixed, frame_values (nc * d, may be
  // null): further components fixed in the contact frames (the known-state linear reference).
  // A is taken by value: a caller that no longer needs its matrix moves it in (no second copy).
  ContactProblem(BlockMatrix<d> A, const double* f, const std::uint8_t* fixed, const double* fixed_values,
                 const std::vector<Index>& contact_nodes, const double* normals, const double* gaps, const double* coefficients,
                 const std::uint8_t* frame_fixed = nullptr, const double* frame_values = nullptr)
      : A_(std::move(A)) {
    const Index n = A_.rows;
    const Index nc = (Index)contact_nodes.size();
    for (Index k = 0; k < n * d; ++k)
      if (fixed[k] && !std::isfinite(fixed_values[k])) throw InputError("a Dirichlet value is not finite");
    for (Index k = 0; k < n * d; ++k)
      if (!std::isfinite(f[k])) throw InputError("the load vector has a non-finite entry");
    f_.assign(f, f + n * d);
    fixed_.assign(fixed, fixed + n * d);
    std::vector<double> values(n * d, 0.0);
    for (Index k = 0; k < n * d; ++k)
      if (fixed[k]) values[k] = fixed_values[k];
    node_ = contact_nodes;
    gap_.assign(gaps, gaps + nc);
    coef_.assign(coefficients, coefficients + nc);
    bound_.assign(nc, 0.0);
    free_.assign(nc, all_tangents<d>());
    contact_of_node_.assign(n, -1);
    std::vector<Mat<d>> frames(nc);
    for (Index c = 0; c < nc; ++c) {
      const Index i = contact_nodes[c];
      if (i < 0 || i >= n) throw InputError("contact node " + std::to_string(i) + " is not a mesh node");
      if (contact_of_node_[i] >= 0) throw InputError("contact node " + std::to_string(i) + " is listed twice");
      if (!std::isfinite(gaps[c])) throw InputError("the gap of contact node " + std::to_string(i) + " is not finite");
      if (!(coefficients[c] >= 0) || !std::isfinite(coefficients[c]))
        throw InputError("the friction coefficient/bound of contact node " + std::to_string(i) + " must be finite and >= 0");
      contact_of_node_[i] = c;
      const ContactDirichlet kind = classify_contact_dirichlet<d>(normals + c * d, gaps[c], fixed + i * d, values.data() + i * d, i);
      if (kind == ContactDirichlet::Normal || kind == ContactDirichlet::Clamped)
        throw InputError("contact node " + std::to_string(i) + " has its " +
                         (kind == ContactDirichlet::Normal ? "normal component" : "every component") +
                         " prescribed by a Dirichlet condition: it is not a contact node");
      frames[c] = contact_frame<d>(normals + c * d, fixed + i * d, i);
      if (kind == ContactDirichlet::Tangential) {
        std::uint8_t lf[d];
        double lv[d] = {};
        free_[c] = frame_dirichlet<d>(frames[c], fixed + i * d, values.data() + i * d, lf, lv);
        for (int a = 0; a < d; ++a) { fixed_[i * d + a] = lf[a]; values[i * d + a] = lf[a] ? lv[a] : 0.0; }
      }
      if (frame_fixed)
        for (int a = 0; a < d; ++a)
          if (frame_fixed[c * d + a] && !fixed_[i * d + a]) {  // a Dirichlet component keeps its own value
            if (!std::isfinite(frame_values[c * d + a])) throw InputError("a Dirichlet value is not finite");
            fixed_[i * d + a] = 1;
            values[i * d + a] = frame_values[c * d + a];
            if (a > 0) free_[c] &= ~(1u << (a - 1));
          }
    }
    T_ = BasisTransform<d>(n, node_, std::move(frames));
    T_.transform_matrix(A_);
    T_.to_local(f_.data());
    eliminate_dirichlet(values.data());
    A_.find_diagonal();
    keep_special_inverses();
    base_mask_.assign(n * d, 1);
    for (Index k = 0; k < n * d; ++k) base_mask_[k] = fixed_[k] ? 0 : 1;
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) { fixed_dofs_.push_back(k); fixed_dof_values_.push_back(values[k]); }
  }

  Index num_nodes() const { return A_.rows; }
  Index num_contact() const { return (Index)node_.size(); }
  const BlockMatrix<d>& matrix() const { return A_; }
  const std::vector<double>& load() const { return f_; }
  // The inverse of the diagonal block of row i (invert_diagonal's): formed from the block itself
  // in the sweep -- the same bits as a stored one, and 16 bytes a dof less to hold and to stream
  // (issue 15) -- except on the rows where it is not the plain inverse (inert components,
  // pseudo-inverses), kept here.
  // (the lookup of a special row out of line, so that the common case inlines into the sweep)
  Mat<d> diagonal_inverse(Index i) const {
    if (!(row_flags_[i] & kSpecialInverse)) return Mat<d>(A_.block(A_.diag[i])).inverse();
    return special_inverse(i);
  }
  // What a row is, one byte each (the byte that said "special inverse" before; no more memory):
  // the fine sweep's kernel (steps/nonlinear_gauss_seidel.hpp) takes the rows with no bit set --
  // neither a contact node nor a special inverse, nearly all of them -- from this byte alone,
  // without the contact lookup or the law's solve.
  enum RowFlag : std::uint8_t { kSpecialInverse = 1, kContactRow = 2 };
  const std::uint8_t* row_flags() const { return row_flags_.data(); }
  const std::vector<std::uint8_t>& base_mask() const { return base_mask_; }  // 0 on Dirichlet dofs (local)
  const std::vector<std::uint8_t>& fixed() const { return fixed_; }
  // The Dirichlet dofs (local numbering) and their values: a list, not a vector over all dofs.
  const std::vector<Index>& fixed_dofs() const { return fixed_dofs_; }
  const std::vector<double>& fixed_dof_values() const { return fixed_dof_values_; }
  const BasisTransform<d>& basis() const { return T_; }
  Index contact_node(Index c) const { return node_[c]; }
  Index contact_of_node(Index i) const { return contact_of_node_[i]; }
  const std::vector<Index>& contact_nodes() const { return node_; }
  ContactNode node(Index c) const {
    return {gap_[c], coef_[c], bound_[c], free_[c], origin_.empty() ? nullptr : origin_.data() + c * d};
  }
  // The previous step of a load path (DESIGN section 12): friction acts on u_T - u_prev_T from now
  // on. u_prev is canonical (n * d); nullptr clears it (the path's first step from u = 0).
  void set_slip_origin(const double* u_prev) {
    if (!u_prev) { origin_.clear(); return; }
    const Index n = num_nodes();
    for (Index k = 0; k < n * d; ++k)
      if (!std::isfinite(u_prev[k])) throw InputError("the previous displacement of the load path has a non-finite entry");
    std::vector<double> u(u_prev, u_prev + n * d);
    T_.to_local(u.data());
    origin_.assign(num_contact() * d, 0.0);
    for (Index c = 0; c < num_contact(); ++c)
      for (int a = 0; a < d; ++a) origin_[c * d + a] = u[node_[c] * d + a];
  }
  bool has_slip_origin() const { return !origin_.empty(); }
  double energy_offset() const { return energy_offset_; }
  // Over-relaxation of the fine sweeps at nodes without contact (CycleOptions::omega), set by the
  // solver for each solve.
  double smoothing_omega() const { return omega_; }
  void set_smoothing_omega(double omega) { check_omega_range(omega); omega_ = omega; }
  std::size_t memory_bytes() const {
    return A_.memory_bytes() + sizeof(double) * (f_.size() + gap_.size() * 3 + fixed_dof_values_.size()) + row_flags_.size() +
           sizeof(special_[0]) * special_.size() +
           sizeof(Index) * (fixed_dofs_.size() + node_.size()) + sizeof(ColIndex) * contact_of_node_.size() + fixed_.size() +
           base_mask_.size();
  }

  // Tresca bounds in force: the coefficients (a Tresca law), or F |s_n| (Algorithm 1).
  void set_bounds_to_coefficients() { bound_ = coef_; }
  void set_bound(Index c, double s) { bound_[c] = s; }
  double coefficient(Index c) const { return coef_[c]; }

 private:
  __attribute__((noinline)) Mat<d> special_inverse(Index i) const {
    const auto it = std::lower_bound(special_.begin(), special_.end(), i, [](const auto& e, Index r) { return e.first < r; });
    return it->second;
  }

  void keep_special_inverses() {
    const Index n = A_.rows;
    const double thr = 1e-12 * max_diagonal<d>(A_);
    row_flags_.assign(n, 0);
    for (Index i : node_) row_flags_[i] |= kContactRow;
    special_.clear();
    std::uint8_t inert[d];
    for (Index i = 0; i < n; ++i) {
      const Mat<d> M = diagonal_block_inverse<d>(A_, i, thr, inert);
      bool plain = A_.diag[i] >= 0;
      for (int c = 0; c < d; ++c) plain = plain && !inert[c];
      if (plain) plain = M == Mat<d>(A_.block(A_.diag[i])).inverse();
      if (!plain) { row_flags_[i] |= kSpecialInverse; special_.emplace_back(i, M); }
    }
  }

  void eliminate_dirichlet(const double* values) {
    const Index n = A_.rows;
    std::vector<double> v(n * d, 0.0), Av(n * d);
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) v[k] = values[k];
    // energy offset: true energy = eliminated energy + const (for the history only)
    A_.multiply(v.data(), Av.data());
    energy_offset_ = 0;
    for (Index k = 0; k < n * d; ++k) energy_offset_ += 0.5 * v[k] * Av[k] - f_[k] * v[k] + 0.5 * v[k] * v[k];
    for (Index k = 0; k < n * d; ++k) f_[k] -= Av[k];
    for (Index i = 0; i < n; ++i)
      for (Index k = A_.indptr[i]; k < A_.indptr[i + 1]; ++k) {
        const Index j = A_.indices[k];
        auto B = A_.block(k);
        for (int a = 0; a < d; ++a) {
          if (fixed_[i * d + a]) B.row(a).setZero();
          if (fixed_[j * d + a]) B.col(a).setZero();
        }
        if (i == j)
          for (int a = 0; a < d; ++a)
            if (fixed_[i * d + a]) B(a, a) = 1;
      }
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) f_[k] = values[k];
  }

  BlockMatrix<d> A_;
  BasisTransform<d> T_;
  std::vector<double> f_, fixed_dof_values_;
  std::vector<std::uint8_t> row_flags_;           // RowFlag bits; kSpecialInverse: the row's inverse is in special_
  std::vector<std::pair<Index, Mat<d>>> special_;  // ascending rows
  std::vector<Index> fixed_dofs_;
  std::vector<std::uint8_t> fixed_, base_mask_;
  std::vector<Index> node_;
  std::vector<ColIndex> contact_of_node_;  // 32 bits: nodes fit a ColIndex (check_block_count)
  std::vector<double> gap_, coef_, bound_;
  std::vector<double> origin_;  // nc * d in the frames, empty without a previous step
  std::vector<TangentMask> free_;
  double energy_offset_ = 0;
  double omega_ = 1.0;
  static void check_omega_range(double omega) {
    if (!(omega > 0 && omega < 2)) throw InputError("the over-relaxation omega must lie in (0, 2)");
  }
};

}  // namespace cmg
