"""The distributed mesh hierarchy: every rank refines its own coarse cells, plus one layer of ghost
cells around them, with the project's own uniform refinement, and numbers every node and cell with
its GLOBAL id: the number it has in the serial hierarchy (MeshHierarchy.build) of the same coarse
mesh. The serial and the distributed hierarchies are then the same meshes, node for node.

The serial refinement (cpp/fem/refine_2d.hpp, refine_3d.hpp) numbers the fine nodes of a level with
N nodes, NE edges, NQ quadrilateral faces (hexahedra only) and M cells as
    the level's nodes (ids kept) | one node per edge, edges in ascending (smaller id, larger id)
    | one per quadrilateral face, faces in ascending sorted-id order | one per cell (quadrilaterals,
    hexahedra), in cell order,
and the children of cell c are cells c * children + j. Each rank numbers its local nodes in
ascending global id; the refinement then keeps that order for the new nodes (its edges and faces
are sorted by local ids, which sort as the global ones do), so a local refinement computes every
coordinate from the same parents in the same order as the serial one: bitwise the same points and
the same choice of the tetrahedra's interior diagonals.

What a rank cannot know locally is an edge's position in the global sorted list: it is
(edges whose smaller node has a smaller id) + (the edge's rank among the edges of its smaller
node). The owner of a node holds all cells around it, so it counts that node's edges; a distributed
prefix sum over node ids (each rank sums a block of ids) gives every owner its nodes' offsets;
ghost edges get their ids from the owner of their smaller node. Faces likewise (by their smallest
node). Cells need nothing: their ids follow from their parents'.

Ownership: a node belongs to the lowest rank among the cells that contain it (cells belong to the
rank of their coarse ancestor). That rank is computed on every rank from the coarse mesh alone: a
node lies in exactly the coarse cells that contain all the coarse vertices it descends from (its
"origin", at most one cell's vertices), so each rank knows the owner of each of its nodes without
asking. A coarse node keeps its owner on every level, and the parents of an owned node are nodes
of an owned cell: the prolongation rows of owned nodes are local.

A point-wise boundary projector moves the new boundary nodes as the serial build does; then every
ghost takes its owner's position before the next refinement. The serial refinement projects a node
on a rim (between a curved and a flat face) by the smaller tag of the facets at the node; a ghost
may hold only one of them, its owner holds all.

Once every level is built, the nodes of each level above the coarsest are renumbered in ascending
(colour, global id) for the sweeps (_order_by_colour says why the sums keep their bits)."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from .. import _core
from ..mesh.mesh import _LOCAL_FACETS, CELL_NODES, Mesh, unique_rows
from .comm import get_comm, raise_together
from .colouring import colour_level
from .exchange import Halo
from .partition import partition


@dataclass
class LocalTransfer:
    """The prolongation rows of this rank's owned fine nodes: fine node rows[i] (a local index of the
    fine level) = sum of weight[k] * coarse node parent[k] (local index of the level below) for k in
    ptr[i]:ptr[i+1]; parent_gid holds the parents' global ids."""

    rows: np.ndarray
    ptr: np.ndarray
    parent: np.ndarray
    parent_gid: np.ndarray
    weight: np.ndarray


@dataclass
class LocalLevel:
    """One level on one rank: its owned cells and one layer of ghost cells (every cell sharing a node
    with an owned one), their nodes each with its owner rank: in ascending global id on the coarsest
    level, in ascending (colour, global id) above it (_order_by_colour)."""

    points: np.ndarray          # (n, d) local nodes' coordinates
    cells: np.ndarray           # (m, k) local node indices
    cell_gid: np.ndarray        # (m,) ascending global cell ids
    cell_owner: np.ndarray      # (m,) rank of each cell (of its coarse ancestor)
    gid: np.ndarray             # (n,) global node ids
    owner: np.ndarray           # (n,) owner rank of each node
    facets: np.ndarray          # boundary facets of the local cells (local node indices)
    facet_tags: np.ndarray
    num_global_nodes: int
    num_global_cells: int
    rank: int
    # (n, k) coarse vertices each node descends from, -1 padded; kept on the finest level only
    origin: Optional[np.ndarray] = field(repr=False)
    transfer: Optional[LocalTransfer] = None  # from the level below (None on the coarse level)
    halo: Optional[Halo] = None
    # (n,) each node's colour (colouring.py); the nodes are then in ascending (colour, global id)
    colour: Optional[np.ndarray] = None

    @property
    def owned(self) -> np.ndarray:
        """Local indices of the nodes this rank owns."""
        return np.flatnonzero(self.owner == self.rank)

    @property
    def ghosts(self) -> np.ndarray:
        """Local indices of the nodes other ranks own."""
        return np.flatnonzero(self.owner != self.rank)

    @property
    def owned_cells(self) -> np.ndarray:
        """Local indices of this rank's own cells."""
        return np.flatnonzero(self.cell_owner == self.rank)


