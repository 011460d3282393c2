// The fine level of the contact problem and the algorithms on top of it:
//  - linear multigrid (Law::Linear),
//  - truncated monotone multigrid for frictionless and Tresca contact,
//  - Algorithm 2 of the paper (nonlinear multigrid for Coulomb friction, no outer loop),
//  - Algorithm 1 (fixed point in the normal stresses, each step a Tresca problem).
// Contact nodes work in their frames Q_p = [n, t(, s)]; Dirichlet dofs are eliminated.
#pragma once
#include <chrono>
#include <cstdio>
#include <cmath>
#include <functional>
#include <limits>
#include "coarse_correction.hpp"
#include "nodal_solver.hpp"

namespace cmg {

enum class Law : int { Linear = 0, Frictionless = 1, Tresca = 2, Coulomb = 3 };

struct SolveOptions {
  double tol = 1e-11;    // stop when ||u^{k+1} - u^k||_A <= tol
  double rtol = 0;       // ... or <= rtol * (the first cycle's correction norm)
  int max_cycles = 200;  // per solve (per Tresca solve inside the fixed point)
  double fixed_point_tol = 1e-9;
  int fixed_point_max = 100;
  double divergence_factor = 1e8;  // a correction this much larger than the first one: diverged
  const double* reference = nullptr;  // canonical u*: record ||u - u*||_A per cycle (costs a matvec)
};

struct CycleRecord {
  int cycle = 0, outer = 0;
  double correction_norm = 0, energy = 0, seconds = 0;
  double error = std::numeric_limits<double>::quiet_NaN();  // ||u - u*||_A when a reference is given
  Index active = 0, stick = 0, slip = 0;
  bool rebuilt = false;
};

struct SolveResult {
  std::vector<double> u;               // displacement, canonical frame, n * d
  std::vector<double> contact_force;   // (A u - f) at contact nodes in their frames, nc * d
  std::vector<double> friction_bound;  // the bound s of each contact node at the end
  std::vector<std::int8_t> state;      // contact nodes: 0 free, 1 stick, 2 slip
  std::vector<CycleRecord> history;
  bool converged = false;
  std::string status;
  int cycles = 0, outer_iterations = 0, rebuilds = 0;
  double seconds = 0, rebuild_seconds = 0;
  double sweep_check = std::numeric_limits<double>::quiet_NaN();  // ||S(u) - u||_A at the stop
  std::vector<double> phase_seconds;  // indexed by Phase
};

// A stop on the correction norm is confirmed only if one more smoothing sweep moves the iterate by
// at most this many times the tolerance (a sweep changes a converged iterate by about its error,
// which is below the last correction; a limit cycle moves it by orders of magnitude more).
constexpr double kSweepCheckFactor = 100;

// Orthonormal frame with first column n: 2D t = n rotated by +90 degrees; 3D t orthogonal to n
// built from the canonical axis least aligned with n, s = n x t.
template <int d>
Mat<d> frame_from_normal(const double* nrm, Index c) {
  Vec<d> n = CVecMap<d>(nrm);
  const double len = n.norm();
  if (!(len > 1e-12) || !std::isfinite(len))
    throw InputError("contact normal " + std::to_string(c) + " is zero or not finite");
  n /= len;
  Mat<d> Q;
  Q.col(0) = n;
  if constexpr (d == 2) {
    Q(0, 1) = -n[1];
    Q(1, 1) = n[0];
  } else {
    Index k;
    n.cwiseAbs().minCoeff(&k);
    Vec<d> e = Vec<d>::Zero();
    e[k] = 1;
    Vec<d> t = n.cross(e).normalized();
    Q.col(1) = t;
    Q.col(2) = n.cross(t);
  }
  return Q;
}

// Where a solve spends its time (SolveResult::phase_seconds): a handful of clock reads per cycle.
enum class Phase : int { PreSmooth, Linearize, CoarseUpdate, CoarseCorrection, PostSmooth, Norm, Check, Count };
inline const char* phase_name(int p) {
  static const char* names[] = {"presmooth", "linearize", "coarse_update", "coarse_correction", "postsmooth", "norm", "check"};
  return names[p];
}
struct PhaseClock {
  using clock = std::chrono::steady_clock;
  double* acc;
  clock::time_point t = clock::now();
  explicit PhaseClock(double* a) : acc(a) {}
  void lap(Phase p) {
    const auto now = clock::now();
    acc[(int)p] += std::chrono::duration<double>(now - t).count();
    t = now;
  }
};

template <int d>
class ContactSolver {
 public:
  struct Transfer {  // interpolation weights of one refinement step
    Index n_fine, n_coarse;
    std::vector<Index> ptr, parent;
    std::vector<double> weight;
  };

