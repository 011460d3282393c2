"""The distributed pieces on one process, without mpirun: the serial stand-in communicator, errors
raised together, exact sums, the partitioners, the hierarchy and the colouring on one rank, and
the package without mpi4py and pymetis."""
import math
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import contactmg
from contactmg.distributed import (DistributedError, DistributedHierarchy, SerialComm, collective, colour_level,
                                   coordinate_bisection, exact_dot, exact_norm, exact_sum, get_comm, partition_cells,
                                   raise_together)
from contactmg.distributed.partition import dual_graph
from contactmg.mesh.generators import hertz_half_disk, rectangle
from contactmg.mesh.generators_3d import box
from contactmg.mesh.hierarchy import MeshHierarchy

MESHES = [rectangle(3, 2, cell="triangle"), hertz_half_disk("quad"), box(2, 2, 1, cell="tetra"),
          box(2, 1, 2, cell="hexahedron")]


def test_one_process_gets_the_serial_stand_in():
    comm = get_comm()
    assert isinstance(comm, SerialComm) and comm.rank == 0 and comm.size == 1
    assert comm.allgather(5) == [5] and comm.alltoall(["x"]) == ["x"]
    # no launcher started this process: MPI is not initialized for it
    assert "mpi4py.MPI" not in sys.modules
    with pytest.raises(TypeError, match="communicator"):
        get_comm(object())


def test_an_error_in_a_guarded_block_is_raised_with_its_rank():
    with pytest.raises(DistributedError, match="rank 0: KeyError: 'levels'") as info:
        with raise_together(SerialComm()):
            raise KeyError("levels")
    assert isinstance(info.value.__cause__, KeyError)

    with pytest.raises(SystemExit):  # an exit stays an exit on the rank that asked for it
        with raise_together(SerialComm()):
            raise SystemExit(2)

    @collective
    def check(x, comm=None):
        if x < 0:
            raise ValueError(f"x must be non-negative, got {x}")
        return 2 * x

    assert check(3) == 6
    with pytest.raises(DistributedError, match="x must be non-negative, got -1"):
        check(-1)


def test_exact_sum_is_the_correctly_rounded_sum():
    rng = np.random.default_rng(3)
    for scale in (1, 40, 600):
        x = rng.standard_normal(3001) * np.exp2(rng.integers(-scale, scale, 3001).astype(float))
        x[1::2] = -x[0:-1:2] * (1 + 2.0 ** -45)
        assert exact_sum(x) == math.fsum(x)
        # a plain sum of the same terms is off: the check could fail
        if scale == 40:
            assert float(np.sum(x)) != math.fsum(x)
    assert exact_sum(np.array([1e308, 1e308, -1e308])) == 1e308  # no intermediate overflow
    assert exact_sum(np.array([5e-324, 5e-324])) == 1e-323
    assert exact_sum(np.zeros(0)) == 0.0


def test_exact_dot_is_the_correctly_rounded_dot_product():
    rng = np.random.default_rng(4)
    x = rng.standard_normal(400) * np.exp2(rng.integers(-200, 200, 400).astype(float))
    y = rng.standard_normal(400)
    want = float(sum(Fraction(a) * Fraction(b) for a, b in zip(x.tolist(), y.tolist())))
    assert exact_dot(x, y) == want
    assert exact_norm(np.array([3.0, 4.0])) == 5.0
    with pytest.raises(ValueError, match="non-finite"):
        exact_sum(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="one length"):
        exact_dot(np.ones(2), np.ones(3))


def test_partition_refuses_fewer_cells_than_ranks_and_covers_every_rank():
    mesh = rectangle(2, 1, cell="quad")
    with pytest.raises(ValueError, match="2 cells, fewer than the 3 ranks"):
        partition_cells(mesh, 3)
    with pytest.raises(ValueError, match="method"):
        partition_cells(mesh, 2, "scotch")
    for m in MESHES:
        for method in ("bisection", None):
            part = partition_cells(m, 3, method)
            assert sorted(np.unique(part)) == [0, 1, 2]
            assert np.array_equal(part, partition_cells(m, 3, method))  # deterministic
        counts = np.bincount(partition_cells(m, 3, "bisection"))
        assert counts.max() - counts.min() <= 1


def test_dual_graph_joins_cells_sharing_a_facet():
    xadj, adjncy = dual_graph(rectangle(2, 1, cell="quad"))
    assert xadj.tolist() == [0, 1, 2] and adjncy.tolist() == [1, 0]


