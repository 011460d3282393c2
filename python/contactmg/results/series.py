"""Time series output that ParaView opens as one: a .pvd collection of VTU files, one per time
value, and its reader (for tests and post-processing: a list of (time, meshio.Mesh))."""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import Callable, List, Sequence, Tuple
from xml.sax.saxutils import quoteattr


def write_pvd_collection(path, frames: Sequence[Tuple[float, object, dict]], write_mesh: Callable) -> List[str]:
    """Write `path` (.pvd) and <stem>_<k>.vtu next to it for frames (time, mesh, point_data);
    the collection names the VTU files relative to itself, so the folder can be moved whole."""
    path = os.fspath(path)
    if not path.lower().endswith(".pvd"):
        raise ValueError(f"a time series is written as a .pvd collection: {path} does not end in .pvd")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"cannot write {path}: directory {folder} does not exist")
    stem = os.path.splitext(os.path.basename(path))[0]
    width = max(4, len(str(len(frames))))
    files, entries = [], []
    for k, (t, mesh, point_data) in enumerate(frames, start=1):
        name = f"{stem}_{k:0{width}d}.vtu"
        write_mesh(os.path.join(folder, name), mesh, point_data=point_data)
        files.append(os.path.join(folder, name))
        entries.append(f'    <DataSet timestep="{float(t)!r}" group="" part="0" file={quoteattr(name)}/>')
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    with open(path, "w") as fh:
        fh.write(text)
    return files


def read_pvd_collection(path) -> List[Tuple[float, object]]:
    """(time, meshio.Mesh) for every data set of a .pvd collection, in file order."""
    import meshio

    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"cannot read the collection {path}: {e}") from None
    out = []
    for ds in root.iter("DataSet"):
        out.append((float(ds.get("timestep")), meshio.read(os.path.join(folder, ds.get("file")))))
    return out
