"""Distributed output written on any number of ranks and checked against the serial hierarchy: shared
by test_output.py (one process) and test_mpi_ranks.py (whose ranks run write_fields in mpi_checks.py
and whose test process then checks the files)."""
import os
import xml.etree.ElementTree as ET

import meshio
import numpy as np

from contactmg.distributed import DistributedHierarchy, read_pvtu, write_gathered_vtu, write_pvtu
from contactmg.distributed.output import pvtu_sources
from contactmg.mesh.generators import hertz_half_disk, hertz_projector
from contactmg.mesh.generators_3d import box
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.mesh.io import write_mesh

LEVELS = 3
# the half disk's new nodes on the arc are projected: ghosts must take their owners' positions
MESHES = {
    "triangle": (lambda: hertz_half_disk("triangle"), hertz_projector),
    "tetra": (lambda: box(3, 2, 2, cell="tetra"), lambda: None),
}


def fields(lev):
    """Point and cell data of a level known from the node and cell ids alone: the node coordinates
    themselves, the global ids, a scalar; per cell a 3 x 3 tensor (flattened to 9 on writing)."""
    point_data = {"x": lev.points, "gid": lev.gid, "s": np.sin(lev.gid)}
    cell_data = {"tensor": lev.cell_gid[:, None, None] + np.arange(9.0).reshape(3, 3) / 10}
    return point_data, cell_data


def serial_fields(mesh):
    """What fields() gives on the serial hierarchy's finest mesh."""
    g = np.arange(mesh.num_points)
    return ({"x": mesh.points, "gid": g, "s": np.sin(g)},
            {"tensor": np.arange(mesh.num_cells)[:, None] + np.arange(9.0) / 10})


def write_fields(folder, name, comm):
    """Build the distributed hierarchy of MESHES[name] on comm and write its finest level as
    <folder>/<name>.pvtu and <folder>/<name>_gathered.vtu. Collective."""
    make, projector = MESHES[name]
    d = DistributedHierarchy.build(make(), LEVELS, comm=comm, projector=projector())
    lev = d.levels[-1]
    point_data, cell_data = fields(lev)
    write_pvtu(os.path.join(folder, f"{name}.pvtu"), lev, point_data, cell_data, comm=comm)
    write_gathered_vtu(os.path.join(folder, f"{name}_gathered.vtu"), lev, point_data, cell_data, comm=comm)
    d.free()


def serial_mesh(name):
    make, projector = MESHES[name]
    return MeshHierarchy.build(make(), LEVELS, projector=projector()).meshes[-1]


def padded(x):
    return np.c_[x, np.zeros(len(x))] if x.shape[1] == 2 else x


def declared(parent):
    """{name: (VTK type, components)} of the (P)DataArray children of an XML element."""
    return {a.get("Name"): (a.get("type"), int(a.get("NumberOfComponents", "1"))) for a in parent}


def check_declarations(pvtu, ranks):
    """The .pvtu names one piece per rank, relative to itself, and declares exactly the arrays each
    piece holds (names, types, components)."""
    grid = ET.parse(pvtu).getroot().find("PUnstructuredGrid")
    sources = [p.get("Source") for p in grid.findall("Piece")]
    stem = os.path.splitext(os.path.basename(pvtu))[0]
    assert sources == [f"{stem}/{stem}_{r}.vtu" for r in range(ranks)]
    want_points = [(a.get("type"), a.get("NumberOfComponents")) for a in grid.find("PPoints")]
    want_pd, want_cd = declared(grid.find("PPointData")), declared(grid.find("PCellData"))
    assert set(want_pd) == {"x", "gid", "s", "global_id"} and set(want_cd) == {"tensor", "global_cell_id", "rank"}
    for source in pvtu_sources(pvtu):
        piece = ET.parse(source).getroot().find("UnstructuredGrid/Piece")
        assert [(a.get("type"), a.get("NumberOfComponents")) for a in piece.find("Points")] == want_points
        assert declared(piece.find("PointData")) == want_pd, source
        assert declared(piece.find("CellData")) == want_cd, source