  ContactSolver(const BlockMatrix<d>& A, const double* f, const std::uint8_t* fixed, const double* fixed_values,
                const std::vector<Index>& contact_nodes, const double* normals, const double* gaps, const double* coefficients,
                Law law, const std::vector<Transfer>& transfers, CycleOptions cyc)
      : law_(law), A_(A), cc_(make_transfers(A, contact_nodes, normals, transfers), cyc), cyc_(cyc) {
    const Index n = A.rows;
    const Index nc = (Index)contact_nodes.size();
    f_.assign(f, f + n * d);
    fixed_.assign(fixed, fixed + n * d);
    contact_node_ = contact_nodes;
    gap_.assign(gaps, gaps + nc);
    coef_.assign(coefficients, coefficients + nc);
    bound_.assign(nc, 0.0);
    contact_of_node_.assign(n, -1);
    frames_.resize(nc);
    for (Index c = 0; c < nc; ++c) {
      const Index i = contact_nodes[c];
      if (i < 0 || i >= n) throw InputError("contact node " + std::to_string(i) + " is not a mesh node");
      if (contact_of_node_[i] >= 0) throw InputError("contact node " + std::to_string(i) + " is listed twice");
      if (!std::isfinite(gaps[c])) throw InputError("the gap of contact node " + std::to_string(i) + " is not finite");
      if (!(coefficients[c] >= 0) || !std::isfinite(coefficients[c]))
        throw InputError("the friction coefficient/bound of contact node " + std::to_string(i) + " must be finite and >= 0");
      for (int a = 0; a < d && law != Law::Linear; ++a)
        if (fixed[i * d + a])
          throw InputError("contact node " + std::to_string(i) + " also carries a Dirichlet condition");
      contact_of_node_[i] = c;
      frames_[c] = frame_from_normal<d>(normals + c * d, c);
    }
    for (Index k = 0; k < n * d; ++k)
      if (fixed[k] && !std::isfinite(fixed_values[k])) throw InputError("a Dirichlet value is not finite");
    for (Index k = 0; k < n * d; ++k)
      if (!std::isfinite(f[k])) throw InputError("the load vector has a non-finite entry");
    to_local_frames();
    eliminate_dirichlet(fixed_values);
    A_.find_diagonal();
    invert_diagonal<d>(A_, Dinv_, inert_, max_diagonal<d>(A_));
    base_mask_.assign(n * d, 1);
    for (Index k = 0; k < n * d; ++k) base_mask_[k] = fixed_[k] ? 0 : 1;
    mask_ = base_mask_;
    cc_.rebuild(A_, mask_.data());
    built_mask_ = mask_;
    u_.assign(n * d, 0.0);
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) u_[k] = fixed_values[k];
    fixed_values_ = u_;
    Au_.assign(n * d, 0.0); r_.assign(n * d, 0.0); tmp_.assign(n * d, 0.0); old_.assign(n * d, 0.0);
    lo_.assign(n * d, -kInf); hi_.assign(n * d, kInf);
  }

