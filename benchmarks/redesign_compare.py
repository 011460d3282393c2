"""Old core against new core in one run (issue 9): Hertz cycle counts for every paper coefficient
(triangles levels 3-8, quads 3-7), the difference of the solutions in the relative energy norm,
and the time per cycle at levels 8 and 9, the old and new builds timed interleaved (the machine is
shared and noisy: medians of alternating solves in two long-lived worker processes).

    python benchmarks/redesign_compare.py --old /path/to/old/pkg [--json out.json] [--quick]

--old is a directory holding an importable `contactmg` package of the old build (its python/contactmg
with the compiled _core next to it); the new build is the one this interpreter imports.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

WORKER = r'''
import sys, json, time
old = sys.argv[1]
if old != "-":
    # leave an editable install of the new build out of the way of the old package
    sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__.lower()
                     and "skbc" not in type(f).__module__.lower()]
    sys.path.insert(0, old)
import numpy as np
import contactmg
from contactmg.checks import contact_conditions
from contactmg.friction import Coulomb
from contactmg.generators import HERTZ_ARC, HERTZ_TOP, hertz_half_disk, hertz_projector
from contactmg.hertz import CENTER, E, NU, RADIUS, TOP_DISPLACEMENT
from contactmg.hierarchy import MeshHierarchy
from contactmg.material import Material
from contactmg.obstacle import PlaneObstacle
from contactmg.problem import ContactProblem, Dirichlet
hier = {}
def problem(cell, L, F):
    if (cell, L) not in hier:
        hier.clear()
        hier[(cell, L)] = MeshHierarchy.build(hertz_half_disk(cell), L, projector=hertz_projector(CENTER, RADIUS))
    return ContactProblem(hier[(cell, L)], Material(E, NU), [Dirichlet([HERTZ_TOP], (0.0, TOP_DISPLACEMENT))],
                          contact_tags=[HERTZ_ARC], obstacle=PlaneObstacle((0.0, 0.0), (0.0, -1.0)),
                          friction=Coulomb(F), cycle="F", nu1=3, nu2=3)
print(json.dumps({"ready": contactmg.__file__}), flush=True)
keep = {}
for line in sys.stdin:
    cmd = json.loads(line)
    if cmd["op"] == "solve":
        p = problem(cmd["cell"], cmd["level"], cmd["F"])
        r = p.solve()
        out = {"cycles": int(r.cycles), "converged": bool(r.converged), "seconds": float(r.solve_seconds),
               "violation": float(contact_conditions(p, r)["max"]) if cmd.get("check", True) else None}
        if cmd.get("save"):
            np.save(cmd["save"], r.displacement)
        print(json.dumps(out), flush=True)
    elif cmd["op"] == "prepare":
        keep.clear()
        keep["p"] = problem(cmd["cell"], cmd["level"], cmd["F"])
        keep["p"].solver
        print(json.dumps({"nodes": int(keep["p"].mesh.num_points)}), flush=True)
    elif cmd["op"] == "time":
        c0 = time.thread_time()
        r = keep["p"].solve()
        cpu = time.thread_time() - c0
        print(json.dumps({"cycles": int(r.cycles), "seconds": float(r.solve_seconds), "cpu": cpu}), flush=True)
'''

FRICTIONS = (0.08, 0.4, 0.7, 0.9, 1.0, 1.1, 2.0, 5.0, 8.0, 40.0)


class Worker:
    def __init__(self, old_path):
        self.p = subprocess.Popen([sys.executable, "-c", WORKER, old_path], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  text=True)
        self.where = json.loads(self.p.stdout.readline())["ready"]

    def ask(self, **cmd):
        self.p.stdin.write(json.dumps(cmd) + "\n")
        self.p.stdin.flush()
        line = self.p.stdout.readline()
        if not line:
            raise RuntimeError("worker died")
        return json.loads(line)

    def close(self):
        self.p.stdin.close()
        self.p.wait()


def energy_difference(cell, L, F, files):
    from contactmg.hertz import hertz_problem
    p = hertz_problem(cell, L, F)
    a, b = np.load(files[0]), np.load(files[1])
    d = a - b
    fixed = p.fixed.astype(bool)
    d[fixed] = 0
    num = float(np.sqrt(max(np.sum(d * p.A.matvec(d)), 0.0)))
    den = float(np.sqrt(max(np.sum(b * p.A.matvec(b)), 1e-300)))
    return num / den


def counts(old, new, cell, levels, frictions, tmp):
    rows = []
    for L in levels:
        for F in frictions:
            res = {}
            files = []
            for name, w in (("old", old), ("new", new)):
                f = os.path.join(tmp, f"{name}_{cell}_{L}_{F}.npy")
                res[name] = w.ask(op="solve", cell=cell, level=L, F=F, save=f)
                files.append(f)
            diff = energy_difference(cell, L, F, files) if L <= 8 else None
            rows.append({"cell": cell, "level": L, "F": F, "old": res["old"]["cycles"], "new": res["new"]["cycles"],
                         "old_converged": res["old"]["converged"], "new_converged": res["new"]["converged"],
                         "new_violation": res["new"]["violation"], "energy_diff": diff})
            print(f"{cell:8s} L{L} F={F:<5} cycles old {res['old']['cycles']:3d} new {res['new']['cycles']:3d}  "
                  f"rel. energy-norm diff {diff:.2e}  check {res['new']['violation']:.1e}", flush=True)
    return rows


def timing(old, new, cell, L, F, reps):
    for w in (old, new):
        w.ask(op="prepare", cell=cell, level=L, F=F)
    t = {"old": [], "new": []}
    cpu = {"old": [], "new": []}
    cyc = {}
    for k in range(reps):
        for name, w in ((("old", old), ("new", new)) if k % 2 == 0 else (("new", new), ("old", old))):
            r = w.ask(op="time")
            t[name].append(r["seconds"] / r["cycles"])
            cpu[name].append(r["cpu"] / r["cycles"])  # the solve runs on this thread: CPU time is less load-dependent
            cyc[name] = r["cycles"]
    med = {k: float(np.median(v)) for k, v in t.items()}
    best = {k: float(np.min(v)) for k, v in t.items()}
    row = {"cell": cell, "level": L, "F": F, "reps": reps, "old_s_per_cycle": med["old"], "new_s_per_cycle": med["new"],
           "ratio": med["new"] / med["old"], "old_min": best["old"], "new_min": best["new"],
           "ratio_min": best["new"] / best["old"], "old_cycles": cyc["old"], "new_cycles": cyc["new"],
           "old_all": t["old"], "new_all": t["new"], "old_cpu": cpu["old"], "new_cpu": cpu["new"],
           "cpu_ratio": float(np.median(cpu["new"]) / np.median(cpu["old"]))}
    print(f"timing {cell} L{L} F={F}: median old {med['old']:.4f} new {med['new']:.4f} s/cycle (ratio {row['ratio']:.3f}); "
          f"fastest old {best['old']:.4f} new {best['new']:.4f} (ratio {row['ratio_min']:.3f}); {reps} interleaved solves each; "
          f"load average {os.getloadavg()[0]:.1f}; CPU time per cycle median old {np.median(cpu['old']):.4f} new "
          f"{np.median(cpu['new']):.4f} (ratio {row['cpu_ratio']:.3f})", flush=True)
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="directory with the old build's contactmg package")
    ap.add_argument("--json", help="write the tables here")
    ap.add_argument("--quick", action="store_true", help="levels 3-5 and F = 0.4, 5 only; timing at level 6")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--skip-counts", action="store_true")
    ap.add_argument("--skip-timing", action="store_true")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    old, new = Worker(a.old), Worker("-")
    print(f"old: {old.where}\nnew: {new.where}", flush=True)
    out = {"counts": [], "timing": []}
    fr = (0.4, 5.0) if a.quick else FRICTIONS
    with tempfile.TemporaryDirectory() as tmp:
        if not a.skip_counts:
            out["counts"] += counts(old, new, "triangle", range(3, 6 if a.quick else 9), fr, tmp)
            out["counts"] += counts(old, new, "quad", range(3, 6 if a.quick else 8), fr, tmp)
    if not a.skip_timing:
        for L in ((6,) if a.quick else (8, 9)):
            out["timing"].append(timing(old, new, "triangle", L, 0.4, a.reps))
    old.close()
    new.close()
    c = out["counts"]
    if c:
        worst = max(r["new"] - r["old"] for r in c)
        print(f"cycle counts: new - old at most {worst:+d} over {len(c)} runs; largest energy-norm difference "
              f"{max(r['energy_diff'] for r in c):.2e}; all new converged: {all(r['new_converged'] for r in c)}")
    out["seconds"] = time.perf_counter() - t0
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