def test_coordinate_bisection_splits_across_the_widest_extent():
    x = np.c_[np.arange(8.0), np.zeros(8)]
    assert coordinate_bisection(x, 2).tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
    assert coordinate_bisection(x, 3).tolist() == [0, 0, 1, 1, 1, 2, 2, 2]


@pytest.mark.parametrize("mesh", MESHES, ids=lambda m: m.cell_type)
def test_one_rank_hierarchy_is_the_serial_one(mesh):
    h = MeshHierarchy.build(mesh, 3)
    d = DistributedHierarchy.build(mesh, 3)
    for level, m in enumerate(h.meshes):
        points, cells = d.gathered(level)
        assert np.array_equal(points, m.points) and np.array_equal(cells, m.cells)
        assert len(d.levels[level].ghosts) == 0
    # the transfer's rows by global id (the local nodes are in (colour, global id) order)
    lev, t, P = d.levels[-1], d.levels[-1].transfer, h.transfers[-1]
    order = np.argsort(lev.gid[t.rows])
    assert np.array_equal(lev.gid[t.rows][order], np.arange(len(order)))
    ptr = np.r_[0, np.cumsum(np.diff(t.ptr)[order])]
    entries = np.concatenate([np.arange(t.ptr[i], t.ptr[i + 1]) for i in order])
    assert np.array_equal(ptr, P.ptr) and np.array_equal(t.parent_gid[entries], P.parent)
    assert np.array_equal(t.weight[entries], P.weight)
    assert np.array_equal(d.levels[-2].gid[t.parent[entries]], P.parent)  # the local parents are those nodes


def test_hierarchy_refuses_bad_input():
    mesh = rectangle(2, 2, cell="triangle")
    with pytest.raises(DistributedError, match="levels must be an integer >= 1"):
        DistributedHierarchy.build(mesh, 0)
    with pytest.raises(DistributedError, match="one rank per coarse cell"):
        DistributedHierarchy.build(mesh, 2, part=np.zeros(3, int))
    with pytest.raises(DistributedError, match="outside 0..0"):
        DistributedHierarchy.build(mesh, 2, part=np.ones(mesh.num_cells, int))


def test_colouring_is_valid_and_uses_few_colours():
    d = DistributedHierarchy.build(box(2, 2, 2, cell="hexahedron"), 2)
    lev = d.levels[-1]
    colour = colour_level(lev)
    assert colour.min() == 0
    for a in range(8):
        for b in range(a):
            assert np.all(colour[lev.cells[:, a]] != colour[lev.cells[:, b]])
    # a structured hexahedral mesh needs 8 colours; greedy in a hashed order takes somewhat more
    assert colour.max() + 1 <= 27


def test_serial_package_works_without_mpi4py_and_pymetis():
    # a finder that makes both imports fail, as on a machine where mpi4py and pymetis are missing
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('mpi4py', 'pymetis'):\n"
        "            raise ImportError('blocked: ' + name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "import contactmg, contactmg.distributed as dist\n"
        "from contactmg.mesh.generators import rectangle\n"
        "d = dist.DistributedHierarchy.build(rectangle(2, 2), 2)\n"
        "print(type(d.comm).__name__, d.levels[-1].num_global_nodes)\n"
        "m = rectangle(4, 4)\n"
        "print(dist.partition_cells(m, 3).tolist() == dist.partition_cells(m, 3, 'bisection').tolist())\n"
    )
    root = str(Path(contactmg.__file__).resolve().parent.parent)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                       env={"PYTHONPATH": root, "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["SerialComm", "25", "True"]


def test_projected_one_rank_hierarchy_is_the_serial_one_and_cad_projectors_are_refused():
    from contactmg.mesh.generators import hertz_projector

    mesh = hertz_half_disk("triangle")
    h = MeshHierarchy.build(mesh, 3, projector=hertz_projector())
    d = DistributedHierarchy.build(mesh, 3, projector=hertz_projector())
    assert np.array_equal(d.gathered(2)[0], h.meshes[2].points)
    assert not np.array_equal(h.meshes[2].points, MeshHierarchy.build(mesh, 3).meshes[2].points)

    class FollowsFacets:
        def __call__(self, points, tags):
            return points

        def project_refinement(self, coarse, r):
            return r["points"][r["boundary_nodes"]]

    with pytest.raises(DistributedError, match="not distributed yet"):
        DistributedHierarchy.build(mesh, 2, projector=FollowsFacets())
    with pytest.raises(DistributedError, match="returned shape"):
        DistributedHierarchy.build(mesh, 2, projector=lambda p, t: p[:1])
