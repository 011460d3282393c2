"""The solver's options: one frozen dataclass mirroring the core's SolverOptions
(cpp/base/solver_options.hpp), validated once, and the one function that fills the defaults that
depend on the problem."""
from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass
from typing import Optional

import numpy as np

METHODS = ("nmg", "fixed-point", "linear", "tnnmg")
STARTS = ("zero", "nested")
CYCLES = ("V", "W", "F")
ORDERINGS = ("coloured", "lexicographic", "hashed")
LINEAR_CORRECTIONS = ("pcg", "cycle", "coarse")
INT32_MAX = 2 ** 31 - 1  # the core counts cycles in a C int

# The default omega by cell type: symmetric over-relaxation of the simplices' block Gauss-Seidel;
# plain Gauss-Seidel on quadrilaterals and hexahedra (0005-over-relaxation).
DEFAULT_OMEGA = {"triangle": 1.3, "tetra": 1.3}
# The post-smoothing's own omega on 2D adaptive hierarchies, where the Petrov-Galerkin coupling is on
# by default (0005-over-relaxation, 0006-petrov-galerkin-coupling).
DEFAULT_OMEGA_POST_ADAPTIVE = {"triangle": 1.5}
# A core solver built for the coloured order stores its levels by colours (each colour a contiguous
# range: the coloured sweep streams memory; 0003-coloured-gauss-seidel).
DEFAULT_ORDERING = "coloured"
# The default stop, relative (see SolverOptions.rtol): on the Hertz benchmark 2 cycles before the
# paper's absolute 1e-11 (0022-scale-free-stop).
DEFAULT_RTOL = 1e-10

# Options taken only when the core is built: a solve cannot change them. (ordering is taken at the
# build too, as the storage of the levels, but a solve may sweep in the other order on it: the same
# answer, slower.)
BUILD_FIELDS = ("local_smoothing", "release_hierarchy")
# The fields of the package alone, which the core does not take: how the core is built, and where a
# solve starts (made here: solve/nested.py).
PACKAGE_ONLY = BUILD_FIELDS + ("start",)


def _is_int(v) -> bool:
    return not isinstance(v, (bool, np.bool_)) and isinstance(v, (int, np.integer))


def _is_real(v) -> bool:
    return not isinstance(v, (bool, np.bool_)) and isinstance(v, numbers.Real) and bool(np.isfinite(v))