  Index num_nodes() const { return A_.rows; }
  Index num_contact() const { return (Index)contact_node_.size(); }
  const CoarseCorrection<d>& coarse() const { return cc_; }
  const BlockMatrix<d>& fine_matrix() const { return A_; }
  std::size_t memory_bytes() const {
    return A_.memory_bytes() + cc_.memory_bytes() + sizeof(double) * (Dinv_.size() + 9 * u_.size());
  }
  // Full Galerkin rebuild for the current truncation (diagnostics: compare with the incremental one).
  void rebuild_coarse() { cc_.rebuild(A_, built_mask_.data()); }
  void set_interrupt_check(std::function<bool()> f) { interrupted_ = std::move(f); }
  void set_tresca_bounds(const double* s) {
    for (Index c = 0; c < num_contact(); ++c) {
      if (!(s[c] >= 0) || !std::isfinite(s[c])) throw InputError("Tresca bounds must be finite and >= 0");
      bound_[c] = s[c];
    }
  }
  void set_coefficients(const double* F) {
    for (Index c = 0; c < num_contact(); ++c) {
      if (!(F[c] >= 0) || !std::isfinite(F[c])) throw InputError("friction coefficients must be finite and >= 0");
      coef_[c] = F[c];
    }
  }

  // Runs the method of the solver's law from u0 (canonical; nullptr = 0).
  SolveResult solve(const double* u0, const SolveOptions& opt) {
    start(u0);
    SolveResult R;
    const auto t0 = clock::now();
    switch (law_) {
      case Law::Linear: iterate<Law::Linear>(opt, R, 0, t0); break;
      case Law::Frictionless: iterate<Law::Frictionless>(opt, R, 0, t0); break;
      case Law::Tresca:
        for (Index c = 0; c < num_contact(); ++c) bound_[c] = coef_[c];
        iterate<Law::Tresca>(opt, R, 0, t0);
        break;
      case Law::Coulomb: iterate<Law::Coulomb>(opt, R, 0, t0); break;
    }
    finish(R, t0);
    return R;
  }

  // `sweeps` nonlinear Gauss-Seidel sweeps of the solver's law from u0 (canonical), alternating
  // direction starting forward; returns the canonical iterate. A solution is a fixed point of this
  // map (the nodal rules keep every local solution), so it serves as an independent check.
  std::vector<double> smooth(const double* u0, int sweeps) {
    start(u0);
    if (law_ == Law::Tresca) bound_ = coef_;
    for (int k = 0; k < sweeps; ++k) {
      const bool fw = k % 2 == 0;
      switch (law_) {
        case Law::Linear: sweep<Law::Linear>(fw); break;
        case Law::Frictionless: sweep<Law::Frictionless>(fw); break;
        case Law::Tresca: sweep<Law::Tresca>(fw); break;
        case Law::Coulomb: sweep<Law::Coulomb>(fw); break;
      }
    }
    std::vector<double> u = u_;
    for (Index c = 0; c < num_contact(); ++c) {
      VecMap<d> ui(u.data() + contact_node_[c] * d);
      ui = frames_[c] * Vec<d>(ui);
    }
    return u;
  }

  // Algorithm 1: u^k solves the Tresca problem with s = F |s_n(u^{k-1})| (warm-started from u^{k-1}).
  SolveResult solve_fixed_point(const double* u0, const SolveOptions& opt) {
    if (law_ != Law::Coulomb) throw InputError("the fixed-point iteration needs a Coulomb friction law");
    start(u0);
    SolveResult R;
    const auto t0 = clock::now();
    const Index nc = num_contact();
    std::vector<double> sn_prev(nc), sn(nc);
    normal_stress(sn_prev);
    for (int k = 1; k <= opt.fixed_point_max; ++k) {
      for (Index c = 0; c < nc; ++c) bound_[c] = coef_[c] * std::abs(sn_prev[c]);
      R.outer_iterations = k;
      if (!iterate<Law::Tresca>(opt, R, k, t0)) {
        R.status = "the Tresca solve of outer iteration " + std::to_string(k) + " did not converge: " + R.status;
        R.converged = false;
        finish(R, t0);
        return R;
      }
      normal_stress(sn);
      double diff = 0, nrm = 0;
      for (Index c = 0; c < nc; ++c) { diff += (sn[c] - sn_prev[c]) * (sn[c] - sn_prev[c]); nrm += sn[c] * sn[c]; }
      if (std::sqrt(diff) <= opt.fixed_point_tol * std::sqrt(nrm)) {
        R.converged = true;
        R.status = "converged";
        finish(R, t0);
        return R;
      }
      sn_prev = sn;
    }
    R.converged = false;
    R.status = "no convergence of the fixed-point iteration in " + std::to_string(opt.fixed_point_max) + " outer iterations";
    finish(R, t0);
    return R;
  }

