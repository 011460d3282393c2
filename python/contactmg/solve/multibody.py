"""Elastic bodies in frictional contact with each other (2D), through the dual mortar basis
transformation of Wohlmuth & Krause (2003).

The bodies are assembled one by one (each a ContactProblem without contact: its own hierarchy,
material, Dirichlet data and loads) into a block-diagonal A. Each contact pair couples the
nonmortar boundary of one body with the mortar boundary of another (mortar.py). The change of
basis u = T w, T = I + N (N = D^{-1} M on the nonmortar contact rows and mortar columns of every
pair), makes the
nonmortar unknowns the relative displacements w_p = u_p - (D^{-1} M u_m)_p, and the coupled
conditions nodal: the core then solves the problem T^T A T, T^T f with its own nodal solvers,
truncation and monotone multigrid, in the nodal frames of the nonmortar normals. T^{-1} = I - N
(N^2 = 0: no node is both nonmortar and mortar), so the fine prolongation T^{-1} P is again a
scalar interpolation (weights may be negative), and each body keeps its own coarse levels: the
coarse spaces are the union of the two bodies' coarse spaces, coupled only through the
transformed fine level, where the Galerkin products T^{-1}P^T (T^T A T) T^{-1}P = P^T A P are the
untransformed, uncoupled ones plus the truncation. The friction law acts on the tangential part of
w: the relative tangential displacement. A second coarse correction with every contact dof frozen
(the tied correction, MultiBodyProblem) moves touching bodies together.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Dict, Optional, Sequence

import numpy as np
import scipy.sparse as sp

from .. import _core
from ..model.frames import contact_frames
from ..model.friction import Coulomb, Frictionless, Tresca
from ..mesh.hierarchy import MeshHierarchy, Transfer
from ..model.material import Material
from ..mesh.mesh import Mesh
from ..model.mortar import MortarCoupling, mortar_coupling_2d
from ..model.mortar_3d import mortar_coupling_3d
from ..solve.contact_problem import ContactBoundary, ContactProblem, CycleOptions, Dirichlet, tag_tuple


@dataclass
class Body:
    """One elastic body: its hierarchy, material, Dirichlet data and surface loads."""

    hierarchy: MeshHierarchy
    material: Material
    dirichlet: Sequence[Dirichlet] = ()
    traction: Optional[Dict[int, object]] = None
    body_force: Optional[object] = None


@dataclass
class ContactPair:
    """Body `nonmortar` (the slave side, carrying the multiplier) against body `mortar` (the master
    side), on the facets with the given tags; `region(midpoints) -> bool` restricts the nonmortar
    facets (the possible contact zone); `search`: how far along its normal a nonmortar point looks
    for the mortar boundary."""

    nonmortar: int
    mortar: int
    nonmortar_tags: Sequence[int]
    mortar_tags: Sequence[int]
    search: float
    region: Optional[Callable[[np.ndarray], np.ndarray]] = None


def _bsr(A, n: int, d: int) -> sp.bsr_matrix:
    return sp.bsr_matrix((np.asarray(A.data), np.asarray(A.indices), np.asarray(A.indptr)), shape=(n * d, n * d))


def _block_matrix(A: sp.spmatrix, d: int):
    B = sp.bsr_matrix(A, blocksize=(d, d))
    B.sort_indices()
    cls = _core.BlockMatrix2D if d == 2 else _core.BlockMatrix3D
    n = B.shape[0] // d
    return cls(n, n, B.indptr.astype(np.int64), B.indices.astype(np.int64), np.ascontiguousarray(B.data))


def _scalar_transfer(P: sp.csr_matrix) -> Transfer:
    P = sp.csr_matrix(P)
    P.eliminate_zeros()
    P.sort_indices()
    return Transfer(P.shape[0], P.shape[1], P.indptr.astype(np.int64), P.indices.astype(np.int64),
                    P.data.astype(float))


class MultiBodyProblem(ContactProblem):
    """Bodies in contact through one or more mortar pairs (2D, or 3D through mortar_3d.py). solve() and its methods ("nmg",
    "fixed-point", "linear") are those of ContactProblem, on the transformed problem; the result's
    displacement is the canonical u = T w on the union mesh (`mesh`, with `body_id` per node), its
    contact quantities those of the nonmortar nodes of all pairs (contact_force: the nonmortar nodal
    force in the frames, measure: D, so normal_stress is the dual multiplier). `pair_of_contact[c]`
    says which pair contact node c belongs to.

    Each body keeps its own coarse levels (the finest prolongation is T^{-1} P): the pairs couple
    them only through the transformed fine level. A fine nonmortar row then has weights on both
    bodies' coarse unknowns, and the monotone bound restriction bounds each body's unknowns by a
    part of the slack: a common motion of the bodies at the edge of the contact zone, which leaves
    the slack unchanged, is cut as if it closed the gap. With unequal materials the interface has
    to settle by such a motion, and Algorithm 2 alone needed more cycles on finer levels (17 -> 30
    over levels 3-6 for E2 = 2 E1). `tied_correction` (the default) adds after each coarse
    correction of "nmg" and "fixed-point" a second one without bounds in the space where every
    contact dof (relative displacement) is frozen: the common motions (cpp/steps/tied_correction.hpp).
    "tnnmg" (a linear coarse correction, projected and line-searched) needs no such help
    (issue 13, benchmarks/two_body_levels.py)."""

    def __init__(self, bodies: Sequence[Body], pairs: Sequence[ContactPair], friction=None, cycle: str = "F",
                 nu1: int = 3, nu2: int = 3, tied_correction: bool = True):
        t0 = time.perf_counter()
        bodies = list(bodies)
        if len(bodies) < 2 or not all(isinstance(b, Body) for b in bodies):
            raise TypeError("bodies must be a sequence of at least two Body")
        pairs = [pairs] if isinstance(pairs, ContactPair) else list(pairs)
        if not pairs or not all(isinstance(q, ContactPair) for q in pairs):
            raise TypeError("pairs must be a ContactPair or a non-empty sequence of ContactPair")
        for q in pairs:
            if q.nonmortar == q.mortar or not all(0 <= k < len(bodies) for k in (q.nonmortar, q.mortar)):
                raise ValueError("a contact pair needs two different bodies of the problem")
        friction = Frictionless() if friction is None else friction
        if not isinstance(friction, (Frictionless, Tresca, Coulomb)):
            raise TypeError("friction must be Frictionless(), Tresca(bound) or Coulomb(F)")
        if not isinstance(tied_correction, (bool, np.bool_)):
            raise TypeError(f"tied_correction must be True or False, got {tied_correction!r}")
        self.tied_correction = bool(tied_correction)
        levels = {b.hierarchy.levels for b in bodies}
        if len(levels) != 1:
            raise ValueError(f"the bodies' hierarchies need the same number of levels, got {sorted(levels)}")
        dims = {b.hierarchy.finest.dim for b in bodies}
        if len(dims) != 1:
            raise ValueError(f"the bodies need one dimension, got {sorted(dims)}")
        self.bodies, self.pairs = bodies, pairs
        self.default_cycle = CycleOptions(cycle, nu1, nu2)
        self.friction = friction
        self.benchmark = None
        # each body on its own: assembly, Dirichlet data, its rigid motions held (no contact relied on)
        self.parts = [ContactProblem(b.hierarchy, b.material, b.dirichlet, body_force=b.body_force,
                                     traction=b.traction) for b in bodies]
        d = dims.pop()
        sizes = [p.mesh.num_points for p in self.parts]
        self.offsets = np.r_[0, np.cumsum(sizes)].astype(np.int64)
        n = int(self.offsets[-1])
        self.mesh = _union_mesh([p.mesh for p in self.parts], self.offsets)
        self.body_id = np.repeat(np.arange(len(bodies)), sizes).astype(np.int32)
        self.hierarchy = bodies[pairs[0].nonmortar].hierarchy  # for reports (kind, levels)
        self.material = bodies[pairs[0].nonmortar].material
        fine = self._level_coupling(levels.pop() - 1, [p.fixed.any(axis=1) for p in self.parts])
        self.couplings = fine["couplings"]
        self.N = fine["N"]
        Tk = sp.kron(sp.identity(n) + self.N, sp.identity(d), format="csr")
        A = sp.block_diag([_bsr(p.A, p.mesh.num_points, d) for p in self.parts], format="csr")
        self.A_canonical = A
        self.load_canonical = np.vstack([p.load for p in self.parts])
        self._Tk = Tk
        self._A = self._assemble_matrix()
        self.load = (Tk.T @ self.load_canonical.ravel()).reshape(n, d)
        self.fixed = np.vstack([p.fixed for p in self.parts])
        self.fixed_values = np.vstack([p.fixed_values for p in self.parts])
        order = np.argsort(fine["nodes"], kind="stable")  # contact nodes ascending
        nodes, normals = fine["nodes"][order], np.ascontiguousarray(fine["normals"][order])
        measure, gaps = fine["measure"][order], np.ascontiguousarray(fine["gaps"][order])
        self.pair_of_contact = fine["pair"][order]
        self.contact = ContactBoundary(nodes.astype(np.int64), normals, gaps, measure,
                                       facets=np.ascontiguousarray(fine["facets"]), frames=contact_frames(normals))
        self.coefficients = friction.coefficients(self.contact.nodes, measure)
        self.transfers = self._transfers()
        self._solvers = {}
        self._build_seconds = {}
        self.assembly_seconds = time.perf_counter() - t0 + sum(b.hierarchy.build_seconds for b in bodies)

    # -- the pieces ----------------------------------------------------------------------------
    @property
    def pair(self) -> ContactPair:
        """The first (for two bodies: the only) contact pair."""
        return self.pairs[0]

    @property
    def coupling(self) -> MortarCoupling:
        """The fine mortar coupling of the first pair."""
        return self.couplings[0]

    def _nonmortar_facet_mask(self, pair: ContactPair, m: Mesh) -> np.ndarray:
        sel = np.isin(m.facet_tags, list(tag_tuple(pair.nonmortar_tags, "nonmortar_tags")))
        if pair.region is not None:
            sel &= np.asarray(pair.region(m.points[m.facets].mean(axis=1)), dtype=bool)
        if not np.any(sel):
            raise ValueError(f"no facet of body {pair.nonmortar} carries the nonmortar tags "
                             f"{list(pair.nonmortar_tags)} (in the region)")
        return sel

    def _level_coupling(self, level: int, held: Sequence[np.ndarray]) -> dict:
        """The pairs' dual mortar couplings on the meshes of `level`: N_l (union numbering of that
        level) and, per kept nonmortar node, its union id, normal, gap, measure D and pair.
        A nonmortar node is kept where the mortar side covers the support of its dual basis
        function and no Dirichlet data (`held[body]`, per node of the body's mesh) holds it."""
        meshes = [b.hierarchy.meshes[level] for b in self.bodies]
        offsets = np.r_[0, np.cumsum([m.num_points for m in meshes])].astype(np.int64)
        n = int(offsets[-1])
        rows, cols, vals = [], [], []
        out = {k: [] for k in ("nodes", "normals", "gaps", "measure", "pair", "facets")}
        couplings = []
        for k, q in enumerate(self.pairs):
            sm, mm = meshes[q.nonmortar], meshes[q.mortar]
            msel = np.isin(mm.facet_tags, list(tag_tuple(q.mortar_tags, "mortar_tags")))
            if not np.any(msel):
                raise ValueError(f"no facet of body {q.mortar} carries the mortar tags {list(q.mortar_tags)}")
            ssel = self._nonmortar_facet_mask(q, sm)
            c = (mortar_coupling_2d if sm.dim == 2 else mortar_coupling_3d)(sm.points, sm.facets[ssel], mm.points, mm.facets[msel], q.search)
            couplings.append(c)
            keep = c.covered & ~held[q.nonmortar][c.nonmortar_nodes]
            if not np.any(keep):
                raise ValueError(f"no nonmortar node of contact pair {k} sees the mortar boundary within the search "
                                 "distance (or every one is held by Dirichlet data)")
            Mhat = c.Mhat[keep].tocoo()
            nodes = c.nonmortar_nodes[keep] + offsets[q.nonmortar]
            rows.append(nodes[Mhat.row])
            cols.append(Mhat.col + offsets[q.mortar])
            vals.append(Mhat.data)
            out["nodes"].append(nodes)
            out["normals"].append(c.normals[keep])
            out["gaps"].append(c.gaps(sm.points, mm.points)[keep])
            out["measure"].append(c.D[keep])
            out["pair"].append(np.full(len(nodes), k, np.int32))
            out["facets"].append(sm.facets[ssel] + offsets[q.nonmortar])
        res = {key: np.concatenate(v) for key, v in out.items()}
        if len(np.unique(res["nodes"])) != len(res["nodes"]):
            raise ValueError("a node is a nonmortar node of two contact pairs (pairs must not share nonmortar nodes)")
        N = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
        N.sum_duplicates()
        N.eliminate_zeros()
        # T^{-1} = I - N needs N^2 = 0: no mortar node of one pair is a nonmortar node of another
        if (abs(N) @ abs(N)).nnz:
            raise ValueError("a mortar node of one contact pair is a nonmortar node of another: make that body the "
                             "nonmortar (or the mortar) side of both its pairs")
        res["N"], res["couplings"] = N, couplings
        return res

    def _assemble_matrix(self):
        """T^T A T of the bodies' block-diagonal stiffness (the core may take the matrix over; asking
        for `A` again comes here, not to a one-mesh assembly)."""
        return _block_matrix((self._Tk.T @ self.A_canonical @ self._Tk).tocsr(), self.mesh.dim)

    def _transfers(self):
        """Per level the union of the bodies' interpolations; on the finest, T^{-1} P = (I - N) P."""
        levels = self.bodies[0].hierarchy.levels
        out = []
        for l in range(levels - 1):
            P = sp.block_diag([b.hierarchy.transfers[l].matrix() for b in self.bodies], format="csr")
            if l == levels - 2:
                P = (sp.identity(P.shape[0]) - self.N) @ P
            out.append(_scalar_transfer(P))
        return out

    def to_canonical(self, w: np.ndarray) -> np.ndarray:
        """u = T w = w + N w."""
        return w + self.N @ w

    def relative_displacement(self, u: np.ndarray) -> np.ndarray:
        """w = T^{-1} u = u - N u: at a nonmortar node its displacement relative to the mortar side's
        (D^{-1} M u_m); elsewhere u itself."""
        return u - self.N @ u

    def _new_core_solver(self, law: str, options: CycleOptions, frame_fixed=None, frame_values=None, load=None,
                         fixed_values=None, take_matrix: bool = False):
        # the transformed matrix stays here (take_matrix is declined): it is what checks and reports multiply with
        c = self.contact
        values = self.fixed_values if fixed_values is None else fixed_values
        solver = (_core.ContactSolver2D if self.mesh.dim == 2 else _core.ContactSolver3D)(self.A, self.load if load is None else load, self.fixed, values,
                                       c.nodes, c.normals, c.gaps, self.coefficients, law,
                                       [t.as_tuple() for t in self.transfers],
                                       dict(cycle=options.cycle, nu1=options.nu1, nu2=options.nu2),
                                       frame_fixed=frame_fixed, frame_values=frame_values)
        if self.tied_correction and law != "linear":
            if not hasattr(solver, "enable_tied_correction"):
                raise ValueError("tied_correction needs a core with enable_tied_correction (rebuild the core)")
            solver.enable_tied_correction()
        return solver

    def _result(self, raw: dict, method: str, options: CycleOptions):
        raw = dict(raw)
        raw["u"] = self.to_canonical(np.asarray(raw["u"]))
        res = super()._result(raw, method, options)
        res.extra["body_id"] = self.body_id
        return res

    def write_vtu(self, path, result) -> None:
        """One VTU file with all bodies: the result's point data and a body_id field."""
        from ..mesh.io import write_mesh

        data = result.point_data()
        data["body_id"] = self.body_id
        write_mesh(path, self.mesh, point_data=data)


class TwoBodyProblem(MultiBodyProblem):
    """Two (or more) bodies through one mortar pair (or a sequence of pairs): MultiBodyProblem."""

    def __init__(self, bodies: Sequence[Body], pair: ContactPair, friction=None, cycle: str = "F", nu1: int = 3,
                 nu2: int = 3, tied_correction: bool = True):
        if not isinstance(pair, ContactPair) and not (isinstance(pair, (list, tuple))
                                                      and all(isinstance(q, ContactPair) for q in pair)):
            raise TypeError("pair must be a ContactPair")
        super().__init__(bodies, pair, friction, cycle, nu1, nu2, tied_correction)


def _union_mesh(meshes: Sequence[Mesh], offsets: np.ndarray) -> Mesh:
    cell_types = {m.cell_type for m in meshes}
    if len(cell_types) != 1:
        raise ValueError(f"the bodies need one cell type for one output mesh, got {sorted(cell_types)}")
    return Mesh._trusted(np.vstack([m.points for m in meshes]),
                         np.vstack([m.cells + o for m, o in zip(meshes, offsets)]), meshes[0].cell_type,
                         np.vstack([m.facets + o for m, o in zip(meshes, offsets)]),
                         np.concatenate([m.facet_tags for m in meshes]))