def check_pieces(pvtu, mesh, ranks):
    """Every cell of the level lies in exactly one piece, the piece of its rank; every node of a
    piece is used by its cells; on several ranks some nodes lie in several pieces."""
    cell_ids, nodes = [], 0
    for r, source in enumerate(pvtu_sources(pvtu)):
        p = meshio.read(source)
        assert np.all(p.cell_data["rank"][0] == r)
        assert len(p.cell_data["rank"][0]) > 0, f"rank {r} wrote no cell"
        assert len(np.unique(p.cells[0].data)) == len(p.points), f"piece {r} holds nodes its cells do not use"
        cell_ids.append(p.cell_data["global_cell_id"][0])
        nodes += len(p.points)
    assert (nodes > mesh.num_points) == (ranks > 1)
    assert np.array_equal(np.sort(np.concatenate(cell_ids)), np.arange(mesh.num_cells))


def check_merged(m, mesh):
    """A mesh read back (read_pvtu or the gathered file) equals the serial mesh and its fields."""
    point_data, cell_data = serial_fields(mesh)
    assert np.array_equal(m.points, padded(mesh.points)), "points differ from the serial hierarchy's"
    assert [b.type for b in m.cells] == [mesh.cell_type]
    cells = m.cells[0].data
    assert {tuple(c) for c in cells.tolist()} == {tuple(c) for c in mesh.cells.tolist()}
    assert np.array_equal(cells, mesh.cells)  # in global cell order, too
    assert np.array_equal(m.point_data["x"], padded(mesh.points))
    assert np.array_equal(m.point_data["gid"], point_data["gid"]) and m.point_data["gid"].dtype == np.int64
    assert np.array_equal(m.point_data["s"], point_data["s"])
    assert np.array_equal(m.cell_data["tensor"][0], cell_data["tensor"])


def check_vtk_reads(pvtu, mesh):
    """VTK's own reader (ParaView's) takes the .pvtu: where the vtk module is installed."""
    try:
        import vtk
    except ImportError:
        return False
    reader = vtk.vtkXMLPUnstructuredGridReader()
    reader.SetFileName(str(pvtu))
    reader.Update()
    out = reader.GetOutput()
    assert out.GetNumberOfCells() == mesh.num_cells
    assert out.GetPointData().GetArray("x").GetNumberOfComponents() == 3
    return True


def check_files(folder, name, ranks):
    """All checks of the files write_fields wrote for MESHES[name] on `ranks` ranks."""
    mesh = serial_mesh(name)
    pvtu = os.path.join(folder, f"{name}.pvtu")
    check_declarations(pvtu, ranks)
    check_pieces(pvtu, mesh, ranks)
    merged = read_pvtu(pvtu)
    check_merged(merged, mesh)
    assert np.array_equal(merged.point_data["global_id"], np.arange(mesh.num_points))
    assert np.array_equal(merged.cell_data["global_cell_id"][0], np.arange(mesh.num_cells))
    gathered = meshio.read(os.path.join(folder, f"{name}_gathered.vtu"))
    check_merged(gathered, mesh)
    # the same as the serial writer's file of the same fields, but for its facet block and tags
    serial_path = os.path.join(folder, f"{name}_serial.vtu")
    write_mesh(serial_path, mesh, *serial_fields(mesh))
    serial = meshio.read(serial_path)
    assert np.array_equal(gathered.points, serial.points)
    assert np.array_equal(gathered.cells[0].data, serial.cells[0].data)
    assert set(gathered.point_data) == set(serial.point_data)
    for k, v in serial.point_data.items():
        assert np.array_equal(gathered.point_data[k], v) and gathered.point_data[k].dtype == v.dtype, k
    assert np.array_equal(gathered.cell_data["tensor"][0], serial.cell_data["tensor"][0])
    check_vtk_reads(pvtu, mesh)
