"""Mesh input and output through meshio."""
from __future__ import annotations

import os
from typing import Dict, Optional, Union

import meshio
import numpy as np

from ..mesh.mesh import CELL_DIM, FACET_NODES, Mesh, boundary_facets

_TAG_KEYS = ("gmsh:physical", "tag", "tags", "cell_tags", "medit:ref")
_FACET_TYPE = {"triangle": "line", "quad": "line", "tetra": "triangle", "hexahedron": "quad"}
_UNSUPPORTED_2D = {"triangle6", "triangle7", "quad8", "quad9", "polygon"}
_UNSUPPORTED_3D = {"tetra10", "hexahedron20", "hexahedron27", "wedge", "pyramid", "wedge15", "pyramid13"}
# Formats that keep what write_mesh hands over (cells, tagged facets, point data), by extension.
# meshio reads ".msh" as ANSYS or Gmsh; here it is Gmsh. Surface formats (.stl, .obj, ...) would
# drop the cells or the data without a word: refused.
WRITE_FORMATS = {".vtu": "vtu", ".vtk": "vtk", ".msh": "gmsh22", ".xdmf": "xdmf", ".xmf": "xdmf"}
# Coordinates beyond the mesh's dimension that are zero up to this (relative to the extent) are
# round-off of a planar mesh, not a third dimension.
PLANAR_TOL = 1e-12


def read_mesh(source: Union[str, os.PathLike, meshio.Mesh], dim: Optional[int] = None) -> Mesh:
    """A coarse mesh from anything meshio reads (.msh, .vtu, .vtk, .xdmf, ...). Facet tags come from
    line (2D) or triangle/quad (3D) blocks with physical tags; other boundary facets get tag 0."""
    if isinstance(source, meshio.Mesh):
        m = source
    else:
        path = os.fspath(source)
        if not os.path.exists(path):
            raise ValueError(f"cannot read mesh {path}: no such file")
        try:
            m = meshio.read(path)
        except (Exception, SystemExit) as e:  # meshio raises many kinds, and exits on some files
            raise ValueError(f"cannot read mesh {path}: {e or type(e).__name__}") from None
    types = [b.type for b in m.cells]
    volume = [t for t in types if t in ("tetra", "hexahedron")] or [t for t in types if t in _UNSUPPORTED_3D]
    if not volume:
        volume = [t for t in types if t in ("triangle", "quad")] or [t for t in types if t in _UNSUPPORTED_2D]
    if not volume:
        raise ValueError(f"the mesh has no supported cells (found {sorted(set(types)) or 'none'}; "
                         "supported: triangle, quad, tetra, hexahedron)")
    kinds = sorted(set(volume))
    if any(k in _UNSUPPORTED_2D | _UNSUPPORTED_3D for k in kinds):
        raise ValueError(f"cell type {kinds[0]} is not supported (first-order triangle, quad, tetra, hexahedron only)")
    if len(kinds) > 1:
        raise ValueError(f"mixed cell types {kinds} are not supported")
    cell_type = kinds[0]
    d = CELL_DIM[cell_type] if dim is None else dim
    pts = np.asarray(m.points, dtype=float)
    if pts.shape[1] > d:
        extent = float(np.abs(pts[:, :d] - pts[:, :d].min(axis=0)).max(initial=0.0)) if len(pts) else 0.0
        off = float(np.abs(pts[:, d:]).max(initial=0.0))
        if not off <= PLANAR_TOL * max(extent, 1e-300):
            raise ValueError(f"{cell_type} mesh has non-zero coordinates beyond dimension {d} (up to {off:.3g}, "
                             f"the mesh extent is {extent:.3g})")
        pts = pts[:, :d]
    cells = np.vstack([b.data for b in m.cells if b.type == cell_type]).astype(np.int64)
    cell_tags = _cell_tags(m, cell_type)
    tmp = Mesh(pts, cells, cell_type, np.zeros((0, FACET_NODES[cell_type]), np.int64), np.zeros(0, np.int64),
               cell_tags)
    facets = boundary_facets(tmp.cells, cell_type)
    tags = np.zeros(len(facets), np.int64)
    ftype = _FACET_TYPE[cell_type]
    lookup = {tuple(sorted(f)): i for i, f in enumerate(facets.tolist())}
    for key in _TAG_KEYS:
        if key not in m.cell_data:
            continue
        for block, data in zip(m.cells, m.cell_data[key]):
            if block.type != ftype:
                continue
            for f, t in zip(block.data.tolist(), np.asarray(data).tolist()):
                i = lookup.get(tuple(sorted(f)))
                if i is not None:
                    if not (np.isfinite(t) and float(t) == int(t)):
                        raise ValueError(f"facet {f} has tag {t!r}: facet tags must be integers")
                    tags[i] = int(t)
        break
    # the cells are checked and the facets are the boundary facets by construction
    return Mesh._trusted(tmp.points, tmp.cells, cell_type, facets, tags, tmp.cell_tags)


