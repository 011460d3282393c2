"""Distributed output on one process (the serial stand-in communicator): the .pvtu and its piece, the
gathered .vtu, read back and compared with the serial hierarchy; the errors of the writers and of
read_pvtu. The same checks on 2 and 3 ranks are in test_mpi_ranks.py."""
import os

import meshio
import numpy as np
import pytest

from contactmg.distributed import (DistributedError, DistributedHierarchy, SerialComm, read_pvtu, write_gathered_vtu,
                                   write_pvtu)
from contactmg.mesh.generators import rectangle

from output_checks import MESHES, check_files, check_vtk_reads, serial_mesh, write_fields


@pytest.mark.parametrize("name", sorted(MESHES))
def test_pvtu_and_gathered_vtu_equal_the_serial_mesh(tmp_path, name):
    write_fields(str(tmp_path), name, SerialComm())
    check_files(str(tmp_path), name, 1)


def test_vtk_reads_the_pvtu(tmp_path):
    pytest.importorskip("vtk")
    write_fields(str(tmp_path), "triangle", SerialComm())
    assert check_vtk_reads(tmp_path / "triangle.pvtu", serial_mesh("triangle"))


def test_meshio_does_not_read_pvtu_so_read_pvtu_does(tmp_path):
    # if a meshio release learns to read .pvtu files, test it here against read_pvtu
    write_fields(str(tmp_path), "triangle", SerialComm())
    with pytest.raises(Exception):
        meshio.read(tmp_path / "triangle.pvtu")


def level():
    return DistributedHierarchy.build(rectangle(2, 2, cell="triangle"), 2, comm=SerialComm()).levels[-1]


def test_writers_refuse_bad_fields_on_every_rank(tmp_path):
    lev = level()
    with pytest.raises(DistributedError, match="one row per local node"):
        write_pvtu(tmp_path / "a.pvtu", lev, {"u": np.zeros(3)})
    with pytest.raises(DistributedError, match="one row per local cell"):
        write_gathered_vtu(tmp_path / "a.vtu", lev, {}, {"c": np.zeros(len(lev.cells) + 1)})
    with pytest.raises(DistributedError, match="written by the distributed writer itself"):
        write_pvtu(tmp_path / "a.pvtu", lev, {"global_id": lev.gid})
    with pytest.raises(DistributedError, match="dtype complex128"):
        write_pvtu(tmp_path / "a.pvtu", lev, {"z": np.zeros(len(lev.gid), complex)})
    with pytest.raises(DistributedError, match="does not end in .pvtu"):
        write_pvtu(tmp_path / "a.vtu", lev, {})
    with pytest.raises(DistributedError, match="does not exist"):
        write_gathered_vtu(tmp_path / "missing" / "a.vtu", lev, {})
    assert not os.listdir(tmp_path)


def test_boolean_fields_are_written_as_bytes(tmp_path):
    lev = level()
    write_pvtu(tmp_path / "b.pvtu", lev, {"flag": lev.gid % 2 == 0})
    m = read_pvtu(tmp_path / "b.pvtu")
    assert m.point_data["flag"].dtype == np.uint8
    assert np.array_equal(m.point_data["flag"], np.arange(len(m.points)) % 2 == 0)


def test_read_pvtu_refuses_pieces_that_disagree_on_a_shared_node(tmp_path):
    lev = level()
    write_pvtu(tmp_path / "r.pvtu", lev, {"u": np.ones(len(lev.gid))})
    # a second piece holding the same nodes, one node with another value
    piece = meshio.read(tmp_path / "r" / "r_0.vtu")
    piece.point_data["u"] = piece.point_data["u"] + (piece.point_data["global_id"] == 3)
    meshio.write(tmp_path / "r" / "r_1.vtu", piece)
    text = (tmp_path / "r.pvtu").read_text().replace('<Piece Source="r/r_0.vtu"/>',
                                                       '<Piece Source="r/r_0.vtu"/>\n    <Piece Source="r/r_1.vtu"/>')
    (tmp_path / "r.pvtu").write_text(text)
    with pytest.raises(ValueError, match="'u' of node 3 differs between the pieces"):
        read_pvtu(tmp_path / "r.pvtu")
    with pytest.raises(ValueError, match="not a parallel unstructured grid"):
        read_pvtu(tmp_path / "r" / "r_0.vtu")
