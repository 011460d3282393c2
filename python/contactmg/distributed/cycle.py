"""The truncated monotone multigrid cycle on MPI ranks: the serial cycle's steps (steps/
monotone_mg_step.hpp, mg/cycle.hpp) with each rank doing them on its owned rows and a ghost exchange
where a row reads a neighbour's new value.

- A Gauss-Seidel sweep runs colour by colour (colours of the hashed greedy rule, the same on any
  number of ranks), the owned rows of a colour by the core's kernels, then one halo exchange.
- Restriction: the owners of the fine rows form the residual, the ghosts get it, and the owner of a
  coarse row sums its fine rows in ascending local index (a global order: hierarchy.py). Bounds restrict by minima and maxima (exact).
- Prolongation: every local row (ghost rows are their owners' rows), so no exchange is needed.
- Galerkin rows by their owners (operators.py), rebuilt when the truncation or a Hessian changes,
  only the rows whose inputs changed.
- The kernels of a coarse level (Galerkin rows, residual, restriction, prolongation, bounds) are the
  core's (cpp/mg/distributed_galerkin.hpp); the recursion that orders them is the serial cycle's
  (cpp/mg/cycle_recursion.hpp, through _core.multigrid_cycle), and this module gives it the level
  operations with their exchanges.
- The coarsest level gathered and solved on every rank; its bounded correction is the serial one
  (cpp/mg/bounded_coarsest.hpp).
- The loop, its stop and the Anderson rule of the settled cycles are the core's too
  (_core.run_loop; SettledAnderson settle).
- Norms and energies by exact sums: each owned node's value (its products summed in a fixed order)
  summed exactly over the ranks (exchange.node_dots). A u is kept and updated in the pass that
  measures the step, as the serial step does.

So every value is the same on every number of ranks: the iterates, cycle counts and norms are
bitwise those of one rank."""
from __future__ import annotations

import time
from typing import List, Optional

import numpy as np
import scipy.sparse as sp

from .. import _core
from .colouring import colour_level
from .comm import is_serial, op
from .exchange import exact_sum, exact_totals, node_dots
from .operators import (GatheredCoarsest, galerkin_rows, local_transfer, rotate_rows, rows_to_csr,
                        transfer_kernel)
from .replicated import Whole, replicated_count

INF = np.inf


def _any(comm, flag: bool) -> bool:
    return bool(flag) if is_serial(comm) else bool(comm.allreduce(int(bool(flag)), op=op(comm, "MAX")))


def _colour_rows(comm, level) -> List[np.ndarray]:
    """The owned rows of each colour, with the number of colours the largest over the ranks."""
    colour = level.colour if level.colour is not None else colour_level(level, comm)
    owned = level.owner == level.rank
    ncol = int(colour.max(initial=-1)) + 1
    if not is_serial(comm):
        ncol = comm.allreduce(ncol, op=op(comm, "MAX"))
    return [np.flatnonzero(owned & (colour == c)).astype(np.int64) for c in range(ncol)]


def _split(colours: List[np.ndarray], reads_ghost: np.ndarray) -> List[tuple]:
    """Each colour's rows as (those that read no ghost, those that do): the first are swept while the
    ghosts of the colour before are on their way."""
    return [(rows[~reads_ghost[rows]], rows[reads_ghost[rows]]) for rows in colours]


def _overlapped_sweep(split, forward: bool, sweep_rows, start) -> None:
    """One coloured pass with the exchanges overlapped: per colour the rows that read no ghost, the
    ghosts of the colour before written, the rows that read ghosts, the exchange begun. Rows of one
    colour do not read each other, so the values are those of the plain pass."""
    pending = None
    for interior, boundary in (split if forward else split[::-1]):
        sweep_rows(interior)
        if pending is not None:
            pending.finish()
        sweep_rows(boundary)
        pending = start()
    if pending is not None:
        pending.finish()