 private:
  using clock = std::chrono::steady_clock;

  static std::vector<BlockMatrix<d>> make_transfers(const BlockMatrix<d>& A, const std::vector<Index>& nodes,
                                                    const double* normals, const std::vector<Transfer>& T) {
    std::vector<BlockMatrix<d>> P;
    const Index nc = (Index)nodes.size();
    std::vector<double> frames(nc * d * d);
    for (Index c = 0; c < nc; ++c) MatMap<d>(frames.data() + c * d * d) = frame_from_normal<d>(normals + c * d, c);
    for (std::size_t l = 0; l < T.size(); ++l) {
      const bool fine = l + 1 == T.size();
      if (l > 0 && T[l].n_coarse != T[l - 1].n_fine) throw InputError("prolongations do not chain: level sizes differ");
      if (fine && T[l].n_fine != A.rows) throw InputError("the finest prolongation does not match the matrix size");
      if ((Index)T[l].ptr.size() != T[l].n_fine + 1) throw InputError("prolongation pointer array has the wrong length");
      P.push_back(make_prolongation<d>(T[l].n_fine, T[l].n_coarse, T[l].ptr.data(), T[l].parent.data(), T[l].weight.data(),
                                       fine ? nodes.data() : nullptr, fine ? frames.data() : nullptr, fine ? nc : 0));
    }
    return P;
  }