@dataclass(frozen=True)
class SolverOptions:
    """Every option of a solve, validated when made (ValueError naming the field).

    A field None takes the problem-dependent default that resolve_options(problem, options) fills in;
    result.options reports the values used."""

    method: Optional[str] = None
    """None: chosen from the problem (resolve_options: "tnnmg" with its line smoother where Algorithm
    2's point smoother is slow -- nearly incompressible materials, stretched cells -- else "nmg");
    "nmg" (Algorithm 2 for Coulomb friction; truncated monotone multigrid for frictionless and
    Tresca; linear multigrid without contact), "tnnmg" (truncated nonsmooth Newton multigrid),
    "fixed-point" (Algorithm 1, Coulomb only) or "linear" (the cost reference: the linear problem with
    the contact state of an nmg solve known in advance)."""
    tol: Optional[float] = None
    """An absolute stop: when the correction's energy norm ||u^{k+1} - u^k||_A falls below tol (in
    the model's units: energy^(1/2)). The paper's benchmarks stop at 1e-11."""
    rtol: Optional[float] = None
    """A relative stop: when the correction's energy norm falls below rtol times the larger of the
    first correction's and the iterate's own ||u||_A -- the same cycles whatever the units. Given
    alone, tol or rtol is the one stop (the other off); neither given: rtol = DEFAULT_RTOL; both: the
    first met."""
    max_cycles: int = 200
    """At most this many cycles."""
    cycle: str = "F"
    """The multigrid cycle: "V", "W" or "F"."""
    nu1: int = 3
    """Pre-smoothing sweeps."""
    nu2: int = 3
    """Post-smoothing sweeps."""
    omega: Optional[float] = None
    """Over-relaxation in (0, 2) of the smoothers' unbounded block solves; None: by cell type."""
    omega_post: Optional[float] = None
    """The post-smoothing's own over-relaxation; None: omega, or 1.5 on 2D adaptive triangle hierarchies."""
    threads: int = 0
    """Threads of sweeps, products and norms (0: all cores); results are bitwise the same on any count."""
    ordering: Optional[str] = None
    """Gauss-Seidel order: "coloured", "lexicographic" or "hashed" (None: coloured). "coloured"
    colours each level greedily in node order; "hashed" greedily in the order of a hash of the node
    numbers (splitmix64, ties by number), the colours of the distributed solver
    (contactmg.distributed.colour_level) on every smoothed level, so that a serial solve sweeps the
    nodes as a distributed one does and takes the same cycles (0030-distributed-cycle). The solver is
    built for its options' ordering (coloured, hashed: the levels stored by those colours,
    0003-coloured-gauss-seidel); a solve may take another order on it (the same answer as a solver
    built for that order up to round-off, slower)."""
    local_smoothing: Optional[bool] = None
    """Coarse levels smooth only where they differ from the level below (fixed when the solver is
    built); None: on for adaptive hierarchies (0004-local-smoothing)."""
    petrov_galerkin: Optional[bool] = None
    """Algorithm 2's Petrov-Galerkin coupling of the sliding nodes on the top coarse level; None: on for
    2D adaptive hierarchies under Coulomb friction (0006-petrov-galerkin-coupling)."""
    upwind_contact_sweep: Optional[bool] = None
    """Algorithm 2's extra upwind visit of the contact nodes after each fine sweep; None: on for 2D
    adaptive hierarchies under Coulomb friction (0007-upwind-contact-sweep)."""
    projected_coarse_correction: Optional[bool] = None
    """The coarse correction projected onto the gap with an exact line search; None: on where a
    contact frame is rotated (0008-projected-coarse-correction)."""
    fixed_point_tol: float = 1e-9
    """Algorithm 1: the relative change of the friction bound that ends the outer iteration."""
    fixed_point_max: int = 100
    """Algorithm 1: at most this many outer iterations."""
    fixed_point_stall_window: int = 0
    """Algorithm 1: stop as not converging once the change has not fallen below the one that many
    outer iterations before (0: run to fixed_point_max)."""
    switch_rate: Optional[float] = None
    """Algorithm 2 (method nmg): once its corrections contract by less than this per cycle, the solve
    goes on with TNNMG steps from its iterate, under the same stop (0: never). None: SWITCH_RATE where
    the method was left to the solver and the coarse levels were made from a fine mesh alone
    (0029-geometric-coarsening), else 0."""
    linear: Optional[str] = None
    """tnnmg's linear correction: "pcg", "cycle" or "coarse" (None: the core's default)."""
    lines: Optional[bool] = None
    """tnnmg: line smoothing in the linear correction (None: the core's default)."""
    start: Optional[str] = None
    """Where a solve given no start value begins: "zero" (u = 0, the paper's counts) or "nested" (the
    problem solved on its coarse levels first, each solution interpolated to the next as its start:
    solve/nested.py). None: "nested" where a body is held only by its contacts (one body; its
    answer may lie far from u = 0), else "zero". The result's cycles are the finest level's; the
    coarse levels' go to result.extra["nested_start"] (0034-nested-start)."""
    release_hierarchy: bool = False
    """Once the solver is built, release the hierarchy's coarse meshes and transfers and the problem's
    load and Dirichlet values (made again if asked for) and the cycles' workspace after each solve:
    the lower memory peak of single solves (0011-memory-release). Fixed when the solver is built."""

    def __post_init__(self):
        if self.method is not None and self.method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        if self.cycle not in CYCLES:
            raise ValueError(f"cycle must be one of {CYCLES}, got {self.cycle!r}")
        for name in ("nu1", "nu2"):
            v = getattr(self, name)
            if not _is_int(v) or not 0 <= v <= 100:
                raise ValueError(f"{name} must be an integer in 0..100, got {v!r}")
        if self.nu1 + self.nu2 < 1:
            raise ValueError("nu1 + nu2 must be at least 1: a cycle needs smoothing")
        for name in ("tol", "rtol", "fixed_point_tol"):
            v = getattr(self, name)
            if v is None and name != "fixed_point_tol":
                continue
            if not _is_real(v) or v < 0:
                raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
        if self.stop == (0, 0):
            raise ValueError("one of tol and rtol must be positive")
        for name in ("max_cycles", "fixed_point_max"):
            v = getattr(self, name)
            if not _is_int(v) or not 1 <= v <= INT32_MAX:
                raise ValueError(f"{name} must be an integer in 1..{INT32_MAX}, got {v!r}")
        v = self.fixed_point_stall_window
        if not _is_int(v) or not 0 <= v <= INT32_MAX:
            raise ValueError(f"fixed_point_stall_window must be an integer >= 0, got {v!r}")
        if not _is_int(self.threads) or not 0 <= self.threads <= 4096:
            raise ValueError(f"threads must be an integer in 0..4096 (0: all cores), got {self.threads!r}")
        if self.ordering is not None and self.ordering not in ORDERINGS:
            raise ValueError(f"ordering must be one of {ORDERINGS}, got {self.ordering!r}")
        for name in ("omega", "omega_post"):
            w = getattr(self, name)
            if w is not None and not (_is_real(w) and 0 < w < 2):
                raise ValueError(f"{name} must be a number in (0, 2), got {w!r}")
        for name in ("local_smoothing", "petrov_galerkin", "upwind_contact_sweep", "projected_coarse_correction",
                     "lines", "release_hierarchy"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {v!r}")
        if self.start is not None and self.start not in STARTS:
            raise ValueError(f"start must be one of {STARTS}, got {self.start!r}")
        if self.switch_rate is not None:
            if not (_is_real(self.switch_rate) and 0 <= self.switch_rate < 1):
                raise ValueError(f"switch_rate must be a number in [0, 1) (0: never), got {self.switch_rate!r}")
            if self.switch_rate > 0 and self.method not in (None, "nmg"):
                raise ValueError(f"switch_rate is a choice of method 'nmg' (Algorithm 2), not {self.method!r}")
        if self.release_hierarchy is None:
            raise ValueError("release_hierarchy must be True or False, got None")
        if (self.linear is not None or self.lines is not None) and self.method not in (None, "tnnmg"):
            raise ValueError("linear and lines choose the linear correction of method 'tnnmg'")
        if self.linear is not None and self.linear not in LINEAR_CORRECTIONS:
            raise ValueError(f"linear must be one of {LINEAR_CORRECTIONS}, got {self.linear!r}")
        if self.method not in (None, "nmg", "linear"):
            for name in ("petrov_galerkin", "upwind_contact_sweep", "projected_coarse_correction"):
                if getattr(self, name):
                    raise ValueError(f"{name} is a choice of method 'nmg' (Algorithm 2), not {self.method!r}")

    @property
    def stop(self) -> tuple:
        """(tol, rtol) as the solve uses them: one given alone turns the other off; neither given:
        (0, DEFAULT_RTOL)."""
        if self.tol is None and self.rtol is None:
            return 0.0, DEFAULT_RTOL
        return (0.0 if self.tol is None else float(self.tol)), (0.0 if self.rtol is None else float(self.rtol))

    def replace(self, **changes) -> "SolverOptions":
        """A validated copy with `changes` (field names; TypeError for an unknown one). tol and rtol
        are one choice: changing one alone leaves the other off (None)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise TypeError(f"unknown solver option(s): {sorted(unknown)}")
        if "tol" in changes and "rtol" not in changes:
            changes["rtol"] = None
        elif "rtol" in changes and "tol" not in changes:
            changes["tol"] = None
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """The fields as a dict, tol and rtol as the solve uses them."""
        out = dataclasses.asdict(self)
        out["tol"], out["rtol"] = self.stop
        return out

    def to_core(self) -> dict:
        """The core's options dict (bindings/options.cpp): every field but the package's own
        (PACKAGE_ONLY), those left None omitted (the core's default: the package's, or the core's own
        choice for linear and lines), the stop as `stop` gives it, and method "linear" as the core's
        "nmg" (the known-state problem is linear: the core's cycles without contact)."""
        out = {f.name: (bool(v) if isinstance(v, np.bool_) else v) for f in dataclasses.fields(self)
               if f.name not in PACKAGE_ONLY and (v := getattr(self, f.name)) is not None}
        out["tol"], out["rtol"] = self.stop
        if self.method == "linear":
            out["method"] = "nmg"
        return out


SWITCHES = ("petrov_galerkin", "upwind_contact_sweep", "projected_coarse_correction")


def for_method(base: SolverOptions, method: str, **fields) -> SolverOptions:
    """`base` with `method` and `fields`: Algorithm 2's switches that `base` holds (a problem's
    defaults) are dropped for another method, whose solves they do not concern; given in `fields`,
    they are checked."""
    if method not in ("nmg", "linear"):
        for k in SWITCHES:
            fields.setdefault(k, None)
    return base.replace(method=method, **fields)


# The paper's absolute stop, which its benchmarks keep (the default stop is relative: DEFAULT_RTOL).
PAPER_TOL = 1e-11


def with_cycle(problem, cycle: str = "F", nu1: int = 3, nu2: int = 3, tol: float = PAPER_TOL):
    """`problem` with Algorithm 2, the cycle (cycle, nu1, nu2) and the absolute stop `tol` as the
    defaults of problem.solve (the paper's benchmarks: nmg F(3,3), 1e-11); returns the problem."""
    problem.default_options = options_from(problem.default_options).replace(method="nmg", cycle=cycle, nu1=nu1,
                                                                            nu2=nu2, tol=tol)
    return problem


def options_from(options=None, **fields) -> SolverOptions:
    """A SolverOptions from None, a SolverOptions or a dict, with `fields` set on top (TypeError for
    an unknown field)."""
    if options is None:
        base = SolverOptions()
    elif isinstance(options, SolverOptions):
        base = options
    elif isinstance(options, dict):
        base = SolverOptions().replace(**options)
    else:
        raise TypeError(f"options must be a SolverOptions or a dict, got {type(options).__name__}")
    return base.replace(**fields) if fields else base


# Where the default method turns to TNNMG with line smoothing (0026-default-method): a Poisson ratio
# from which Algorithm 2's point smoother slows down (nu = 0.49: 41 cycles against TNNMG's 14), and a
# cell aspect ratio (longest over shortest edge) from which it stalls (aspect 32: 283 against 22).
STIFF_NU = 0.45
STRETCHED_ASPECT = 8.0
# Where Algorithm 2 on coarse levels made from a fine mesh alone goes on with TNNMG: corrections that
# contract by less than this per cycle (0029-geometric-coarsening: the cork's 4-layer mesh coarsened,
# 41 cycles of Algorithm 2 against 9 of TNNMG; the Hertz and sphere families contract by 0.1-0.2 and
# stay with Algorithm 2, which is twice as fast there).
SWITCH_RATE = 0.5


def cell_aspect_ratio(mesh) -> float:
    """The largest ratio of a cell's longest edge to its shortest over the mesh."""
    from ..mesh.mesh import CELL_EDGES

    X = mesh.points[mesh.cells]
    edges = np.stack([np.linalg.norm(X[:, a] - X[:, b], axis=1) for a, b in CELL_EDGES[mesh.cell_type]], axis=1)
    return float((edges.max(axis=1) / edges.min(axis=1)).max())


def default_method(problem) -> str:
    """The method for a problem whose options name none: "tnnmg" (its line smoother handles what a
    point smoother does not) for a contact problem of a nearly incompressible material or stretched
    cells, else "nmg" (Algorithm 2). The paper's benchmarks name "nmg" themselves."""
    if problem.law == "linear":
        return "nmg"
    from ..model.material import cell_moduli

    nu = max(float(cell_moduli(b.hierarchy.finest, b.material)[1].max()) for b in problem.bodies)
    if nu >= STIFF_NU or cell_aspect_ratio(problem.mesh) >= STRETCHED_ASPECT:
        return "tnnmg"
    return "nmg"


def _held_by_contact(problem) -> bool:
    """Does some body of `problem` have rigid motions that only its contacts hold? Algorithm 2's
    friction bound lags the normal stress, which is zero before the body touches: a load along a
    motion only friction holds moved such a body away (a 2 x 1 block pushed sideways, |u| = 2e8 after
    200 cycles), where the switch to TNNMG solves it in 12-23 cycles (0032-two-body-cycle)."""
    parts = getattr(problem, "parts", None) or [problem]
    return any(bool(getattr(part, "floating", None)) for part in parts)


def resolve_options(problem, options=None) -> SolverOptions:
    """`options` (None: the defaults) with every problem-dependent default (a field None) filled in
    for `problem`: the one place these defaults are decided.

    omega: DEFAULT_OMEGA of the cell type (1 where it has none); omega_post: omega where omega is
    given, else DEFAULT_OMEGA_POST_ADAPTIVE on 2D adaptive hierarchies, else omega; petrov_galerkin
    and upwind_contact_sweep: on for 2D adaptive hierarchies under Coulomb friction;
    projected_coarse_correction: on where a contact frame is rotated on one body (off for several
    bodies, 0032-two-body-cycle); local_smoothing: on for adaptive hierarchies; ordering:
    DEFAULT_ORDERING; switch_rate: SWITCH_RATE where the method is the solver's choice, Algorithm 2,
    and the coarse levels were made from a fine mesh alone, the bodies are several or a body is held
    only by its contacts, else 0; start: "nested" where the one body is held only by its contacts.
    Left
    None: linear and lines (the core's own)."""
    o = options_from(options)
    chosen = o.method is None
    if chosen:
        o = o.replace(method=default_method(problem) if o.linear is None and o.lines is None else "tnnmg")
    mesh = problem.mesh
    adaptive_2d = problem.hierarchy.kind == "adaptive" and mesh.dim == 2
    coulomb = problem.friction.law == "coulomb"
    changes = {}
    if o.omega_post is None:
        post = o.omega if o.omega is not None else (DEFAULT_OMEGA_POST_ADAPTIVE.get(mesh.cell_type) if adaptive_2d else None)
        changes["omega_post"] = post
    if o.omega is None:
        changes["omega"] = float(DEFAULT_OMEGA.get(mesh.cell_type, 1.0))
    if changes.get("omega_post", o.omega_post) is None:
        changes["omega_post"] = changes.get("omega", o.omega)
    algorithm2 = o.method in ("nmg", "linear")
    if o.petrov_galerkin is None:
        changes["petrov_galerkin"] = bool(algorithm2 and adaptive_2d and coulomb)
    if o.upwind_contact_sweep is None:
        changes["upwind_contact_sweep"] = bool(algorithm2 and adaptive_2d and coulomb)
    if o.projected_coarse_correction is None:
        changes["projected_coarse_correction"] = bool(algorithm2 and problem.rotated_frames()
                                                        and not getattr(problem, "multibody", False))
    if o.local_smoothing is None:
        changes["local_smoothing"] = problem.hierarchy.kind == "adaptive"
    if o.ordering is None:
        changes["ordering"] = DEFAULT_ORDERING
    if o.switch_rate is None:
        auto = (chosen and o.method == "nmg" and problem.law != "linear"
                and (problem.coarse_levels_from_mesh() or getattr(problem, "multibody", False)
                     or _held_by_contact(problem)))
        changes["switch_rate"] = SWITCH_RATE if auto else 0.0
    if o.start is None:
        nested = (o.method != "linear" and problem.law != "linear" and not getattr(problem, "multibody", False)
                  and _held_by_contact(problem))
        changes["start"] = "nested" if nested else "zero"
    return o.replace(**changes) if changes else o
