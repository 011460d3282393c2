"""Peak memory of a solve and who holds it: for each case (the Hertz half disk in 2D, the sphere in
3D), the peak resident memory of the command line's solve in a fresh process, and a worker on the
command line's path (the problem releases its Python hierarchy once the core solver is built, as
the single solves of the command line do) that reports the resident and peak memory after each
stage (imports, problem, core solver, solve) and what each owner holds after the solve (fine and
coarse matrices in the core, the core's other arrays, the Python copies, the result), in MiB and
bytes per dof.

    python benchmarks/performance/memory.py [--cases 2:triangle:9 3:hexahedron:4 3:tetra:3]
        [--quick] [--json PATH]
"""
import json
import os
import resource
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

WORKER = r'''
import json, resource, sys
import numpy as np
from contactmg import _core
from contactmg.solve.options import options_from
def status(key):  # VmRSS (now) or VmHWM (peak so far) in bytes
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
stages = {}
def stage(name):
    stages[name] = {"rss": status("VmRSS"), "peak": status("VmHWM")}
dim, cell, level = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
stage("imports")
if dim == 2:
    from contactmg.examples.hertz import hertz_problem
    p = hertz_problem(cell, level, 0.4)
else:
    from contactmg.examples.sphere import sphere_problem
    p = sphere_problem(cell, levels=level, friction=0.4)
p.default_options = options_from(p.default_options).replace(release_hierarchy=True)
stage("problem")
p.solver.core
stage("core solver")
r = p.solve("nmg")
stage("solve")
d, n = p.mesh.dim, p.mesh.num_points
S = p.solver.core
own = p.solver.memory_bytes()
fine = _core.testing.fine_matrix(S).memory_bytes()
coarse = sum(_core.testing.coarse_matrix(S, l).memory_bytes() for l in range(S.num_levels - 1))
core = S.memory_bytes()
nb = lambda *arrs: int(sum(a.nbytes for a in arrs if isinstance(a, np.ndarray)))
results = nb(r.displacement, r.contact_force, r.friction_bound, r.node_state) + sum(v.nbytes for v in r.history.values())
print(json.dumps(dict(dofs=d * n, cycles=r.cycles, converged=r.converged,
                      peak_rss_bytes=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
                      owners=dict(fine_matrix=fine, coarse_matrices=coarse, core_other=core - fine - coarse,
                                  python_matrix_copy=own["python_matrix"], mesh_hierarchy_python=own["mesh_hierarchy"],
                                  transfers_python=own["transfers"], problem_vectors_python=own["problem_vectors"],
                                  results=results),
                      stages=stages)))
'''


def cli_peak_rss(dim, cell, level):
    """Peak resident bytes of `contactmg hertz` / `contactmg sphere` in a fresh process (from
    wait4's resource usage of that child alone)."""
    cmd = [sys.executable, "-m", "contactmg"] + (
        ["hertz", "--cell", cell, "--levels", str(level), "--friction", "0.4"] if dim == 2 else
        ["sphere", "--cell", cell, "--levels", str(level)]) + ["--json", "-", "-q"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    if status != 0 and status >> 8 != 3:
        raise SystemExit(proc.stderr.read().decode())
    return usage.ru_maxrss * 1024


def measure(dim, cell, level):
    """The CLI's peak and the worker's stages and owners of one case."""
    cli = cli_peak_rss(dim, cell, level)
    out = subprocess.run([sys.executable, "-c", WORKER, str(dim), cell, str(level)], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res.update(dim=dim, cell=cell, level=level, cli_peak_rss_bytes=cli, cli_peak_bytes_per_dof=cli / res["dofs"],
               peak_bytes_per_dof=res["peak_rss_bytes"] / res["dofs"])
    dofs = res["dofs"]
    print(f"== {dim}D {cell} level {level}: {dofs:,} dofs, {res['cycles']} cycles; command line peak "
          f"{cli / 2**20:.1f} MiB ({cli / dofs:.0f} B/dof), worker peak {res['peak_rss_bytes'] / 2**20:.1f} MiB")
    for k, v in res["owners"].items():
        print(f"   {k:28s} {v / 2**20:9.1f} MiB {v / dofs:7.1f} B/dof")
    for name, st in res["stages"].items():
        print(f"   after {name:14s} rss {st['rss'] / 2**20:9.1f} MiB  peak so far {st['peak'] / 2**20:9.1f} MiB")
    return res


def main():
    ap = parser(__doc__)
    ap.add_argument("--cases", nargs="+", default=["2:triangle:9", "3:hexahedron:4", "3:tetra:3"],
                    help="dim:cell:level")
    a = ap.parse_args()
    if a.quick:
        a.cases = ["2:triangle:4", "3:hexahedron:2"]
    rows = []
    for case in a.cases:
        dim, cell, level = case.split(":")
        rows.append(measure(int(dim), cell, int(level)))
    write_result(__file__, a, {"own_peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "rows": rows})


if __name__ == "__main__":
    main()