def _rows_lookup(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Index in `table` of every row of `query` (-1 where absent); rows of non-negative integers."""
    query = np.asarray(query, np.int64)
    if not len(query):
        return np.zeros(0, np.int64)
    table = np.asarray(table, np.int64).reshape(-1, query.shape[1])
    _, inv = unique_rows(np.vstack([table, query]), return_inverse=True)
    where = np.full(int(inv.max()) + 1, -1, np.int64)
    where[inv[:len(table)]] = np.arange(len(table))
    return where[inv[len(table):]]


def _facets_of_cells(facets: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Mask of the facets (rows of node ids) that are faces of some cell of `cells`."""
    if not len(facets):
        return np.zeros(0, bool)
    local = np.array(_LOCAL_FACETS[cell_type])
    own = np.sort(cells[:, local].reshape(-1, local.shape[1]), axis=1)
    return _rows_lookup(own, np.sort(facets, axis=1)) >= 0


def _union(rows: List[np.ndarray], width: int) -> np.ndarray:
    """Row-wise union of sets of coarse vertices (rows padded with -1 in front), as rows of `width`."""
    allv = np.sort(np.concatenate(rows, axis=1), axis=1)
    allv[:, 1:][allv[:, 1:] == allv[:, :-1]] = -1
    allv = np.sort(allv, axis=1)
    if allv.shape[1] > width and np.any(allv[:, -width - 1] >= 0):
        raise RuntimeError("a new node descends from more coarse vertices than one cell has")  # pragma: no cover
    return allv[:, -width:]


def _ask(comm, dest: np.ndarray, rows: np.ndarray, answer) -> np.ndarray:
    """Send each row of `rows` to rank dest[i], where answer(received rows) -> one value per row; the
    answers come back in the order of `rows`. Collective (every rank calls it, with rows or none)."""
    size = comm.size
    out = np.empty(len(rows), np.int64)
    picks = [np.flatnonzero(dest == r) for r in range(size)]
    received = comm.alltoall([rows[p] for p in picks])
    back = comm.alltoall([np.asarray(answer(q), np.int64) for q in received])
    for p, b in zip(picks, back):
        out[p] = b
    return out


def _prefix_by_id(comm, ids: np.ndarray, counts: np.ndarray, total_ids: int) -> Tuple[np.ndarray, int]:
    """The exclusive prefix sum over all global ids 0..total_ids-1 of counts given by the ranks (each id
    by at most one rank; ids not given count 0), at the given ids, and the sum of all counts. Rank r
    adds up the block of ids [r * b, (r + 1) * b): no rank holds more than its block."""
    size, rank = comm.size, comm.rank
    block = max(1, -(-total_ids // size))
    dest = ids // block
    picks = [np.flatnonzero(dest == r) for r in range(size)]
    received = comm.alltoall([(ids[p], counts[p]) for p in picks])
    lo = rank * block
    mine = np.zeros(max(0, min(total_ids, lo + block) - lo), np.int64)
    for i, c in received:
        mine[i - lo] = c
    before = np.cumsum(mine) - mine
    sums = comm.allgather(int(mine.sum()))
    offset = sum(sums[:rank])
    back = comm.alltoall([before[i - lo] + offset for i, _ in received])
    out = np.empty(len(ids), np.int64)
    for p, b in zip(picks, back):
        out[p] = b
    return out, int(sum(sums))


class _Owners:
    """The owner of a node from its origin (the coarse vertices it descends from): the lowest part
    among the coarse cells that contain all of them. Cached per origin."""

    def __init__(self, coarse: Mesh, part: np.ndarray):
        self.cells = coarse.cells.astype(np.int64)
        self.part = part
        flat = self.cells.ravel()
        self.order = np.argsort(flat, kind="stable") // self.cells.shape[1]
        self.ptr = np.zeros(coarse.num_points + 1, np.int64)
        np.cumsum(np.bincount(flat, minlength=coarse.num_points), out=self.ptr[1:])
        self.cache: Dict[tuple, int] = {}

    def __call__(self, origin: np.ndarray) -> np.ndarray:
        if not len(origin):
            return np.zeros(0, np.int64)
        uniq, inv = unique_rows(origin + 1, return_inverse=True)
        out = np.empty(len(uniq), np.int64)
        for i, row in enumerate(uniq - 1):
            key = tuple(row.tolist())
            got = self.cache.get(key)
            if got is None:
                verts = row[row >= 0]
                cand = self.order[self.ptr[verts[-1]]:self.ptr[verts[-1] + 1]]
                holds = (self.cells[cand][:, :, None] == verts[None, None, :]).any(axis=1).all(axis=1)
                got = self.cache[key] = int(self.part[cand[holds]].min())
            out[i] = got
        return out[inv]


def _select_rows(ptr: np.ndarray, rows: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """CSR pointer of the chosen rows and the entry indices they hold."""
    counts = ptr[rows + 1] - ptr[rows]
    new_ptr = np.zeros(len(rows) + 1, np.int64)
    np.cumsum(counts, out=new_ptr[1:])
    entries = np.repeat(ptr[rows], counts) + np.arange(new_ptr[-1]) - np.repeat(new_ptr[:-1], counts)
    return new_ptr, entries


def _trim(rank: int, points, cells, cell_gid, cell_owner, gid, owner, origin, facets, tags, cell_type):
    """Keep the owned cells and the cells sharing a node with them (one ghost layer), and their nodes
    in the same (ascending global id) order. Returns the kept arrays and the kept node indices."""
    touch = np.zeros(len(points), bool)
    touch[cells[cell_owner == rank]] = True
    keep_c = np.flatnonzero(touch[cells].any(axis=1))
    used = np.zeros(len(points), bool)
    used[cells[keep_c]] = True
    nodes = np.flatnonzero(used)
    new = np.full(len(points), -1, np.int64)
    new[nodes] = np.arange(len(nodes))
    cells = new[cells[keep_c]]
    facets = np.asarray(facets, np.int64)
    ok = np.all(used[facets], axis=1) if len(facets) else np.zeros(0, bool)
    facets, tags = new[facets[ok]], np.asarray(tags)[ok]
    inside = _facets_of_cells(facets, cells, cell_type)
    facets, tags = facets[inside], tags[inside]
    return (points[nodes], cells, cell_gid[keep_c], cell_owner[keep_c], gid[nodes], owner[nodes], origin[nodes],
            facets.reshape(-1, facets.shape[1] if facets.ndim == 2 else 1), tags, nodes)


class DistributedHierarchy:
    """Uniform refinements of a coarse mesh held by every rank, each rank holding its part of every
    level (LocalLevel) with global ids equal to the serial hierarchy's. See the module's doc."""

    def __init__(self, levels: List[LocalLevel], comm, part: np.ndarray, cell_type: str, build_seconds: float):
        self.levels = levels
        self.comm = comm
        self.part = part
        self.cell_type = cell_type
        self.build_seconds = build_seconds

    def __repr__(self) -> str:
        fine = self.levels[-1]
        return (f"DistributedHierarchy({self.cell_type}, {len(self.levels)} levels, {fine.num_global_nodes} fine nodes, "
                f"rank {self.comm.rank} of {self.comm.size}: {len(fine.owned)} owned, {len(fine.ghosts)} ghosts)")

    @classmethod
    def build(cls, coarse: Mesh, levels: int, comm=None, part: Optional[np.ndarray] = None,
              method: Optional[str] = None, projector=None) -> "DistributedHierarchy":
        """Partition `coarse` (the same mesh on every rank) among the ranks of `comm` (or take `part`,
        a rank per coarse cell) and refine each rank's part until there are `levels` levels.
        `projector(points, tags)` moves the new boundary nodes as in MeshHierarchy.build (a point-wise
        projector such as the generators' circle, sphere and cylinder projectors); every ghost node
        then takes its owner's position, which saw all the boundary facets at the node. Collective."""
        comm = get_comm(comm)
        t0 = time.perf_counter()
        with raise_together(comm):
            if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 1:
                raise ValueError(f"levels must be an integer >= 1, got {levels!r}")
            if coarse.cell_type not in CELL_NODES:
                raise ValueError(f"unknown cell type {coarse.cell_type!r}")
            _core.check_cells(coarse.points, coarse.cells, coarse.cell_type)
            if projector is not None and hasattr(projector, "project_refinement"):
                raise ValueError("a projector that follows the coarse facets (a CAD model's) is not distributed yet: "
                                 "build the hierarchy on one rank")
            if projector is not None and getattr(projector, "relax", False):
                raise ValueError("relaxation next to projected nodes is not distributed yet: use a projector "
                                 "without relax, or one rank")
        if part is None:
            part = partition(coarse, comm, method)
        with raise_together(comm):
            part = np.asarray(part, np.int64)
            if part.shape != (coarse.num_cells,):
                raise ValueError(f"part must hold one rank per coarse cell ({coarse.num_cells}), got shape {part.shape}")
            if part.min() < 0 or part.max() >= comm.size:
                raise ValueError(f"part holds ranks outside 0..{comm.size - 1}")
            empty = sorted(set(range(comm.size)) - set(np.unique(part).tolist()))
            if empty:
                raise ValueError(f"rank(s) {empty} have no coarse cell in part: every rank needs at least one")
            owners = _Owners(coarse, part)
            local = [cls._coarse_level(coarse, part, comm.rank, owners)]
        local[0].halo = Halo.build(comm, local[0].gid, local[0].owner)
        for _ in range(levels - 1):
            lev = cls._refine(local[-1], coarse.cell_type, comm, owners, projector)
            lev.halo = Halo.build(comm, lev.gid, lev.owner)
            if projector is not None:
                lev.halo.update(lev.points)  # a ghost may miss a boundary facet at the node: its owner has all
            local[-1].origin = None  # needed only to refine that level
            local.append(lev)
        _order_by_colour(local, comm)
        return cls(local, comm, part, coarse.cell_type, time.perf_counter() - t0)

    @staticmethod
    def _coarse_level(coarse: Mesh, part: np.ndarray, rank: int, owners: _Owners) -> LocalLevel:
        cells = coarse.cells.astype(np.int64)
        k = cells.shape[1]
        origin = np.full((coarse.num_points, k), -1, np.int64)
        origin[:, -1] = np.arange(coarse.num_points)
        owner = owners(origin)
        out = _trim(rank, coarse.points, cells, np.arange(coarse.num_cells, dtype=np.int64), part,
                    np.arange(coarse.num_points, dtype=np.int64), owner, origin, coarse.facets, coarse.facet_tags,
                    coarse.cell_type)
        points, cells, cell_gid, cell_owner, gid, owner, origin, facets, tags, _ = out
        return LocalLevel(np.ascontiguousarray(points, float), cells, cell_gid, cell_owner, gid, owner, facets, tags,
                          coarse.num_points, coarse.num_cells, rank, origin)

    @staticmethod
    def _refine(lev: LocalLevel, cell_type: str, comm, owners: _Owners, projector=None) -> LocalLevel:
        rank = comm.rank
        r = _core.refine(lev.points, lev.cells, cell_type, lev.facets, lev.facet_tags)
        if projector is not None:
            with raise_together(comm):
                _project(r, projector, lev.points.shape[1])
        ptr, parent, weight = (np.asarray(r[key]) for key in ("ptr", "parent", "weight"))
        ptr, parent = ptr.astype(np.int64), parent.astype(np.int64)
        n, m, k = len(lev.gid), len(lev.cells), lev.cells.shape[1]
        n_fine = len(ptr) - 1
        count = np.diff(ptr)
        ne = int(np.count_nonzero(count == 2))
        n_centre = m if cell_type in ("quad", "hexahedron") else 0
        nq = n_fine - n - ne - n_centre
        N, M = lev.num_global_nodes, lev.num_global_cells

        # edges: (smaller, larger) local nodes, in ascending order of both local and global ids
        pe = parent[ptr[n]:ptr[n + ne]].reshape(ne, 2)
        edge_gid, NE = _entity_ids(comm, lev, pe, N)
        # quadrilateral faces of hexahedra: four sorted local nodes, ascending
        pf = parent[ptr[n + ne]:ptr[n + ne + nq]].reshape(nq, 4)
        face_gid, NQ = _entity_ids(comm, lev, pf, N + NE) if cell_type == "hexahedron" else (np.zeros(0, np.int64), 0)
        centre_gid = N + NE + NQ + lev.cell_gid if n_centre else np.zeros(0, np.int64)
        gid = np.concatenate([lev.gid, edge_gid, face_gid, centre_gid])
        if np.any(np.diff(gid) <= 0):
            raise RuntimeError("the local refinement did not keep the global order of the nodes")  # pragma: no cover

        origin = np.concatenate([
            lev.origin,
            _union([lev.origin[pe[:, 0]], lev.origin[pe[:, 1]]], k),
            _union([lev.origin[pf[:, j]] for j in range(4)], k) if nq else np.zeros((0, k), np.int64),
            _union([lev.origin[lev.cells[:, j]] for j in range(k)], k) if n_centre else np.zeros((0, k), np.int64)])
        owner = owners(origin)

        fine_cells = np.asarray(r["cells"], np.int64)
        children = len(fine_cells) // m
        cell_gid = (lev.cell_gid[:, None] * children + np.arange(children)).ravel()
        cell_owner = np.repeat(lev.cell_owner, children)
        num_nodes = N + NE + NQ + (M if n_centre else 0)
        out = _trim(rank, np.asarray(r["points"], float), fine_cells, cell_gid, cell_owner, gid, owner, origin,
                    np.asarray(r["facets"], np.int64), np.asarray(r["facet_tags"]), cell_type)
        points, cells, cell_gid, cell_owner, gid, owner, origin, facets, tags, kept = out
        rows = np.flatnonzero(owner == rank)
        tptr, entries = _select_rows(ptr, kept[rows])
        transfer = LocalTransfer(rows, tptr, parent[entries], lev.gid[parent[entries]], np.asarray(weight)[entries])
        return LocalLevel(points, cells, cell_gid, cell_owner, gid, owner, facets, tags, num_nodes, M * children,
                          rank, origin, transfer)

    def free(self) -> None:
        """Release the halos' neighbourhood communicators (MPI holds them until freed or finalized)."""
        for lev in self.levels:
            if lev.halo is not None:
                lev.halo.free()

    def gathered(self, level: int, root: int = 0) -> Optional[Tuple[np.ndarray, np.ndarray]]:
        """(points (N, d) in global id order, cells (M, k) of global node ids in global cell order) of
        one level on rank `root`, from the owned nodes and cells of every rank; None on the others.
        Collective. For checks and output of a whole level; it needs the whole level's memory on root."""
        lev = self.levels[level]
        own, own_c = lev.owned, lev.owned_cells
        got = self.comm.gather((lev.gid[own], lev.points[own], lev.cell_gid[own_c], lev.gid[lev.cells[own_c]]),
                               root=root)
        if self.comm.rank != root:
            return None
        d, k = lev.points.shape[1], lev.cells.shape[1]
        points = np.full((lev.num_global_nodes, d), np.nan)
        cells = np.full((lev.num_global_cells, k), -1, np.int64)
        seen = np.zeros(lev.num_global_nodes, np.int64)
        seen_c = np.zeros(lev.num_global_cells, np.int64)
        for g, x, cg, c in got:
            points[g], cells[cg] = x, c
            seen[g] += 1
            seen_c[cg] += 1
        if np.any(seen != 1) or np.any(seen_c != 1):
            raise RuntimeError(f"level {level}: {int(np.count_nonzero(seen != 1))} nodes and "
                               f"{int(np.count_nonzero(seen_c != 1))} cells are not owned by exactly one rank")
        return points, cells


def _order_by_colour(levels: List[LocalLevel], comm) -> None:
    """Renumber the local nodes of every level above the coarsest in ascending (colour, global id),
    in place (the points, ids, owners, cells, facets, transfers and halo follow).

    Why: a Gauss-Seidel sweep visits the owned rows of one colour, then exchanges; in global id
    order those rows are spread over the whole matrix, and the sweep over them took twice the time
    of one over consecutive rows. Sorted by colour they are consecutive but for the ghosts among
    them. Why the sums keep their bits on every number of ranks: every sum over a node's neighbours,
    a coarse node's fine rows or a row's blocks runs in ascending local index, which is now
    ascending (colour, global id), and both are properties of the node, not of the partition. The
    coarsest level keeps the global order (it is gathered and solved, not swept)."""
    new_of_old = None  # of the level below
    for lev in levels[1:]:
        colour = colour_level(lev, comm)
        perm = np.lexsort((lev.gid, colour))
        below, new_of_old = new_of_old, np.empty(len(perm), np.int64)
        new_of_old[perm] = np.arange(len(perm))
        lev.points = np.ascontiguousarray(lev.points[perm])
        lev.gid, lev.owner, lev.colour = lev.gid[perm], lev.owner[perm], colour[perm]
        if lev.origin is not None:
            lev.origin = lev.origin[perm]
        lev.cells = new_of_old[lev.cells]
        if lev.facets.size:
            lev.facets = new_of_old[lev.facets]
        t = lev.transfer
        if t is not None:
            t.rows = new_of_old[t.rows]
            if below is not None:
                t.parent = below[t.parent]
        if lev.halo is not None:
            lev.halo.free()
        lev.halo = Halo.build(comm, lev.gid, lev.owner)


def _project(r: dict, projector, d: int) -> None:
    """Move the new boundary nodes of a refinement result in place, checked as the serial build does."""
    nb = np.asarray(r["boundary_nodes"], np.int64)
    if not len(nb):
        return
    moved = np.asarray(projector(r["points"][nb], r["boundary_tags"]), dtype=float)
    if moved.shape != (len(nb), d):
        raise ValueError(f"the boundary projector returned shape {moved.shape}, expected {(len(nb), d)}")
    if not np.all(np.isfinite(moved)):
        raise ValueError("the boundary projector returned a non-finite coordinate")
    r["points"][nb] = moved


def _entity_ids(comm, lev: LocalLevel, nodes: np.ndarray, first: int) -> Tuple[np.ndarray, int]:
    """Global ids (from `first` on) of the local edges or faces given by their ascending local nodes
    (rows, in ascending order), and how many there are globally. Numbered as the serial refinement
    numbers them: ascending by their nodes' global ids. The owner of an entity's smallest node holds
    all entities at that node: it counts them, a prefix sum over node ids gives its offset, and
    ranks that hold the entity as a ghost ask that owner."""
    rank = comm.rank
    lead = nodes[:, 0]
    keys = lev.gid[nodes]
    mine = lev.owner[lead] == rank
    # the entity's position among those of its smallest node: rows are sorted by that node
    position = np.arange(len(nodes)) - np.searchsorted(lead, lead, side="left")
    owned = lev.owned
    counts = np.bincount(lead[mine], minlength=len(lev.gid))[owned]
    offsets, total = _prefix_by_id(comm, lev.gid[owned], counts, lev.num_global_nodes)
    offset = np.zeros(len(lev.gid), np.int64)
    offset[owned] = offsets
    ids = np.full(len(nodes), -1, np.int64)
    ids[mine] = first + offset[lead[mine]] + position[mine]
    table, table_ids = keys[mine], ids[mine]

    def answer(query):
        at = _rows_lookup(table, query)
        if np.any(at < 0):
            raise RuntimeError(f"rank {rank} was asked for an entity it does not hold")  # pragma: no cover
        return table_ids[at]

    ids[~mine] = _ask(comm, lev.owner[lead[~mine]], keys[~mine], answer)
    return ids, total
