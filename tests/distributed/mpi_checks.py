"""Checks run under mpirun by the distributed tests: `mpirun -n N python mpi_checks.py MODE [FOLDER] N`,
MODE one part or several joined by commas (run in one launch, in that order).

Part "all": the distributed hierarchy gathered equals the serial one (points bitwise, with new
boundary nodes projected onto curved boundaries; cells, facets, prolongation rows, owners), the halo
exchange gives every ghost its owner's value, exact sums equal math.fsum of the whole, and the node
colouring equals the serial greedy rule and is valid, for triangles, quadrilaterals, tetrahedra and
hexahedra. Rank 0 prints "OK <check>" per check and "ALL OK" at the end; a failed check raises,
which ends every rank (get_comm sets abort_on_uncaught on several ranks).
Part "solve": the distributed solves of solve_checks.CASES, rank 0 saving each (displacement,
cycles, norms, energies) as FOLDER/<case>.npz; the test compares them.
Part "cli": `contactmg hertz` (Coulomb) and `contactmg sphere` on the ranks (JSON and VTU into
FOLDER) and a run with an option not distributed yet; rank 0 prints each exit status.
Part "output": the finest level of a triangle and a tetrahedron hierarchy written as .pvtu and
gathered .vtu into FOLDER (output_checks.write_fields); the test process checks the files.
MODE "error": rank 1 fails a guarded input check; every rank prints the error it gets.
MODE "uncaught": rank 1 raises outside any guard while the others wait in a barrier: the hook that
get_comm sets must end them."""
import math
import sys
from fractions import Fraction

import numpy as np

from contactmg.distributed import (DistributedError, DistributedHierarchy, colour_level, exact_dot, exact_sum,
                                   get_comm, raise_together, rank0_print)
from contactmg.distributed.colouring import priority
from contactmg.distributed.transfer import prolong
from contactmg.mesh.generators import hertz_half_disk, hertz_projector
from contactmg.mesh.generators_3d import ball_projector, box, half_ball
from contactmg.mesh.hierarchy import MeshHierarchy
from output_checks import MESHES as OUTPUT_MESHES, write_fields
from solve_checks import CASES as SOLVE_CASES, RANKS_ONLY, solve_case

LEVELS = 3
# (coarse mesh, boundary projector): the half disks' new nodes on the arc are projected onto it
MESHES = {
    "triangle": (lambda: hertz_half_disk("triangle"), hertz_projector()),
    "quad": (lambda: hertz_half_disk("quad"), hertz_projector()),
    "tetra": (lambda: box(3, 2, 2, cell="tetra"), None),
    "hexahedron": (lambda: box(3, 2, 2, cell="hexahedron"), None),
}


def serial_colours(cells: np.ndarray, n: int) -> np.ndarray:
    """The greedy rule one node at a time, highest priority first (the reference)."""
    gid = np.arange(n)
    p = priority(gid)
    order = sorted(range(n), key=lambda i: (int(p[i]), i), reverse=True)
    nbrs = [set() for _ in range(n)]
    for c in cells.tolist():
        for a in c:
            nbrs[a].update(c)
    colour = np.full(n, -1, np.int64)
    for i in order:
        used = {int(colour[j]) for j in nbrs[i] if j != i}
        colour[i] = next(c for c in range(len(used) + 1) if c not in used)
    return colour