def _cell_tags(m: meshio.Mesh, cell_type: str) -> Optional[np.ndarray]:
    """The region tag of every cell of type `cell_type` (gmsh's physical tag of its volume or
    surface; None where the file gives none)."""
    for key in _TAG_KEYS:
        if key in m.cell_data:
            data = [np.asarray(d) for b, d in zip(m.cells, m.cell_data[key]) if b.type == cell_type]
            return np.concatenate(data) if data else None
    return None


def _pad(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v)
    if v.ndim == 2 and v.shape[1] == 2:
        return np.c_[v, np.zeros(len(v))]
    return v


def to_meshio(mesh: Mesh, point_data: Optional[Dict[str, np.ndarray]] = None,
              cell_data: Optional[Dict[str, np.ndarray]] = None) -> meshio.Mesh:
    """meshio.Mesh with 3 coordinates (ParaView) and 2-vectors padded to 3; facets go along as a
    second block carrying their tags in "gmsh:physical"."""
    pts = _pad(mesh.points)
    blocks = [(mesh.cell_type, mesh.cells), (_FACET_TYPE[mesh.cell_type], mesh.facets)]
    pd = {k: _pad(v) for k, v in (point_data or {}).items()}
    cd = {"gmsh:physical": [np.asarray(mesh.cell_tags, np.int64), mesh.facet_tags]}
    for k, v in (cell_data or {}).items():
        v = np.asarray(v)
        if len(v) != mesh.num_cells:
            raise ValueError(f"cell data {k!r} needs one entry per cell ({mesh.num_cells}), got {len(v)}")
        cd[k] = [v, np.zeros((len(mesh.facets),) + v.shape[1:], v.dtype)]
    return meshio.Mesh(pts, blocks, point_data=pd, cell_data=cd)


def write_mesh(path: Union[str, os.PathLike], mesh: Mesh, point_data: Optional[Dict[str, np.ndarray]] = None,
               cell_data: Optional[Dict[str, np.ndarray]] = None, **kwargs) -> None:
    """Write through meshio in the format the extension names: .vtu, .vtk, .msh (Gmsh 2.2),
    .xdmf/.xmf; meshio's `file_format=` picks another format explicitly. `point_data`: arrays of
    one row per node; `cell_data`: of one row per cell (the facets written along get zeros)."""
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if "file_format" not in kwargs:
        if ext not in WRITE_FORMATS:
            raise ValueError(f"cannot write {path}: {'unknown extension ' + repr(ext) if ext else 'no extension'} "
                             f"(write_mesh writes {', '.join(WRITE_FORMATS)})")
        kwargs["file_format"] = WRITE_FORMATS[ext]
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"cannot write {path}: directory {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"cannot write {path}: directory {folder} is not writable")
    m = to_meshio(mesh, point_data, cell_data)
    if kwargs["file_format"].startswith("gmsh"):
        m.cell_data["gmsh:geometrical"] = m.cell_data["gmsh:physical"]
    try:
        meshio.write(path, m, **kwargs)
    except (Exception, SystemExit) as e:
        raise ValueError(f"cannot write {path}: {e or type(e).__name__}") from None
