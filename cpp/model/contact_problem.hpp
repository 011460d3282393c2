// The fine level of a contact problem as the steps see it: the stiffness matrix and load in the
// basis of the nodal contact frames (BasisTransform), the Dirichlet dofs eliminated (identity rows
// and columns, the value on the right), and the data of every contact node. Built once; the
// iteration steps read it. What changes: the Tresca bounds of Algorithm 1, and between solves the
// load and the Dirichlet values of a load step (set_load, set_fixed_values: the right-hand side
// alone, the matrix and the fixed components stay).
#pragma once
#include "model/basis_transform.hpp"
#include "model/contact_frames.hpp"
#include "laws/contact_node.hpp"

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
    check_load(f);
    fixed_.assign(fixed, fixed + n * d);
    node_ = contact_nodes;
    gap_.assign(gaps, gaps + nc);
    coef_.assign(coefficients, coefficients + nc);
    bound_.assign(nc, 0.0);
    free_.assign(nc, all_tangents<d>());
    contact_of_node_.assign(n, -1);
    normals_.assign(normals, normals + nc * d);
    contact_fixed_.assign(nc * d, 0);
    if (frame_fixed) {
      frame_fixed_.assign(frame_fixed, frame_fixed + nc * d);
      frame_values_.assign(frame_values, frame_values + nc * d);
    }
    std::vector<Mat<d>> frames(nc);
    for (Index c = 0; c < nc; ++c) {
      const Index i = contact_nodes[c];
      if (i < 0 || i >= n) throw InputError("contact node " + std::to_string(i) + " is not a mesh node");
      if (contact_of_node_[i] >= 0) throw InputError("contact node " + std::to_string(i) + " is listed twice");
      if (!std::isfinite(gaps[c])) throw InputError("the gap of contact node " + std::to_string(i) + " is not finite");
      if (!(coefficients[c] >= 0) || !std::isfinite(coefficients[c]))
        throw InputError("the friction coefficient/bound of contact node " + std::to_string(i) + " must be finite and >= 0");
      contact_of_node_[i] = c;
      for (int a = 0; a < d; ++a) contact_fixed_[c * d + a] = fixed[i * d + a];
      double canonical[d];
      for (int a = 0; a < d; ++a) canonical[a] = fixed[i * d + a] ? fixed_values[i * d + a] : 0.0;
      const ContactDirichlet kind = classify_contact_dirichlet<d>(normals + c * d, gaps[c], fixed + i * d, canonical, i);
      if (kind == ContactDirichlet::Normal || kind == ContactDirichlet::Clamped)
        throw InputError("contact node " + std::to_string(i) + " has its " +
                         (kind == ContactDirichlet::Normal ? "normal component" : "every component") +
                         " prescribed by a Dirichlet condition: it is not a contact node");
      frames[c] = contact_frame<d>(normals + c * d, fixed + i * d, i);
      std::uint8_t lf[d];
      free_[c] = local_dirichlet(frames[c], c, fixed + i * d, lf);
      for (int a = 0; a < d; ++a) fixed_[i * d + a] = lf[a];
      if (frame_fixed)
        for (int a = 0; a < d; ++a)
          if (frame_fixed[c * d + a] && !std::isfinite(frame_values[c * d + a])) throw InputError("a Dirichlet value is not finite");
    }
    T_ = BasisTransform<d>(n, node_, std::move(frames));
    T_.transform_matrix(A_);
    keep_dirichlet_columns();
    eliminate_dirichlet_from_matrix();
    A_.find_diagonal();
    keep_special_inverses();
    base_mask_.assign(n * d, 1);
    for (Index k = 0; k < n * d; ++k) base_mask_[k] = fixed_[k] ? 0 : 1;
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) fixed_dofs_.push_back(k);
    fixed_dof_values_ = local_fixed_values(fixed_values);
    set_load(f);
  }

  // A new load (canonical, n * d) for the same matrix, Dirichlet values and contact data: the
  // state the constructor leaves with this load, bit for bit (a load step of a path).
  void set_load(const double* f) {
    check_load(f);
    f_.assign(f, f + A_.rows * d);
    T_.to_local(f_.data());
    for (std::size_t r = 0; r < coupled_rows_.size(); ++r)
      for (int a = 0; a < d; ++a) coupled_load_[r * d + a] = f_[coupled_rows_[r] * d + a];
    apply_dirichlet_values();
  }

  // New Dirichlet values (canonical, n * d; read on the fixed components only) for the same fixed
  // components: the state the constructor leaves with these values, bit for bit. The contact
  // nodes' frame values (frame_fixed) stay.
  void set_fixed_values(const double* fixed_values) {
    for (Index k = 0; k < A_.rows * d; ++k)
      if (canonical_fixed(k) && !std::isfinite(fixed_values[k])) throw InputError("a Dirichlet value is not finite");
    fixed_dof_values_ = local_fixed_values(fixed_values);
    apply_dirichlet_values();
  }

  Index num_nodes() const { return A_.rows; }
  Index num_contact() const { return (Index)node_.size(); }
  const BlockMatrix<d>& matrix() const { return A_; }
  const std::vector<double>& load() const { return f_; }
  // The inverse of the diagonal block of row i (invert_diagonal's): formed from the block itself in the
  // sweep -- the same bits as a stored one, and 16 bytes a dof less to hold and to stream
  // (docs/dev/decisions/0011-memory-release.md) -- except on the rows where it is not the plain inverse
  // (inert components, pseudo-inverses), kept here. (the lookup of a special row out of line, so that
  // the common case inlines into the sweep)
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
  // The previous step of a load path: friction acts on u_T - u_prev_T from now
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
  // Over-relaxation of the fine sweeps at nodes without contact (SolverOptions::omega), set by the
  // solver for each solve.
  std::size_t memory_bytes() const {
    return A_.memory_bytes() + sizeof(double) * (f_.size() + gap_.size() * 3 + fixed_dof_values_.size()) + row_flags_.size() +
           sizeof(special_[0]) * special_.size() +
           sizeof(Index) * (fixed_dofs_.size() + node_.size()) + sizeof(ColIndex) * contact_of_node_.size() + fixed_.size() +
           base_mask_.size() + coupling_.memory_bytes() +
           sizeof(double) * (normals_.size() + frame_values_.size() + coupled_load_.size()) + contact_fixed_.size() +
           frame_fixed_.size() + sizeof(Index) * coupled_rows_.size();
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

  void check_load(const double* f) const {
    for (Index k = 0; k < A_.rows * d; ++k)
      if (!std::isfinite(f[k])) throw InputError("the load vector has a non-finite entry");
  }

  // Whether canonical component k was given as fixed (the contact nodes' own mask is in their frames).
  bool canonical_fixed(Index k) const {
    const Index c = contact_of_node_[k / d];
    return c < 0 ? fixed_[k] != 0 : contact_fixed_[c * d + k % d] != 0;
  }

  // The components of contact node c fixed in its frame Q (lf) from its canonical fixed ones and
  // the frame_fixed ones; returns its free tangent mask.
  TangentMask local_dirichlet(const Mat<d>& Q, Index c, const std::uint8_t* fixed, std::uint8_t* lf) const {
    TangentMask free = all_tangents<d>();
    double unused[d] = {};
    for (int a = 0; a < d; ++a) lf[a] = 0;
    bool any = false;
    for (int a = 0; a < d; ++a) any = any || fixed[a];
    if (any) free = frame_dirichlet<d>(Q, fixed, unused, lf, unused);
    if (!frame_fixed_.empty())
      for (int a = 0; a < d; ++a)
        if (frame_fixed_[c * d + a] && !lf[a]) {  // a Dirichlet component keeps its own value
          lf[a] = 1;
          if (a > 0) free &= ~(1u << (a - 1));
        }
    return free;
  }

  // The value of every fixed dof (fixed_dofs_, local) from the canonical values: the canonical
  // value itself away from the contact nodes; in the frame of a contact node its tangential
  // Dirichlet value, or the frame value of a frame_fixed component. Throws for a prescribed
  // penetration.
  std::vector<double> local_fixed_values(const double* fixed_values) const {
    const Index n = A_.rows;
    std::vector<double> values(n * d, 0.0);
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k] && contact_of_node_[k / d] < 0) values[k] = fixed_values[k];
    for (Index c = 0; c < num_contact(); ++c) {
      const Index i = node_[c];
      const std::uint8_t* fixed = contact_fixed_.data() + c * d;
      double canonical[d];
      for (int a = 0; a < d; ++a) canonical[a] = fixed[a] ? fixed_values[i * d + a] : 0.0;
      const ContactDirichlet kind = classify_contact_dirichlet<d>(normals_.data() + c * d, gap_[c], fixed, canonical, i);
      if (kind == ContactDirichlet::Tangential) {
        std::uint8_t lf[d];
        double lv[d] = {};
        frame_dirichlet<d>(T_.block(c), fixed, canonical, lf, lv);
        for (int a = 0; a < d; ++a) values[i * d + a] = lf[a] ? lv[a] : 0.0;
        if (!frame_fixed_.empty())
          for (int a = 0; a < d; ++a)
            if (frame_fixed_[c * d + a] && !lf[a]) values[i * d + a] = frame_values_[c * d + a];
      } else if (!frame_fixed_.empty()) {
        for (int a = 0; a < d; ++a)
          if (frame_fixed_[c * d + a]) values[i * d + a] = frame_values_[c * d + a];
      }
    }
    std::vector<double> out(fixed_dofs_.size());
    for (std::size_t m = 0; m < fixed_dofs_.size(); ++m) out[m] = values[fixed_dofs_[m]];
    return out;
  }

  // The rows coupled to a Dirichlet dof and their blocks in the columns of nodes with a fixed
  // dof (T^T A T before the elimination): what the elimination takes from the right-hand side.
  void keep_dirichlet_columns() {
    const Index n = A_.rows;
    std::vector<std::uint8_t> fixed_node(n, 0);
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) fixed_node[k / d] = 1;
    coupling_ = BlockMatrix<d>();
    coupling_.cols = n;
    coupling_.indptr.push_back(0);
    coupled_rows_.clear();
    for (Index i = 0; i < n; ++i) {
      Index kept = 0;
      for (Index k = A_.indptr[i]; k < A_.indptr[i + 1]; ++k) {
        if (!fixed_node[A_.indices[k]]) continue;
        coupling_.indices.push_back(A_.indices[k]);
        coupling_.values.insert(coupling_.values.end(), A_.values.begin() + k * d * d, A_.values.begin() + (k + 1) * d * d);
        ++kept;
      }
      if (!kept) continue;
      coupled_rows_.push_back(i);
      coupling_.indptr.push_back((Index)coupling_.indices.size());
    }
    coupling_.rows = (Index)coupled_rows_.size();
    coupled_load_.assign(coupled_rows_.size() * d, 0.0);
  }

  // Dirichlet rows and columns of A become identity rows and columns.
  void eliminate_dirichlet_from_matrix() {
    const Index n = A_.rows;
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
  }

  // f <- f - A v on the rows coupled to the Dirichlet dofs (v: the Dirichlet values, 0 elsewhere),
  // the value itself on a Dirichlet row, from the load the rows had before (coupled_load_). The
  // blocks of the other columns would add exact zeros, so a product over the kept columns gives
  // the bits of the full one.
  void apply_dirichlet_values() {
    const Index n = A_.rows;
    std::vector<double> v(n * d, 0.0);
    for (std::size_t m = 0; m < fixed_dofs_.size(); ++m) v[fixed_dofs_[m]] = fixed_dof_values_[m];
    std::vector<double> Av(n * d, 0.0);
    for (std::size_t r = 0; r < coupled_rows_.size(); ++r) {
      double s[d] = {};
      accumulate_blocks<d, false>(coupling_.values.data(), coupling_.indices.data(), coupling_.indptr[r], coupling_.indptr[r + 1],
                                  v.data(), s);
      for (int a = 0; a < d; ++a) Av[coupled_rows_[r] * d + a] = s[a];
    }
    // energy offset: true energy = eliminated energy + const (for the history only)
    energy_offset_ = 0;
    for (Index k : fixed_dofs_) {
      const Index r = row_of_coupled(k / d);
      const double fk = coupled_load_[r * d + k % d];
      energy_offset_ += 0.5 * v[k] * Av[k] - fk * v[k] + 0.5 * v[k] * v[k];
    }
    for (std::size_t r = 0; r < coupled_rows_.size(); ++r)
      for (int a = 0; a < d; ++a) {
        const Index k = coupled_rows_[r] * d + a;
        f_[k] = coupled_load_[r * d + a] - Av[k];
      }
    for (std::size_t m = 0; m < fixed_dofs_.size(); ++m) f_[fixed_dofs_[m]] = fixed_dof_values_[m];
  }

  // position of row i in coupled_rows_ (i is one)
  Index row_of_coupled(Index i) const {
    return Index(std::lower_bound(coupled_rows_.begin(), coupled_rows_.end(), i) - coupled_rows_.begin());
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
  // what set_load and set_fixed_values need: the contact nodes' normals, canonical fixed
  // components and frame-fixed data (nc * d), the Dirichlet columns and the load of their rows
  std::vector<double> normals_, frame_values_;
  std::vector<std::uint8_t> contact_fixed_, frame_fixed_;
  BlockMatrix<d> coupling_;
  std::vector<Index> coupled_rows_;
  std::vector<double> coupled_load_;
  std::vector<TangentMask> free_;
  double energy_offset_ = 0;
};

}  // namespace cmg