def check_hierarchy(comm, name, mesh, d, h):
    children = {"triangle": 4, "quad": 4, "tetra": 8, "hexahedron": 8}[mesh.cell_type]
    for L, lev in enumerate(d.levels):
        got = d.gathered(L)
        own = lev.owned
        # boundary facets as global node sets with their tags, and prolongation rows of owned nodes
        facets = comm.gather((np.sort(lev.gid[lev.facets], axis=1), lev.facet_tags), root=0)
        rows = None
        if lev.transfer is not None:
            t = lev.transfer
            rows = comm.gather((lev.gid[t.rows], t.ptr, t.parent_gid, t.weight), root=0)
        owners = comm.gather((lev.gid[own], np.full(len(own), comm.rank)), root=0)
        if comm.rank:
            continue
        m = h.meshes[L]
        points, cells = got
        assert np.array_equal(points, m.points), f"{name} level {L}: points differ from the serial hierarchy"
        assert np.array_equal(cells, m.cells), f"{name} level {L}: cells differ from the serial hierarchy"
        want = {(tuple(f), int(t)) for f, t in zip(np.sort(m.facets, axis=1).tolist(), m.facet_tags.tolist())}
        have = {(tuple(f), int(t)) for fs, ts in facets for f, t in zip(fs.tolist(), ts.tolist())}
        assert have == want, f"{name} level {L}: boundary facets differ"
        # owner: the lowest rank among the cells that hold the node
        cell_part = d.part[np.arange(m.num_cells) // children ** L]
        expect = np.full(m.num_points, comm.size)
        np.minimum.at(expect, m.cells.ravel(), np.repeat(cell_part, m.cells.shape[1]))
        owner = np.full(m.num_points, -1)
        for g, r in owners:
            owner[g] = r
        assert np.array_equal(owner, expect), f"{name} level {L}: owners are not the lowest rank of their cells"
        if rows is not None:
            P = h.transfers[L - 1].matrix().tocsr()
            for g, ptr, parent, weight in rows:
                for i, gi in enumerate(g.tolist()):
                    sl = slice(ptr[i], ptr[i + 1])
                    row = P.getrow(gi)
                    assert sorted(zip(parent[sl].tolist(), weight[sl].tolist())) == \
                        sorted(zip(row.indices.tolist(), row.data.tolist())), f"{name} level {L}: row {gi} differs"
    rank0_print(f"OK hierarchy {name}", comm=comm)


def check_halo(comm, name, d):
    ghosts = 0
    for L, lev in enumerate(d.levels):
        v = np.full((len(lev.gid), 2), np.nan)
        v[lev.owned, 0] = np.sin(lev.gid[lev.owned])
        v[lev.owned, 1] = lev.gid[lev.owned] + 0.5
        lev.halo.update(v)
        assert np.array_equal(v[:, 0], np.sin(lev.gid)) and np.array_equal(v[:, 1], lev.gid + 0.5), \
            f"{name} level {L} rank {comm.rank}: a ghost did not get its owner's value"
        ghosts += len(lev.ghosts)
        # a sum over the owned nodes (each node once) is the sum over the whole level
        total = exact_sum(np.sin(lev.gid[lev.owned]), comm=comm)
        assert total == math.fsum(np.sin(np.arange(lev.num_global_nodes))), f"{name} level {L}: sum differs"
    total = comm.allreduce(ghosts)
    assert (total > 0) == (comm.size > 1), f"{name}: {total} ghosts on {comm.size} ranks"
    rank0_print(f"OK halo {name}", comm=comm)


def check_sums(comm):
    rng = np.random.default_rng(5)
    n = 20011
    x = rng.standard_normal(n) * np.exp2(rng.integers(-60, 60, n).astype(float))
    x[::7] = -x[1::7][: len(x[::7])] if len(x[1::7]) >= len(x[::7]) else x[::7]
    x[:3] = [1e300, -1e300, 5e-324]
    y = rng.standard_normal(n)
    # an uneven and interleaved share of the terms on every rank
    mine = (np.arange(n) * 2654435761 % 1000) * comm.size // 1000 == comm.rank
    s = exact_sum(x[mine], comm=comm)
    assert s == math.fsum(x), f"rank {comm.rank}: exact_sum {s!r} != fsum {math.fsum(x)!r}"
    dot = exact_dot(x[mine][:50], y[mine][:50], comm=comm)
    parts = comm.allgather((x[mine][:50], y[mine][:50]))
    want = float(sum(Fraction(a) * Fraction(b) for px, py in parts for a, b in zip(px.tolist(), py.tolist())))
    assert dot == want, f"rank {comm.rank}: exact_dot {dot!r} != exact {want!r}"
    rank0_print("OK sums", comm=comm)


def check_prolongation(comm, name, d, h):
    for L in range(1, len(d.levels)):
        below, lev = d.levels[L - 1], d.levels[L]
        x = np.full((len(below.gid), 2), np.nan)  # ghosts unknown: prolong must fetch them
        x[below.owned] = np.c_[np.cos(below.gid[below.owned]), below.gid[below.owned] % 7 - 3.0]
        y = prolong(d, L, x)
        assert not np.isnan(y).any(), f"{name} level {L} rank {comm.rank}: a fine value is missing"
        got = comm.gather((lev.gid[lev.owned], y[lev.owned]), root=0)
        if comm.rank == 0:
            n = h.meshes[L - 1].num_points
            g = np.arange(n)
            want = h.transfers[L - 1].matrix() @ np.c_[np.cos(g), g % 7 - 3.0]
            full = np.full_like(want, np.nan)
            for gi, yi in got:
                full[gi] = yi
            assert np.array_equal(full, want), f"{name} level {L}: prolongation differs from the serial one"
    rank0_print(f"OK prolongation {name}", comm=comm)


def check_colouring(comm, name, d, h):
    lev = d.levels[-1]
    colour = colour_level(lev, comm=comm)
    # ghosts carry their owners' colours; owned ones gathered and compared with the serial rule
    got = comm.gather((lev.gid[lev.owned], colour[lev.owned]), root=0)
    if comm.rank == 0:
        m = h.meshes[-1]
        full = np.full(m.num_points, -1)
        for g, c in got:
            full[g] = c
        want = serial_colours(m.cells, m.num_points)
        assert np.array_equal(full, want), f"{name}: colours differ from the serial greedy rule"
        for a in range(m.cells.shape[1]):
            for b in range(a):
                assert np.all(full[m.cells[:, a]] != full[m.cells[:, b]]), f"{name}: two nodes of a cell share a colour"
    rank0_print(f"OK colouring {name}", comm=comm)


def stop_on_distributed_error(comm, run) -> None:
    """run(); where it raises the error that reaches every rank, each rank prints it and exits 3."""
    try:
        run()
    except DistributedError as e:
        print(f"rank {comm.rank} stops: {e}", flush=True)
        sys.exit(3)


def check_pieces(comm) -> None:
    """Part "all": hierarchy, halo, prolongation and colouring of every cell type; exact sums."""
    for name, (make, projector) in MESHES.items():
        mesh = make()
        h = MeshHierarchy.build(mesh, LEVELS, projector=projector) if comm.rank == 0 else None
        # METIS's partition; for two cell types also one scattered cell by cell (parts not connected:
        # many more ghosts and entities numbered by another rank), and recursive bisection for one
        variants = [("", {})]
        if name in ("triangle", "tetra"):
            variants.append((" scattered", {"part": np.arange(mesh.num_cells) % comm.size}))
        if name == "quad":
            variants.append((" bisection", {"method": "bisection"}))
        for suffix, kw in variants:
            d = DistributedHierarchy.build(mesh, LEVELS, comm=comm, projector=projector, **kw)
            check_hierarchy(comm, name + suffix, mesh, d, h)
            check_halo(comm, name + suffix, d)
            check_prolongation(comm, name + suffix, d, h)
            check_colouring(comm, name + suffix, d, h)
            d.free()
    # hexahedra of a half ball, new surface nodes projected onto the sphere (rims between the sphere
    # and the flat face: a ghost may not see both facets, its owner does)
    mesh = half_ball("hexahedron")
    h = MeshHierarchy.build(mesh, 2, projector=ball_projector()) if comm.rank == 0 else None
    d = DistributedHierarchy.build(mesh, 2, comm=comm, projector=ball_projector())
    check_hierarchy(comm, "ball", mesh, d, h)
    check_halo(comm, "ball", d)
    check_sums(comm)
    rank0_print("ALL OK", comm=comm)




def solve_cases(comm, folder: str) -> None:
    """Part "solve": each case of solve_checks.CASES, saved by rank 0 as FOLDER/<case>.npz."""
    for name in [*SOLVE_CASES, *RANKS_ONLY]:
        got = solve_case(name, comm)
        if comm.rank == 0:
            np.savez(f"{folder}/{name}.npz", **got)
        rank0_print(f"OK solve {name}", comm=comm)


def run_commands(comm, folder: str) -> None:
    """Part "cli": the commands on the ranks (JSON and VTU into FOLDER), rank 0 printing each exit
    status: Coulomb hertz, frictionless sphere, an option and a command not distributed yet."""
    from contactmg.cli.main import main as cli_main
    runs = {"hertz": ["hertz", "--levels", "4", "--friction", "0.4", "--json", f"{folder}/hertz.json",
                      "--vtu", f"{folder}/hertz.vtu", "-q"],
            "sphere": ["sphere", "--levels", "2", "--cell", "tetra", "--friction", "0", "--json",
                       f"{folder}/sphere.json", "-q"],
            "adaptive": ["hertz", "--levels", "3", "--hierarchy", "adaptive", "-q"],
            "cork": ["cork", "--levels", "1", "-q"]}
    for name, argv in runs.items():
        status = cli_main(argv)
        rank0_print(f"EXIT {name} {status}", comm=comm)


def write_outputs(comm, folder: str) -> None:
    """Part "output": .pvtu and gathered .vtu of output_checks.MESHES into FOLDER."""
    for name in OUTPUT_MESHES:
        write_fields(folder, name, comm)
        rank0_print(f"OK output {name}", comm=comm)


PARTS = {"all": lambda comm, folder: check_pieces(comm), "solve": solve_cases, "cli": run_commands,
         "output": write_outputs}


def main(mode, ranks, *args):
    comm = get_comm()
    if comm.size != ranks:
        # a launcher of another MPI than mpi4py's starts separate one-rank programs
        print(f"started as {ranks} ranks, this rank sees {comm.size}: the launcher does not belong to mpi4py's MPI",
              flush=True)
        sys.exit(4)
    if mode == "error":
        def bad_input_on_one_rank():
            with raise_together(comm):
                if comm.rank == min(1, comm.size - 1):
                    raise ValueError("bad input on this rank: levels must be positive, got -1")
        stop_on_distributed_error(comm, bad_input_on_one_rank)
        return
    if mode == "uncaught":
        if comm.rank == min(1, comm.size - 1):
            raise RuntimeError("an unguarded failure on one rank")
        comm.barrier()
        return
    # parts joined by commas run in one launch (an mpirun start costs seconds on a small machine)
    for part in mode.split(","):
        PARTS[part](comm, args[0] if args else "")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[-1]), *sys.argv[2:-1])
