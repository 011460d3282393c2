"""Scaling of the distributed solve (contactmg.distributed, Algorithm 2's monotone multigrid, the
Hertz half disk and sphere under Coulomb friction F = 0.4 by default) on MPI ranks, beside the serial
solver on threads and the machine's measured read bandwidth.

- strong: one problem on 1, 2, 4, ... ranks (up to --ranks), and the serial solver of the same
  problem on as many threads;
- weak: about the same dofs per rank (a level more per 4 ranks in 2D, per 8 in 3D);
- per row: cycles, seconds per cycle (the slowest rank's solve over the cycles), speed-up and
  efficiency against one rank, the largest rank's bytes per dof of its own nodes (matrices,
  transfers, vectors held by the cycle), "mem": the largest rank's bytes per local dof (owned and
  ghost) over the serial core's bytes per dof (the target: at most 1.15), whether the ranks were
  more than the cores (oversubscribed: timings then say nothing about scaling), whether the
  displacement equals the one-rank displacement bit for bit, the coarse levels held whole by every
  rank ("whole") and the largest rank's halo exchanges a cycle ("exch");
- --whole-below 0,2000,8192 runs the strong rows once per cap on the whole coarse levels (auto: the
  default rule), to choose it where the exchanges cost what they cost on that machine.

    python benchmarks/performance/mpi_scaling.py [--ranks 16] [--level2d 9] [--level3d 4] [--friction 0.4]
                                                 [--whole-below auto|N[,N...]] [--quick] [--json PATH]
"""
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()
sys.path.insert(0, str(HERE.parents[1]))
from _common import parser, write_result  # noqa: E402

CASES = {"hertz": ("triangle", 4), "sphere": ("tetra", 8)}  # cell, dofs growth per level


def worker(case: str, levels: int, friction: float, out: str, whole_below: str = "auto") -> None:
    """Under mpirun: solve, save the gathered displacement and the slowest rank's facts."""
    from contactmg.distributed import get_comm
    from contactmg.examples.distributed import hertz, sphere
    from contactmg.model.friction import Coulomb
    from contactmg.solve.options import SolverOptions
    comm = get_comm()
    law = Coulomb(friction) if friction > 0 else None
    problem = (hertz if case == "hertz" else sphere)(levels, CASES[case][0], law, comm)
    result = problem.solve(SolverOptions(cycle="F", tol=1e-11), whole_below=None if whole_below == "auto" else int(whole_below))
    u = result.gathered_u()
    lev = problem.hierarchy.levels[-1]
    owned = int(np.count_nonzero(lev.owner == lev.rank)) * lev.points.shape[1]
    local = len(lev.gid) * lev.points.shape[1]  # owned and ghost dofs
    facts = comm.gather((result.seconds, result.memory_bytes, owned, local, result.exchanges), root=0)
    if comm.rank == 0:
        np.save(out + ".npy", u)
        seconds = max(f[0] for f in facts)
        with open(out + ".json", "w") as fh:
            json.dump({"cycles": result.cycles, "converged": result.converged, "seconds": seconds,
                       "dofs": int(lev.num_global_nodes * lev.points.shape[1]),
                       "bytes_per_owned_dof": max(f[1] / max(f[2], 1) for f in facts),
                       "bytes_per_local_dof": max(f[1] / max(f[3], 1) for f in facts),
                       "exchanges_per_cycle": max(f[4] for f in facts) / max(result.cycles, 1),
                       "whole_levels": result.whole_levels,
                       "phase_seconds": result.phase_seconds}, fh)


def launcher() -> str:
    local = Path(sys.executable).parent / "mpiexec"
    return str(local) if local.exists() else "mpiexec"


def run_ranks(case: str, levels: int, ranks: int, friction: float, tmp: str, whole_below: str = "auto") -> dict:
    out = os.path.join(tmp, f"{case}-{levels}-{ranks}-{whole_below}")
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               PYTHONPATH=os.pathsep.join([str(HERE.parents[2] / "python"), os.environ.get("PYTHONPATH", "")]))
    cmd = [launcher(), "--oversubscribe", "-n", str(ranks), sys.executable, str(HERE), "--worker", case, str(levels), str(friction), out,
           whole_below]
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    with open(out + ".json") as fh:
        row = json.load(fh)
    row["u"] = np.load(out + ".npy")
    return row


def threads_row(case: str, levels: int, friction: float, threads: int) -> dict:
    import contactmg
    from contactmg.examples.hertz import hertz_problem
    from contactmg.examples.sphere import sphere_problem
    from contactmg.solve.options import SolverOptions
    make = hertz_problem if case == "hertz" else sphere_problem
    solver = contactmg.Solver(make(CASES[case][0], levels, friction), SolverOptions(method="nmg", tol=1e-11, threads=threads))
    r = solver.solve()
    return {"cycles": r.cycles, "seconds": r.solve_seconds, "converged": r.converged,
            "core_bytes_per_dof": solver.memory_bytes()["core"] / r.displacement.size}


