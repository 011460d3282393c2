"""Results of a distributed solve as files ParaView opens: one VTU piece per rank tied together by a
.pvtu file (nothing gathered), or one ordinary VTU gathered on one rank (the file a serial solve
writes), and a reader of .pvtu files that merges the pieces back into one mesh in global order.

Layout of a parallel file `out/result.pvtu`: the pieces lie in a folder named after it,
`out/result/result_<rank>.vtu`, and the .pvtu names them relative to itself (`result/result_0.vtu`),
so the .pvtu and its folder can be moved together. Piece r holds rank r's OWNED cells and the nodes
they use (ghost nodes included: a node on a partition boundary appears in every piece whose cells
use it, as usual for .pvtu files), renumbered compactly in ascending global id. Besides the given
fields every piece carries the point array `global_id` (the node's global id, int64) and the cell
arrays `global_cell_id` (int64) and `rank` (int32), which read_pvtu uses to merge the pieces.

Conventions are the serial writer's (contactmg.mesh.io.to_meshio): points get 3 coordinates and
point arrays of 2 components (2D vectors) get a zero third one; point arrays of more than two
dimensions are flattened per node, as are cell arrays per cell. Unlike the serial writer, neither
file carries the boundary facets as a second cell block (a rank does not know the serial order of
the facets) nor the "gmsh:physical" cell tags."""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import Dict, List, Optional, Tuple
from xml.sax.saxutils import quoteattr

import numpy as np

from .comm import get_comm, raise_together

# numpy dtype -> VTK type name, as meshio's VTU writer names them (a .pvtu must declare the same)
VTK_TYPES = {np.dtype(t): name for t, name in [
    ("float32", "Float32"), ("float64", "Float64"), ("int8", "Int8"), ("int16", "Int16"), ("int32", "Int32"),
    ("int64", "Int64"), ("uint8", "UInt8"), ("uint16", "UInt16"), ("uint32", "UInt32"), ("uint64", "UInt64")]}
# arrays the pieces carry besides the caller's fields
GLOBAL_ID, GLOBAL_CELL_ID, RANK = "global_id", "global_cell_id", "rank"