class CoarseLevel:
    """A coarse level on one rank: its nodes, colours, its rows and smoother (the core's CoarseRows,
    written in place by the Galerkin kernel), the transfer from the level below (the core's
    DistributedTransfer) and the vectors of the cycle."""

    def __init__(self, comm, level, below, d: int, threads: int = 1):
        self.comm, self.level, self.d, self.threads = comm, level, d, threads
        self.n = len(level.gid)
        self.owned = level.owner == level.rank
        self.owned_u8 = self.owned.astype(np.uint8)
        self.halo = None if is_serial(comm) else level.halo  # one rank: no ghosts, nothing to exchange
        self.colours = _colour_rows(comm, level) if below is not None else []  # the coarsest is solved, not swept
        # without exchanges between the colours (and on one thread) a pass is one call over the
        # colours in turn: the same rows in the same order (reversed backward), without a call per colour
        self.order = None if self.halo is not None or threads > 1 else \
            np.concatenate(self.colours or [np.zeros(0, np.int64)])
        self.rows = (_core.CoarseRows2D if d == 2 else _core.CoarseRows3D)()
        self.split = None  # each colour's rows that read no ghost and those that do
        self.transfer = None  # from the level below
        if below is not None:
            self.transfer = transfer_kernel(local_transfer(level, below, d, comm), level, below, d)
        self.x = np.zeros((self.n, d))
        self.b = np.zeros((self.n, d))
        self.lo = np.full((self.n, d), -INF)
        self.hi = np.full((self.n, d), INF)
        self.bounded = np.zeros(self.n, np.uint8)
        self.any_bounds = False

    def refresh(self) -> None:
        """The smoother's diagonal inverses after the rows changed (the inert threshold relative to the
        largest diagonal entry of the whole level, the same on every rank)."""
        scale = self.rows.max_diagonal(self.owned_u8)
        if not is_serial(self.comm):
            scale = self.comm.allreduce(scale, op=op(self.comm, "MAX"))
        self.rows.invert(scale)

    def set_bounds(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Restricted bounds: the owned rows' are complete, the ghosts' from their owners."""
        self.lo, self.hi = lo, hi
        if self.halo is not None:
            self.halo.update_many(lo, hi)

    def clear_bounds(self) -> None:
        """No bounds on any row (an unbounded correction)."""
        self.lo[:] = -INF
        self.hi[:] = INF

    def set_b(self, b: np.ndarray) -> None:
        """The right-hand side restricted on the owned rows, the ghosts' from their owners."""
        self.b = b
        if self.halo is not None:
            self.halo.update(self.b)

    def set_bounded(self, bounded: bool) -> None:
        """Which rows have a finite bound, and whether any row on any rank has one."""
        if not bounded:
            self.bounded = np.zeros(self.n, np.uint8)
            self.any_bounds = _any(self.comm, False)
            return
        self.bounded = _core.finite_rows(self.lo, self.hi)
        self.any_bounds = _any(self.comm, bool(np.any(self.bounded & self.owned_u8)))

    def sweep(self, forward: bool, omega: float) -> None:
        """One (projected) Gauss-Seidel pass, colour by colour, the ghosts exchanged after each
        (_overlapped_sweep)."""
        if self.order is not None:
            order = [self.order]
        else:
            order = self.colours if forward else self.colours[::-1]
        threads = 1 if self.order is not None else self.threads  # a thread per chunk of one colour's rows

        def sweep_rows(rows):
            if self.any_bounds:
                self.rows.sweep(self.x, self.b, rows, forward, omega, self.lo, self.hi, self.bounded, threads)
            else:
                self.rows.sweep(self.x, self.b, rows, forward, omega, threads=threads)

        if self.halo is None:
            for rows in order:
                sweep_rows(rows)
            return
        if self.split is None:  # a row reads a ghost where its pattern has one (fixed after the first build)
            indptr, indices, _ = self.rows.blocks()
            ghost_block = ~self.owned[indices]
            reads = np.zeros(self.n, bool)
            reads[np.repeat(np.arange(self.n), np.diff(indptr))[ghost_block]] = True
            self.split = _split(self.colours, reads)
        _overlapped_sweep(self.split, forward, sweep_rows, lambda: self.halo.start(self.x))

    def residual(self) -> np.ndarray:
        """b - A x on the owned rows, the ghosts' from their owners."""
        r = self.rows.residual(self.x, self.b, self.owned_u8)
        if self.halo is not None:
            self.halo.update(r)
        return r

    def memory_bytes(self) -> int:
        """The bytes of the level's rows and smoother, its transfer with the ghosts' Z rows, and its vectors."""
        own = self.rows.memory_bytes() + (self.transfer.memory_bytes() if self.transfer is not None else 0)
        return int(own + self.x.nbytes + self.b.nbytes + self.lo.nbytes + self.hi.nbytes + self.bounded.nbytes)


class CoarseCorrection:
    """The coarse levels of one rank and the multilevel correction of the serial CoarseCycle: the
    core's kernels on each level and the core's recursion over them, the exchanges here. The
    smallest coarse levels are held whole by every rank (replicated.py): levels[:k] are whole,
    levels[k:] distributed."""

    def __init__(self, comm, hierarchy, d: int, fine_transfer: sp.csr_matrix, threads: int = 1,
                 whole_below: Optional[int] = None):
        self.comm, self.d = comm, d
        self.dist = levels = hierarchy.levels
        self.k = replicated_count(comm, hierarchy, whole_below)
        self.whole: List[Whole] = []
        for l in range(self.k):
            self.whole.append(Whole(comm, levels[l], self.whole[-1] if l else None, l == 0))
        self.levels = []
        for l in range(len(levels) - 1):
            if l < self.k:
                W = self.whole[l]
                self.levels.append(CoarseLevel(W.serial, W.level, self.whole[l - 1].level if l else None, d, threads))
            else:
                self.levels.append(CoarseLevel(comm, levels[l], levels[l - 1] if l > 0 else None, d, threads))
        # the Galerkin rows of the top whole level as the distributed level's owners form them
        self.boundary_rows = (_core.CoarseRows2D if d == 2 else _core.CoarseRows3D)() if self.k else None
        # onto the fine level from the top coarse level (rotated rows)
        self.fine_transfer = transfer_kernel(fine_transfer, levels[-1], levels[-2], d)
        self.coarsest: Optional[GatheredCoarsest] = None
        self.opt = None  # the options of the correction under way (the level operations read them)

    def _to_whole(self, l: int) -> None:
        """Whole level l's rows from the boundary rows every rank formed for its owned nodes."""
        C = self.levels[l]
        if C.rows.n == 0 or _any(self.comm, self.boundary_rows.changed.any()):
            C.rows.set_blocks(*self.whole[l].gather_rows(self.boundary_rows, self.d))
        else:
            C.rows.clear_changed()

    def build(self, fine, mask: np.ndarray, hess_nodes: np.ndarray, hess: np.ndarray) -> None:
        """Every coarse matrix for the fine matrix with the Hessian blocks `hess` (k, d, d) added at
        the owned nodes hess_nodes, and the truncation mask (per fine dof, 0/1). Rows whose inputs did
        not change since the last build are kept (they would get the same bits). Collective."""
        d, top, k = self.d, len(self.levels) - 1, self.k
        C = self.levels[top]
        # the fine level's own BlockMatrix (a view): no second fine matrix
        galerkin_rows(self.comm, fine.level, self.dist[top], self.fine_transfer, C.rows if top >= k else self.boundary_rows,
                      d, A=fine.core.matrix, mask=mask, hess_nodes=hess_nodes, hess=hess)
        if top < k:
            self._to_whole(top)
        C.refresh()
        for l in range(top, 0, -1):
            L, below = self.levels[l], self.levels[l - 1]
            if l - 1 >= k:  # both distributed
                galerkin_rows(self.comm, L.level, below.level, L.transfer, below.rows, d, above=L.rows)
            elif l >= k:  # the boundary: the owners' rows, gathered whole
                galerkin_rows(self.comm, L.level, self.dist[l - 1], L.transfer, self.boundary_rows, d, above=L.rows)
                self._to_whole(l - 1)
            else:  # both whole: one rank's code
                galerkin_rows(L.comm, L.level, below.level, L.transfer, below.rows, d, above=L.rows)
            below.refresh()
        L0 = self.levels[0]
        if self.coarsest is None:
            self.coarsest = GatheredCoarsest(L0.comm, L0.level, d)
            self.coarsest.set_matrix(rows_to_csr(L0.rows, d))
        elif _any(L0.comm, L0.rows.changed.any()):
            self.coarsest.set_matrix(rows_to_csr(L0.rows, d))

    def memory_bytes(self) -> int:
        """The bytes of the coarse levels (rows, smoother, vectors), the transfers with the Galerkin
        kernels' ghost Z rows, and the gathered coarsest level."""
        total = self.fine_transfer.memory_bytes() + sum(L.memory_bytes() for L in self.levels)
        if self.boundary_rows is not None:
            total += self.boundary_rows.memory_bytes()
        if self.coarsest is not None:
            total += self.coarsest.memory_bytes()
        return int(total)

    def _down(self, l: int, values: np.ndarray) -> np.ndarray:
        """Restricted values (owned rows of level l's distributed numbering) as level l holds them."""
        return self.whole[l].gather(values) if l < self.k else values

    def _up(self, l: int, x: np.ndarray) -> np.ndarray:
        """Level l's correction at the local nodes of its distributed numbering."""
        return np.ascontiguousarray(x[self.whole[l].local]) if l < self.k else x

    def correction(self, opt, r_fine: np.ndarray, mask: np.ndarray, lo_f: np.ndarray, hi_f: np.ndarray,
                   bounded: bool, formed=None) -> np.ndarray:
        """w = M P c on every local fine row for the fine residual r (ghost rows fresh), the mask and
        the fine correction bounds (+-inf where none; ghost rows fresh). formed = (A, u, f, known):
        r holds the rows flagged in `known`, the others are f - A u, formed as they are restricted."""
        top = len(self.levels) - 1
        C, T = self.levels[top], self.fine_transfer
        m = np.ascontiguousarray(mask, np.uint8)
        # sums in ascending fine node
        b = T.restrict_residual(r_fine, m) if formed is None else T.restrict_fine_residual(*formed[:3], r_fine, formed[3], m)
        C.set_b(self._down(top, b))
        if bounded:
            C.set_bounds(*(self._down(top, v) for v in T.restrict_bounds(lo_f, hi_f, mask=m)))
        else:
            C.clear_bounds()
        C.set_bounded(bounded)
        C.x[:] = 0.0
        self.opt = opt
        _core.multigrid_cycle(self, opt.nu1, opt.nu2, top, opt.cycle)
        return T.prolong(self._up(top, C.x), m).ravel()

    # The level operations of the core's multigrid recursion (mg/cycle_recursion.hpp, the serial
    # cycle's): level l's sweeps, the restriction to level l - 1 and the prolongation back. From a
    # distributed level onto a whole one (the boundary) the owned rows are gathered, and the
    # correction is read whole.
    def pre_smooth(self, l: int) -> None:
        """One forward sweep of level l."""
        self.levels[l].sweep(True, self.opt.omega)

    def post_smooth(self, l: int) -> None:
        """One backward sweep of level l."""
        self.levels[l].sweep(False, self.opt.omega_post)

    def restrict_down(self, l: int) -> None:
        """Level l - 1's right-hand side, bounds (the slack left on level l) and x = 0."""
        L, C = self.levels[l], self.levels[l - 1]
        boundary = l >= self.k > l - 1
        b = L.transfer.restrict_residual(L.residual())
        C.set_b(self.whole[l - 1].gather(b) if boundary else b)
        if L.any_bounds:
            bounds = L.transfer.restrict_bounds(L.lo, L.hi, x=L.x, rows=L.bounded)
            C.set_bounds(*((self.whole[l - 1].gather(v) for v in bounds) if boundary else bounds))
        else:
            C.clear_bounds()
        C.set_bounded(L.any_bounds)
        C.x[:] = 0.0

    def prolong_up(self, l: int) -> None:
        """x_l += P x_{l-1}."""
        L, C = self.levels[l], self.levels[l - 1]
        boundary = l >= self.k > l - 1
        L.transfer.prolong_add(self._up(l - 1, C.x) if boundary else C.x, L.x)

    def solve_coarsest(self) -> None:
        """The coarsest level's correction."""
        self._solve_coarsest(self.opt)

    def _solve_coarsest(self, opt) -> None:
        """The serial solve_coarsest on the gathered level: the exact solve, then the core's bounded
        correction where the solution leaves the bounds."""
        L, S, d = self.levels[0], self.coarsest, self.d
        b = S.gather(L.b)
        x = np.ascontiguousarray(S.solve(b)).reshape(-1, d)
        if L.any_bounds:
            S.bound(x, b.reshape(-1, d), S.gather(L.lo).reshape(-1, d), S.gather(L.hi).reshape(-1, d), opt.omega)
        L.x[:] = x[L.level.gid]


class DistributedMonotoneStep:
    """One cycle of truncated monotone multigrid on the ranks: nu1 nonlinear sweeps, the
    linearization at the contact nodes, the coarse correction of the truncated problem, nu2 sweeps
    back; under Coulomb friction (Algorithm 2: the coarse problem freezes the bound F |s_n|) the
    settled cycles Anderson-mixed as in the serial step (steps/monotone_mg_step.hpp); returns
    ||u_new - u_old||_A (exact sums)."""

    def __init__(self, comm, fine, hierarchy, opt, whole_below: Optional[int] = None):
        """opt: the resolved SolverOptions (problem.resolve); whole_below: replicated.py's choice."""
        self.comm, self.fine, self.opt = comm, fine, opt
        d = self.d = fine.d
        lev = fine.level
        self.n = len(lev.gid)
        self.owned = lev.owner == lev.rank
        self.owned_u8 = self.owned.astype(np.uint8)
        self._lo, self._hi = np.full((self.n, d), -INF), np.full((self.n, d), INF)  # the fine correction bounds
        self.halo = None if is_serial(comm) else lev.halo  # one rank: no ghosts, nothing to exchange
        self.colours = _colour_rows(comm, lev)
        self.order = np.concatenate(self.colours or [np.zeros(0, np.int64)])
        # the linearization forms the fine residual only where it is read before the restriction
        # (the contact rows, which it reads, and the rows sent to other ranks); the restriction
        # forms the other owned rows in its own pass (the serial step's fused residual)
        sent = [np.asarray(v, np.int64) for v in (self.halo.send.values() if self.halo is not None else ())]
        self.residual_rows = np.unique(np.concatenate([fine.contact_nodes[fine.owned_contacts]] + sent)).astype(np.int64)
        self.known = (~self.owned).astype(np.uint8)  # ghost rows: their owners'
        self.known[self.residual_rows] = 1
        if self.halo is not None:  # a node reads a ghost where it shares a cell with one (the matrix pattern)
            reads = np.zeros(self.n, bool)
            cells = lev.cells[(lev.owner[lev.cells] != lev.rank).any(axis=1)]
            reads[cells] = True
            self.split = _split(self.colours, reads)
        self.f = fine.core.load
        P = local_transfer(lev, hierarchy.levels[-2], d, comm)
        P = rotate_rows(P, fine.contact_nodes, fine.frames, d)
        self.coarse = CoarseCorrection(comm, hierarchy, d, P, opt.threads, whole_below)
        # the coarse levels built at set-up for the Dirichlet truncation alone, as the serial solver
        # builds them: the first cycle's linearization updates only the rows it changes (the same
        # bits as a full build)
        no_contact = np.zeros(0, np.int64)
        mask = fine.core.linearize(np.zeros((self.n, d)), np.zeros((self.n, d)), no_contact)[0].ravel()
        hess_nodes, hess = no_contact, np.zeros((0, d, d))
        self.coarse.build(fine, mask, hess_nodes, hess)
        self.built = (mask, hess_nodes, hess)  # the truncation and Hessian blocks the coarse levels were built for
        self.Au: Optional[np.ndarray] = None  # A u on the owned rows, updated with u in every cycle
        self._z: Optional[np.ndarray] = None  # A (u - old) of the last step measured without updating A u
        self.phase_seconds = {k: 0.0 for k in ("pre_smooth", "linearize", "coarse_update", "coarse_correction",
                                               "post_smooth", "norm")}
        self.notes = []
        self.rebuilt = False  # whether the last cycle rebuilt the coarse levels
        self.rebuilds = 0  # coarse rebuilds in the solve (the first cycle's update included, the set-up build not: the serial count)
        # Coulomb: the frozen bound leaves a slow linear contraction once the state settles
        # the serial step's Anderson mixing with its dot products as node sums over the ranks (bind_anderson.cpp)
        self.anderson = _core.NodeAnderson(self.owned_u8, d, lambda totals: exact_totals(totals, comm)) \
            if fine.law == "coulomb" else None
        self.best_step = INF  # the smallest ||u^{k+1} - u^k||_A of the solve
        if fine.frames.size and not np.all(np.isin(np.round(np.abs(fine.frames), 15), (0.0, 1.0))):
            self.notes.append("rotated contact frames: the plain truncated coarse correction (the serial solver "
                              "projects it there)")

    def exchanges(self) -> int:
        """The halo exchanges this rank has made on the fine and the distributed coarse levels."""
        halos = [self.halo] + [L.halo for L in self.coarse.levels]
        return int(sum(h.exchanges for h in halos if h is not None))

    @property
    def whole_levels(self) -> int:
        """How many coarse levels every rank holds whole (replicated.py)."""
        return self.coarse.k

    def memory_bytes(self) -> int:
        """The bytes of this rank's matrices, transfers and vectors (arrays only): the fine level (matrix,
        load, Dirichlet and contact data, as the core holds them), the four fine vectors of a cycle
        (u, A u, the iterate before the cycle and the residual, as the serial core counts them),
        what the coarse correction holds, and the Anderson history under Coulomb friction."""
        fine_vectors = 4 * self.n * self.d * 8
        total = self.fine.core.memory_bytes + fine_vectors + self.coarse.memory_bytes()
        if self.anderson is not None:
            total += self.anderson.memory_bytes()
        return int(total)

    def sweep(self, u: np.ndarray, forward: bool, omega: float) -> None:
        """One nonlinear Gauss-Seidel pass over the fine level, colour by colour, u (n, d) in place."""
        if self.halo is None and self.opt.threads == 1:  # no exchange between the colours: one call, the same rows in order
            self.fine.core.sweep(u, self.order, forward, omega, 1)
            return
        core, threads = self.fine.core, self.opt.threads
        if self.halo is None:
            for rows in (self.colours if forward else self.colours[::-1]):
                core.sweep(u, rows, forward, omega, threads)
            return
        _overlapped_sweep(self.split, forward, lambda rows: core.sweep(u, rows, forward, omega, threads),
                          lambda: self.halo.start(u))

    def linearize(self, u: np.ndarray):
        """mask (n*d), node bounds lo/hi (n, d; +-inf away from the contact nodes), the Hessian
        blocks, whether any bound is finite, and the fine residual with the friction gradient on
        the rows flagged in self.known (the restriction forms the rest); ghost rows from their
        owners."""
        fine, d = self.fine, self.d
        r = fine.core.residual(u, self.residual_rows)  # the rest: in the restriction (correction)
        mask, lo_c, hi_c, H, bounded = fine.core.linearize(u, r, fine.owned_contacts)
        # +-inf away from the contact nodes: the arrays are kept, only the contact rows are written
        lo, hi = self._lo, self._hi
        lo[fine.contact_nodes] = lo_c
        hi[fine.contact_nodes] = hi_c
        if self.halo is not None:
            self.halo.update_many(mask, lo, hi, r)
        mask = mask.ravel()
        hess = H[fine.owned_contacts]
        keep = np.abs(hess).reshape(len(hess), -1).max(axis=1, initial=0.0) > 0 if len(hess) else np.zeros(0, bool)
        hess_nodes = fine.contact_nodes[fine.owned_contacts][keep]
        return mask, lo, hi, hess_nodes, hess[keep], _any(self.comm, bounded), r

    def difference_norm(self, u: np.ndarray, old: np.ndarray, update: bool = False) -> float:
        """||u - old||_A over the owned rows (exact sums), u and old (n, d) with fresh ghosts, from one
        pass over the matrix; update: A u += A (u - old) in the same pass (else A (u - old) is left in
        self._z until the next such call: not held beyond the cycle)."""
        if update:
            out = self.Au
        else:
            out = self._z = np.zeros_like(u)
        total = self.fine.core.difference_product(u, old, out, self.owned_u8, update)
        return float(np.sqrt(max(exact_totals([total], self.comm)[0], 0.0)))

    def any_sliding(self, u: np.ndarray) -> bool:
        """Whether a contact node slides on any rank."""
        state, _ = self.fine.core.contact_state(u, self.fine.owned_contacts)
        return _any(self.comm, bool(np.any(state == 2)))

    def admit_mixed(self, y: np.ndarray, plain: np.ndarray) -> bool:
        """The mixed iterate y takes the contact state of the plain cycle's result at every contact
        node (ghosts as their owners), or is refused where any owned node on any rank refuses it."""
        fine, d = self.fine, self.d
        every = np.arange(len(fine.contact_nodes), dtype=np.int64)
        ok = fine.core.admit_mixed(y.reshape(-1, d), plain.reshape(-1, d), every)
        return not _any(self.comm, not bool(np.all(ok[fine.owned_contacts])))

    def mix(self, old: np.ndarray, u: np.ndarray, state_changed: bool) -> float:
        """The Anderson step of a Coulomb cycle x = old -> G(x) = u (in place) by the serial step's
        rule (the core's SettledAnderson settle). Where the restart test's step A (u - old) was
        measured and the mixed iterate refused, A u takes it instead of a second pass over the
        matrix. Returns the step when it was measured here, else -1."""
        def keep_change():
            self.Au += self._z

        measured = self.anderson.settle(old, u, self.any_sliding(u), bool(state_changed), self.best_step,
                                        lambda: self.difference_norm(u, old), self.admit_mixed, keep_change)
        self._z = None
        return measured

    def iterate(self, u: np.ndarray) -> float:
        """One cycle on u (n, d, in place); returns ||u_new - u_old||_A."""
        opt, ph = self.opt, self.phase_seconds
        t = time.perf_counter()

        def lap(name):
            nonlocal t
            now = time.perf_counter()
            ph[name] += now - t
            t = now

        old = u.copy()
        if self.Au is None:
            self.Au = self.fine.core.multiply(u, opt.threads)
        for _ in range(opt.nu1):
            self.sweep(u, True, opt.omega)
        lap("pre_smooth")
        mask, lo, hi, hess_nodes, hess, bounded, r = self.linearize(u)
        lap("linearize")
        key = (mask, hess_nodes, hess)
        # a new truncation restarts the Anderson history (Coulomb only)
        state_changed = self.anderson is not None and _any(
            self.comm, self.built is None or not np.array_equal(mask, self.built[0]))
        changed = self.built is None or not (np.array_equal(mask, self.built[0]) and np.array_equal(hess_nodes, self.built[1])
                                             and np.array_equal(hess, self.built[2]))
        self.rebuilt = _any(self.comm, changed)
        if self.rebuilt:
            self.coarse.build(self.fine, mask, hess_nodes, hess)
            self.built = key
            self.rebuilds += 1
        lap("coarse_update")
        w = self.coarse.correction(opt, r, mask, lo, hi, bounded, formed=(self.fine.core.matrix, u, self.f, self.known))
        u += w.reshape(-1, self.d)
        lap("coarse_correction")
        for _ in range(opt.nu2):
            self.sweep(u, False, opt.omega_post)
        lap("post_smooth")
        measured = self.mix(old, u, state_changed) if self.anderson is not None else -1.0
        step = measured if measured >= 0 else self.difference_norm(u, old, update=True)
        self.best_step = min(self.best_step, step)
        lap("norm")
        return step

    def record(self, u: np.ndarray) -> dict:
        """Energy (without the constant of the Dirichlet values), ||u||_A and the contact counts."""
        Au = self.Au
        state, fe = self.fine.core.contact_state(u, self.fine.owned_contacts, Au)
        # 1/2 u.Au - f.u over the owned nodes: 2 e rounded once (halving is exact)
        quad, twice = node_dots([(u, Au), [(1, u, Au), (-2, self.f, u)]], self.comm, self.owned_u8)
        e = 0.5 * twice + exact_sum(fe, self.comm)
        counts = np.array([np.count_nonzero(state > 0), np.count_nonzero(state == 1), np.count_nonzero(state == 2)])
        if not is_serial(self.comm):
            counts = np.sum(self.comm.allgather(counts), axis=0)
        norm = float(np.sqrt(max(quad, 0.0)))
        return {"energy": e, "solution_norm": norm, "active": int(counts[0]), "stick": int(counts[1]),
                "slip": int(counts[2]), "rebuilt": self.rebuilt}

    def sweep_change(self, u: np.ndarray) -> float:
        """||S(u) - u||_A for one forward nonlinear sweep S (u unchanged)."""
        v = u.copy()
        self.sweep(v, True, self.opt.omega)
        change = self.difference_norm(v, u)
        self._z = None
        return change