def bandwidth(cores: int) -> dict:
    from contactmg import _core
    n = 4_000_000
    return {"read_gb_s_1": _core.testing.stream_read(n, 3, 1, 4), f"read_gb_s_{cores}": _core.testing.stream_read(n, 3, cores, 4)}


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5], sys.argv[6])
        return 0
    ap = parser(__doc__)
    ap.add_argument("--ranks", type=int, default=os.cpu_count())
    ap.add_argument("--level2d", type=int, default=7)
    ap.add_argument("--level3d", type=int, default=3)
    ap.add_argument("--friction", type=float, default=0.4, help="Coulomb coefficient F (0: frictionless)")
    ap.add_argument("--whole-below", default="auto",
                    help="coarse levels of at most this many nodes held whole by every rank (auto: the default rule); "
                         "a comma list runs the strong rows once per value")
    a = ap.parse_args()
    cores = os.cpu_count()
    max_ranks = 2 if a.quick else a.ranks
    levels = {"hertz": 4 if a.quick else a.level2d, "sphere": 2 if a.quick else a.level3d}
    counts = [r for r in (1, 2, 4, 8, 16, 32, 64) if r <= max_ranks]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in ("hertz",) if a.quick else ("hertz", "sphere"):
            threads = {}
            for whole in a.whole_below.split(","):
                base = None
                for r in counts:  # strong
                    row = run_ranks(case, levels[case], r, a.friction, tmp, whole)
                    base = base or row
                    t = threads[r] = threads.get(r) or threads_row(case, levels[case], a.friction, r)
                    rows.append({"kind": "strong", "case": case, "ranks": r, "levels": levels[case], "dofs": row["dofs"],
                                 "whole_below": whole, "whole_levels": row["whole_levels"],
                                 "exchanges_per_cycle": row["exchanges_per_cycle"],
                                 "cycles": row["cycles"], "seconds_per_cycle": row["seconds"] / row["cycles"],
                                 "speedup": (base["seconds"] / base["cycles"]) / (row["seconds"] / row["cycles"]),
                                 "bytes_per_owned_dof": row["bytes_per_owned_dof"], "oversubscribed": r > cores,
                                 "bytes_per_local_dof": row["bytes_per_local_dof"],
                                 "serial_bytes_per_dof": t["core_bytes_per_dof"],
                                 "memory_ratio": row["bytes_per_local_dof"] / t["core_bytes_per_dof"],
                                 "bitwise_as_one_rank": bool(np.array_equal(row["u"], base["u"])),
                                 "threads_cycles": t["cycles"], "threads_seconds_per_cycle": t["seconds"] / t["cycles"],
                                 "phase_seconds": row["phase_seconds"]})
                    rows[-1]["efficiency"] = rows[-1]["speedup"] / r
            growth, level, r, base = CASES[case][1], levels[case], 1, None
            while r <= max_ranks:  # weak: a level more per `growth` ranks
                row = run_ranks(case, level, r, a.friction, tmp)
                base = base or row
                rows.append({"kind": "weak", "case": case, "ranks": r, "levels": level, "dofs": row["dofs"],
                             "dofs_per_rank": row["dofs"] / r, "cycles": row["cycles"],
                             "seconds_per_cycle": row["seconds"] / row["cycles"],
                             "time_ratio": (row["seconds"] / row["cycles"]) / (base["seconds"] / base["cycles"]),
                             "whole_levels": row["whole_levels"], "exchanges_per_cycle": row["exchanges_per_cycle"],
                             "bytes_per_owned_dof": row["bytes_per_owned_dof"], "oversubscribed": r > cores})
                r, level = r * growth, level + 1
    bw = bandwidth(min(cores, max_ranks))
    print(f"cores {cores}; read bandwidth {bw}")
    print(f"{'kind':>6} {'case':>6} {'ranks':>5} {'whole':>5} {'exch':>5} {'dofs':>9} {'cycles':>6} {'s/cycle':>8} "
          f"{'speedup':>7} {'eff':>5} {'B/dof':>6} {'mem':>5} {'thr cyc':>7} {'thr s/cyc':>9} {'bitwise':>7} {'over':>5}")
    for r in rows:
        print(f"{r['kind']:>6} {r['case']:>6} {r['ranks']:>5} {r['whole_levels']:>5} {r['exchanges_per_cycle']:>5.0f} "
              f"{r['dofs']:>9} {r['cycles']:>6} {r['seconds_per_cycle']:>8.3f} "
              f"{r.get('speedup', r.get('time_ratio', 0)):>7.2f} {r.get('efficiency', float('nan')):>5.2f} "
              f"{r['bytes_per_owned_dof']:>6.0f} {r.get('memory_ratio', float('nan')):>5.2f} {r.get('threads_cycles', ''):>7} "
              f"{r.get('threads_seconds_per_cycle', float('nan')):>9.3f} {str(r.get('bitwise_as_one_rank', '')):>7} "
              f"{str(r['oversubscribed']):>5}")
    write_result(__file__, a, {"cores": cores, "friction": a.friction, "bandwidth": bw, "rows": rows})
    ok = all(r.get("bitwise_as_one_rank", True) for r in rows)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