  void to_local_frames() {
    for (Index i = 0; i < A_.rows; ++i) {
      const Index ci = contact_of_node_[i];
      for (Index k = A_.indptr[i]; k < A_.indptr[i + 1]; ++k) {
        const Index cj = contact_of_node_[A_.indices[k]];
        Mat<d> B = A_.block(k);
        if (ci >= 0) B = frames_[ci].transpose() * B;
        if (cj >= 0) B = B * frames_[cj];
        A_.block(k) = B;
      }
      if (ci >= 0) VecMap<d>(f_.data() + i * d) = frames_[ci].transpose() * CVecMap<d>(f_.data() + i * d);
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

  void start(const double* u0) {
    const Index n = A_.rows;
    rebuilds0_ = cc_.rebuilds();
    untimed_ = 0;
    std::fill(std::begin(phase_), std::end(phase_), 0.0);
    rebuild_seconds0_ = cc_.rebuild_seconds();
    if (u0) {
      for (Index k = 0; k < n * d; ++k)
        if (!std::isfinite(u0[k])) throw InputError("the initial guess has a non-finite entry");
      u_.assign(u0, u0 + n * d);
      for (Index c = 0; c < num_contact(); ++c) {
        VecMap<d> ui(u_.data() + contact_node_[c] * d);
        ui = frames_[c].transpose() * Vec<d>(ui);
      }
    } else {
      std::fill(u_.begin(), u_.end(), 0.0);
    }
    for (Index k = 0; k < n * d; ++k)
      if (fixed_[k]) u_[k] = fixed_values_[k];
    A_.multiply(u_.data(), Au_.data());
  }

  // ||u - u*||_A with u* canonical (taken to the contact frames first); outside the timing.
  double error_against(const double* ref) {
    const Index n = A_.rows;
    for (Index k = 0; k < n * d; ++k) old_[k] = fixed_[k] ? 0.0 : u_[k] - ref[k];
    for (Index c = 0; c < num_contact(); ++c) {
      const Index i = contact_node_[c];
      const Vec<d> r = frames_[c].transpose() * CVecMap<d>(ref + i * d);
      for (int a = 0; a < d; ++a) old_[i * d + a] = fixed_[i * d + a] ? 0.0 : u_[i * d + a] - r[a];
    }
    A_.multiply(old_.data(), tmp_.data());
    double e = 0;
    for (Index k = 0; k < n * d; ++k) e += old_[k] * tmp_[k];
    return std::sqrt(std::max(e, 0.0));
  }

  // s_n = (A u - f)_n at the contact nodes, from the tracked A u
  void normal_stress(std::vector<double>& sn) const {
    for (Index c = 0; c < num_contact(); ++c) {
      const Index k = contact_node_[c] * d;
      sn[c] = Au_[k] - f_[k];
    }
  }

  template <Law L>
  void sweep(bool forward) {
    const Index n = A_.rows;
    double* u = u_.data();
    for (Index ii = 0; ii < n; ++ii) {
      const Index i = forward ? ii : n - 1 - ii;
      const Vec<d> b = local_rhs<d>(A_, u, f_.data(), i);
      VecMap<d> ui(u + d * i);
      const Index c = (L == Law::Linear) ? -1 : contact_of_node_[i];
      if (c < 0) {
        ui = CMatMap<d>(Dinv_.data() + i * d * d) * b;
        continue;
      }
      const Mat<d> B = A_.block(A_.diag[i]);
      if constexpr (L == Law::Frictionless) ui = solve_node_tresca<d>(B, b, gap_[c], 0.0);
      else if constexpr (L == Law::Tresca) ui = solve_node_tresca<d>(B, b, gap_[c], bound_[c]);
      else if constexpr (L == Law::Coulomb) ui = solve_node_coulomb<d>(B, b, gap_[c], coef_[c], Vec<d>(ui));
    }
  }

  // The smooth neighbourhood of the smoothed iterate: truncation mask (active normals, sticking
  // tangentials), correction bounds (inactive normals, sign of sliding tangentials) and the friction
  // gradient of sliding nodes added to the residual r. Returns whether any bound is finite.
  template <Law L>
  bool linearize() {
    if constexpr (L == Law::Linear) return false;
    bool bounded = false;
    for (Index c = 0; c < num_contact(); ++c) {
      const Index i = contact_node_[c], k = i * d;
      const double* u = u_.data() + k;
      for (int a = 0; a < d; ++a) { mask_[k + a] = 1; lo_[k + a] = -kInf; hi_[k + a] = kInf; }
      const bool active = u[0] >= gap_[c];
      if (active) mask_[k] = 0;
      else { hi_[k] = gap_[c] - u[0]; bounded = true; }
      double s = 0;
      if constexpr (L == Law::Tresca) s = bound_[c];
      if constexpr (L == Law::Coulomb) s = active ? coef_[c] * std::max(0.0, r_[k]) : 0.0;  // s_n = -r_n
      if (s <= 0) continue;
      double ut = 0;
      for (int a = 1; a < d; ++a) ut += u[a] * u[a];
      ut = std::sqrt(ut);
      if (ut == 0) {
        for (int a = 1; a < d; ++a) mask_[k + a] = 0;
        continue;
      }
      for (int a = 1; a < d; ++a) {
        r_[k + a] -= s * u[a] / ut;
        if (u[a] > 0) { lo_[k + a] = -u[a]; bounded = true; }
        else if (u[a] < 0) { hi_[k + a] = -u[a]; bounded = true; }
      }
    }
    return bounded;
  }

  // One cycle: pre-smoothing, coarse correction of the linearized problem, post-smoothing.
  // Returns ||u_new - u_old||_A.
  template <Law L>
  double cycle(bool& rebuilt) {
    PhaseClock pc(phase_);
    old_ = u_;
    for (int s = 0; s < cyc_.nu1; ++s) sweep<L>(true);
    pc.lap(Phase::PreSmooth);
    A_.multiply(u_.data(), r_.data());
    for (std::size_t k = 0; k < r_.size(); ++k) r_[k] = f_[k] - r_[k];
    const bool bounded = linearize<L>();
    pc.lap(Phase::Linearize);
    rebuilt = mask_ != built_mask_;
    if (rebuilt) {
      cc_.update(A_, built_mask_.data(), mask_.data());
      built_mask_ = mask_;
    }
    pc.lap(Phase::CoarseUpdate);
    cc_.apply(r_.data(), mask_.data(), lo_.data(), hi_.data(), bounded, u_.data());
    pc.lap(Phase::CoarseCorrection);
    for (int s = 0; s < cyc_.nu2; ++s) sweep<L>(false);
    pc.lap(Phase::PostSmooth);
    for (std::size_t k = 0; k < u_.size(); ++k) old_[k] = u_[k] - old_[k];
    A_.multiply(old_.data(), tmp_.data());
    double e = 0;
    for (std::size_t k = 0; k < u_.size(); ++k) { e += old_[k] * tmp_[k]; Au_[k] += tmp_[k]; }
    pc.lap(Phase::Norm);
    return std::sqrt(std::max(e, 0.0));
  }


  template <Law L>
  void record(CycleRecord& rec) const {
    double e = energy_offset_;
    for (std::size_t k = 0; k < u_.size(); ++k) e += 0.5 * u_[k] * Au_[k] - f_[k] * u_[k];
    for (Index c = 0; c < num_contact() && L != Law::Linear; ++c) {
      const Index k = contact_node_[c] * d;
      double ut = 0;
      for (int a = 1; a < d; ++a) ut += u_[k + a] * u_[k + a];
      ut = std::sqrt(ut);
      const bool active = u_[k] >= gap_[c];
      double s = 0;
      if (L == Law::Tresca) s = bound_[c];
      if (L == Law::Coulomb && active) s = coef_[c] * std::max(0.0, f_[k] - Au_[k]);
      e += s * ut;
      if (active) { ++rec.active; (ut == 0 ? rec.stick : rec.slip)++; }
    }
    rec.energy = e;
  }

  // Cycles until the correction norm drops below the tolerance. Returns whether it converged.
  template <Law L>
  bool iterate(const SolveOptions& opt, SolveResult& R, int outer, clock::time_point t0) {
    double first = -1;
    R.status = "no convergence in " + std::to_string(opt.max_cycles) + " cycles";
    for (int it = 1; it <= opt.max_cycles; ++it) {
      if (interrupted_ && interrupted_()) throw Interrupted();
      CycleRecord rec;
      rec.correction_norm = cycle<L>(rec.rebuilt);
      rec.cycle = ++R.cycles;
      rec.outer = outer;
      record<L>(rec);
      rec.seconds = std::chrono::duration<double>(clock::now() - t0).count() - untimed_;
      if (opt.reference) {
        const auto te = clock::now();
        rec.error = error_against(opt.reference);
        untimed_ += std::chrono::duration<double>(clock::now() - te).count();
      }
      R.history.push_back(rec);
      const double cn = rec.correction_norm;
      if (first < 0) first = cn;
      if (!std::isfinite(cn) || (cn > opt.divergence_factor * first && first > 0)) {
        R.status = std::isfinite(cn)
                       ? "diverged: correction norm " + fmt(cn) + " at cycle " + std::to_string(it) + ", " +
                             fmt(cn / first) + " times the first"
                       : "diverged: the iterate is no longer finite at cycle " + std::to_string(it) +
                             " (overflow: are the load and the material of sensible magnitude?)";
        R.converged = false;
        return false;
      }
      if (cn <= opt.tol || cn <= opt.rtol * first) {
        // The stopping test cannot tell a solution from an iterate that the cycle maps back onto
        // itself while the smoother keeps moving it (a limit cycle of the nonlinear Gauss-Seidel,
        // seen for Coulomb at large F). A solution is a fixed point of one sweep: check that.
        if constexpr (L != Law::Linear) {
          PhaseClock pc(phase_);
          R.sweep_check = sweep_change<L>();
          pc.lap(Phase::Check);
        }
        const double allowed = kSweepCheckFactor * std::max(opt.tol, opt.rtol * first);
        if (R.sweep_check > allowed) {
          R.converged = false;
          R.status = "stalled: the cycle returns to an iterate (correction " + fmt(cn) +
                     ") that one more smoothing sweep still moves by " + fmt(R.sweep_check) +
                     " (energy norm): a limit cycle of the nonlinear smoother, not a solution";
          return false;
        }
        R.converged = true;
        R.status = "converged";
        return true;
      }
    }
    R.converged = false;
    return false;
  }

  static std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
  }

  // ||S(u) - u||_A for one forward nonlinear sweep S; u is left as it was.
  template <Law L>
  double sweep_change() {
    old_ = u_;
    sweep<L>(true);
    for (std::size_t k = 0; k < u_.size(); ++k) std::swap(u_[k], old_[k]);
    for (std::size_t k = 0; k < u_.size(); ++k) old_[k] -= u_[k];
    A_.multiply(old_.data(), tmp_.data());
    double e = 0;
    for (std::size_t k = 0; k < u_.size(); ++k) e += old_[k] * tmp_[k];
    return std::sqrt(std::max(e, 0.0));
  }

  void finish(SolveResult& R, clock::time_point t0) {
    const Index n = A_.rows, nc = num_contact();
    R.seconds = std::chrono::duration<double>(clock::now() - t0).count() - untimed_;
    R.rebuilds = cc_.rebuilds() - rebuilds0_;
    R.rebuild_seconds = cc_.rebuild_seconds() - rebuild_seconds0_;
    R.phase_seconds.assign(std::begin(phase_), std::end(phase_));
    R.u = u_;
    R.contact_force.assign(nc * d, 0.0);
    R.friction_bound.assign(nc, 0.0);
    R.state.assign(nc, 0);
    for (Index c = 0; c < nc; ++c) {
      const Index k = contact_node_[c] * d;
      double ut = 0;
      for (int a = 0; a < d; ++a) R.contact_force[c * d + a] = Au_[k + a] - f_[k + a];
      for (int a = 1; a < d; ++a) ut += u_[k + a] * u_[k + a];
      const bool active = u_[k] >= gap_[c];
      R.state[c] = active ? (ut == 0 ? 1 : 2) : 0;
      if (law_ == Law::Tresca) R.friction_bound[c] = bound_[c];
      if (law_ == Law::Coulomb) R.friction_bound[c] = active ? coef_[c] * std::max(0.0, f_[k] - Au_[k]) : 0.0;
      VecMap<d> ui(R.u.data() + contact_node_[c] * d);
      ui = frames_[c] * Vec<d>(ui);
    }
    (void)n;
  }

  Law law_;
  BlockMatrix<d> A_;
  CoarseCorrection<d> cc_;
  CycleOptions cyc_;
  std::vector<double> f_, Dinv_, u_, Au_, r_, tmp_, old_, lo_, hi_, fixed_values_;
  std::vector<std::uint8_t> inert_, fixed_, base_mask_, mask_, built_mask_;
  std::vector<Index> contact_node_, contact_of_node_;
  std::vector<double> gap_, coef_, bound_;
  std::vector<Mat<d>> frames_;
  double energy_offset_ = 0;
  double phase_[(int)Phase::Count] = {};
  double untimed_ = 0;  // seconds spent on error recording, kept out of the timings
  int rebuilds0_ = 0;
  double rebuild_seconds0_ = 0;
  std::function<bool()> interrupted_;
};

}  // namespace cmg