def piece_path(path, rank: int) -> Tuple[str, str]:
    """(file name of rank's piece, its name relative to the folder of the .pvtu `path`)."""
    path = os.fspath(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    relative = f"{stem}/{stem}_{rank}.vtu"
    return os.path.join(os.path.dirname(os.path.abspath(path)), stem, f"{stem}_{rank}.vtu"), relative


def meshio_cell_type(level) -> str:
    """meshio's name of the level's cells, from their node count and the dimension."""
    k, d = level.cells.shape[1], level.points.shape[1]
    names = {(3, 2): "triangle", (4, 2): "quad", (4, 3): "tetra", (8, 3): "hexahedron"}
    if (k, d) not in names:
        raise ValueError(f"cells of {k} nodes in {d}D are none of triangle, quad, tetra, hexahedron")
    return names[(k, d)]


def _column_data(name: str, values, count: int, what: str) -> np.ndarray:
    """`values` as an array of `count` rows of at most two dimensions in a type VTU files hold."""
    v = np.asarray(values)
    if v.ndim == 0 or len(v) != count:
        raise ValueError(f"{what} data {name!r} needs one row per local {'node' if what == 'point' else 'cell'} "
                         f"({count}), got shape {v.shape}")
    if v.ndim > 2:
        v = v.reshape(count, -1)
    if v.dtype == bool:
        v = v.astype(np.uint8)
    if v.dtype not in VTK_TYPES:
        raise ValueError(f"{what} data {name!r} has dtype {v.dtype}, which VTU files do not hold "
                         f"(one of {', '.join(str(t) for t in VTK_TYPES)})")
    return v


def _pad3(v: np.ndarray) -> np.ndarray:
    """Two components padded with a zero third one (points and 2D vectors), exactly as the serial
    writer does (its zeros are float64: an integer pair becomes float64 there too)."""
    if v.ndim == 2 and v.shape[1] == 2:
        return np.c_[v, np.zeros(len(v))]
    return v


def _checked_fields(level, point_data, cell_data) -> Tuple[Dict[str, np.ndarray], Dict[str, np.ndarray]]:
    """The caller's fields checked against the local nodes and cells, reserved names refused; point
    arrays of two components already padded to three."""
    point_data, cell_data = dict(point_data or {}), dict(cell_data or {})
    for name in (GLOBAL_ID, GLOBAL_CELL_ID, RANK):
        if name in point_data or name in cell_data:
            raise ValueError(f"{name!r} is written by the distributed writer itself: choose another field name")
    pd = {k: _pad3(_column_data(k, v, len(level.gid), "point")) for k, v in point_data.items()}
    cd = {k: _column_data(k, v, len(level.cells), "cell") for k, v in cell_data.items()}
    return pd, cd


def _signature(pd: Dict[str, np.ndarray], cd: Dict[str, np.ndarray]) -> tuple:
    """Names, VTK types and component counts of the point and of the cell fields as written."""
    def sig(arrays):
        return tuple((k, VTK_TYPES[v.dtype], 1 if v.ndim == 1 else v.shape[1]) for k, v in arrays.items())
    return sig(pd), sig(cd)


def _piece_mesh(level, pd: Dict[str, np.ndarray], cd: Dict[str, np.ndarray]):
    """meshio.Mesh of this rank's owned cells and the nodes they use, in ascending global id."""
    import meshio

    own_c = level.owned_cells
    used = np.zeros(len(level.gid), bool)
    used[level.cells[own_c]] = True
    nodes = np.flatnonzero(used)
    new = np.full(len(level.gid), -1, np.int64)
    new[nodes] = np.arange(len(nodes))
    point_data = {k: v[nodes] for k, v in pd.items()}
    point_data[GLOBAL_ID] = level.gid[nodes].astype(np.int64)
    cell_data = {k: [v[own_c]] for k, v in cd.items()}
    cell_data[GLOBAL_CELL_ID] = [level.cell_gid[own_c].astype(np.int64)]
    cell_data[RANK] = [np.full(len(own_c), level.rank, np.int32)]
    points = _pad3(np.asarray(level.points[nodes], float))
    return meshio.Mesh(points, [(meshio_cell_type(level), new[level.cells[own_c]])], point_data=point_data,
                       cell_data=cell_data)


def _pdata_arrays(signature: tuple, indent: str) -> List[str]:
    """One PDataArray line per (name, VTK type, components)."""
    return [f'{indent}<PDataArray type="{t}" Name={quoteattr(name)} NumberOfComponents="{c}"/>'
            for name, t, c in signature]


def pvtu_text(point_sig: tuple, cell_sig: tuple, sources: List[str]) -> str:
    """The XML of a .pvtu file (VTK's PUnstructuredGrid) declaring the given point and cell arrays
    ((name, VTK type, components) each) and naming the pieces `sources`."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="PUnstructuredGrid" version="0.1" byte_order="LittleEndian">',
             '  <PUnstructuredGrid GhostLevel="0">',
             '    <PPoints>', '      <PDataArray type="Float64" NumberOfComponents="3"/>', '    </PPoints>',
             '    <PPointData>', *_pdata_arrays(point_sig, "      "), '    </PPointData>',
             '    <PCellData>', *_pdata_arrays(cell_sig, "      "), '    </PCellData>',
             *[f'    <Piece Source={quoteattr(s)}/>' for s in sources],
             '  </PUnstructuredGrid>', '</VTKFile>', '']
    return "\n".join(lines)


def _check_target(path: str, ext: str) -> None:
    """Refuse a path without the extension or in a folder that does not exist."""
    if not path.lower().endswith(ext):
        raise ValueError(f"{path} does not end in {ext}")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"cannot write {path}: directory {folder} does not exist")


def write_pvtu(path, level, point_data: Optional[Dict[str, np.ndarray]] = None,
               cell_data: Optional[Dict[str, np.ndarray]] = None, comm=None) -> List[str]:
    """Write a parallel VTU file `path` (.pvtu) of one level (a LocalLevel): every rank writes its
    piece, rank 0 the .pvtu (see the module's doc for the layout). `point_data`: arrays of one row
    per LOCAL node (owned and ghosts; a ghost must hold its owner's value: update the halo first);
    `cell_data`: of one row per local cell (only the owned rows are written). Every rank must pass
    the same field names with the same dtypes and components. Returns the files this rank wrote.
    Collective: an error on one rank is raised on every rank (DistributedError)."""
    comm = get_comm(comm)
    path = os.fspath(path)
    with raise_together(comm):
        _check_target(path, ".pvtu")
        pd, cd = _checked_fields(level, point_data, cell_data)
        signature = _signature(pd, cd)
    signatures = comm.allgather(signature)
    with raise_together(comm):
        differ = [r for r, s in enumerate(signatures) if s != signatures[0]]
        if differ:
            raise ValueError(f"the fields of rank(s) {differ} differ from rank 0's in name, dtype or components: "
                             f"{signatures[differ[0]]} != {signatures[0]}")
        import meshio

        piece, _ = piece_path(path, comm.rank)
        os.makedirs(os.path.dirname(piece), exist_ok=True)  # every rank: the folder may be rank-local
        meshio.write(piece, _piece_mesh(level, pd, cd), file_format="vtu")
    written = [piece]
    with raise_together(comm):
        if comm.rank == 0:
            point_sig, cell_sig = signature
            point_sig += ((GLOBAL_ID, "Int64", 1),)
            cell_sig += ((GLOBAL_CELL_ID, "Int64", 1), (RANK, "Int32", 1))
            sources = [piece_path(path, r)[1] for r in range(comm.size)]
            with open(path, "w") as fh:
                fh.write(pvtu_text(point_sig, cell_sig, sources))
            written.append(os.path.abspath(path))
    return written


def write_gathered_vtu(path, level, point_data: Optional[Dict[str, np.ndarray]] = None,
                       cell_data: Optional[Dict[str, np.ndarray]] = None, comm=None, root: int = 0) -> Optional[str]:
    """Gather one level (a LocalLevel) and its fields on rank `root`, which writes one ordinary VTU
    file `path`: node i is the node of global id i and cell j the cell of global id j, so the file
    holds what the serial writer writes for the serial hierarchy's mesh and the same fields (without
    the boundary facets, see the module's doc). `point_data` and `cell_data` as for write_pvtu; the
    owners' rows are gathered. Needs the whole level's memory on `root`. Returns the path on `root`,
    None elsewhere. Collective."""
    import meshio

    comm = get_comm(comm)
    path = os.fspath(path)
    with raise_together(comm):
        _check_target(path, ".vtu")
        pd, cd = _checked_fields(level, point_data, cell_data)
        own, own_c = level.owned, level.owned_cells
    got = comm.gather((level.gid[own], level.points[own], {k: v[own] for k, v in pd.items()},
                       level.cell_gid[own_c], level.gid[level.cells[own_c]], {k: v[own_c] for k, v in cd.items()}),
                      root=root)
    with raise_together(comm):
        if comm.rank == root:
            points, cells, pd_all, cd_all = _assemble(got, level.num_global_nodes, level.num_global_cells)
            mesh = meshio.Mesh(_pad3(points), [(meshio_cell_type(level), cells)],
                               point_data=pd_all,
                               cell_data={k: [v] for k, v in cd_all.items()})
            meshio.write(path, mesh, file_format="vtu")
    return path if comm.rank == root else None


def _assemble(got, n: int, m: int):
    """Whole-level points, cells (global node ids) and fields in global order from every rank's
    owned rows; each node and cell must come from exactly one rank."""
    seen, seen_c = np.zeros(n, np.int64), np.zeros(m, np.int64)
    points = cells = None
    pd: Dict[str, np.ndarray] = {}
    cd: Dict[str, np.ndarray] = {}
    for g, x, p, cg, c, cdata in got:
        if points is None:
            points = np.full((n, x.shape[1]), np.nan)
            cells = np.full((m, c.shape[1]), -1, np.int64)
            pd = {k: np.zeros((n,) + v.shape[1:], v.dtype) for k, v in p.items()}
            cd = {k: np.zeros((m,) + v.shape[1:], v.dtype) for k, v in cdata.items()}
        points[g], cells[cg] = x, c
        seen[g] += 1
        seen_c[cg] += 1
        for k, v in p.items():
            pd[k][g] = v
        for k, v in cdata.items():
            cd[k][cg] = v
    if np.any(seen != 1) or np.any(seen_c != 1):
        raise RuntimeError(f"{int(np.count_nonzero(seen != 1))} nodes and {int(np.count_nonzero(seen_c != 1))} "
                           "cells are not owned by exactly one rank")
    return points, cells, pd, cd


def pvtu_sources(path) -> List[str]:
    """The piece files a .pvtu names, as paths (relative ones taken from the .pvtu's folder)."""
    path = os.fspath(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"cannot read the parallel file {path}: {e}") from None
    grid = root.find("PUnstructuredGrid")
    if root.get("type") != "PUnstructuredGrid" or grid is None:
        raise ValueError(f"{path} is not a parallel unstructured grid (.pvtu)")
    folder = os.path.dirname(os.path.abspath(path))
    return [os.path.join(folder, p.get("Source")) for p in grid.findall("Piece")]


def read_pvtu(path):
    """A .pvtu file written by write_pvtu as one meshio.Mesh: the pieces read with meshio and merged
    by their point array `global_id` (node i of the result has global id i; a node held by several
    pieces must have the same coordinates and values in each), the cells in global cell order
    (`global_cell_id`). The result keeps those arrays and `rank`. meshio itself does not read .pvtu."""
    import meshio

    sources = pvtu_sources(path)
    if not sources:
        raise ValueError(f"{os.fspath(path)} names no piece")
    pieces = [meshio.read(s) for s in sources]
    for s, p in zip(sources, pieces):
        if GLOBAL_ID not in p.point_data or GLOBAL_CELL_ID not in p.cell_data or len(p.cells) != 1:
            raise ValueError(f"piece {s} lacks {GLOBAL_ID!r} or {GLOBAL_CELL_ID!r}, or has several cell blocks: "
                             "not written by write_pvtu")
    gid = np.concatenate([np.asarray(p.point_data[GLOBAL_ID], np.int64) for p in pieces])
    n = int(gid.max()) + 1
    first = np.full(n, -1, np.int64)
    first[gid[::-1]] = np.arange(len(gid))[::-1]  # the first row of every global id
    if np.any(first < 0):
        raise ValueError(f"{int(np.count_nonzero(first < 0))} global ids below {n} are in no piece")
    points = _merged("points", np.concatenate([p.points for p in pieces]), gid, first)
    point_data = {k: _merged(k, np.concatenate([p.point_data[k] for p in pieces]), gid, first)
                  for k in pieces[0].point_data}
    offsets = np.cumsum([0] + [len(p.points) for p in pieces])
    cell_gid = np.concatenate([np.asarray(p.cell_data[GLOBAL_CELL_ID][0], np.int64) for p in pieces])
    cells = np.concatenate([gid[o + p.cells[0].data] for o, p in zip(offsets, pieces)])
    if len(np.unique(cell_gid)) != len(cell_gid):
        raise ValueError("a global cell id appears in more than one piece")
    order = np.argsort(cell_gid)
    cell_data = {k: [np.concatenate([p.cell_data[k][0] for p in pieces])[order]] for k in pieces[0].cell_data}
    return meshio.Mesh(points, [(pieces[0].cells[0].type, cells[order])], point_data=point_data, cell_data=cell_data)


def _merged(name: str, rows: np.ndarray, gid: np.ndarray, first: np.ndarray) -> np.ndarray:
    """The rows of every global id (from its first piece), checked equal in every piece that holds it."""
    out = rows[first]
    same = out[gid] == rows
    if rows.dtype.kind == "f":
        same |= np.isnan(out[gid]) & np.isnan(rows)
    if not np.all(same):
        bad = int(gid[np.flatnonzero(~same.reshape(len(rows), -1).all(axis=1))[0]])
        raise ValueError(f"{name!r} of node {bad} differs between the pieces that hold it")
    return out
