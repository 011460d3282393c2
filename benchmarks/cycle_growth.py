"""Why the cycle counts of Algorithm 2 grow over the adaptive Hertz levels 3-11 (issue 11's target
"flat over levels 3-11"): one hierarchy, three prolongations / geometries, and the pieces of a cycle
count (rate per cycle, size of the first correction).

    python benchmarks/cycle_growth.py [--parts linear alg2 uniform nu] [--levels 3 5 7 9 11]
        [--frictions 0.08 0.4 2] [--uniform-levels 3 8] [--omega 1.0] [--omega-post 1.7]
        [--json out/cycle_growth.json]

--omega sets ContactProblem.smoother_omega for every solve (default: the problems' own default, 1.4
on triangles since issue 11; 1.0 gives the plain Gauss-Seidel of the measurements before it);
--omega-post sets ContactProblem.smoother_omega_post (the post-smoothing sweeps' own; --omega 1 --omega-post 1.7
is the split relaxation of issue 11, fifth part).

Variants of the same adaptive hierarchy (hertz_adaptive_hierarchy(11), cached in
out/cache/hertz_adaptive_11.pkl; the same cells on every variant):
  projected    as built: new boundary nodes projected onto the circle, prolongation weights 1/2, 1/2
  polygon      no projection: every node at the weighted mean of its parents (polygonal boundary)
  barycentric  projected, prolongation rows of the projected nodes = barycentric coordinates of the
               projected point in the coarse cell (contactmg.hierarchy.boundary_interpolation):
               P reproduces every linear field

linear:  contraction per F(3,3) and V(3,3) cycle of the linear multigrid (Dirichlet top, no contact,
         zero load, random start, geometric mean of the last 5 of 14 correction ratios), and the
         cycles of the Dirichlet problem (u = (0, -0.005) on top) to tol 1e-11 from u = 0 and from the
         coarse lift (the Dirichlet data on the coarsest mesh, zero elsewhere, interpolated up: its
         energy does not grow with the level, the fine lift's grows like h^-1/2).
alg2:    Algorithm 2 (Coulomb F, F(3,3), tol 1e-11, from u = 0) and the linear solve with its final
         contact state known (--method linear), per variant and level; the first correction norm.
uniform: uniform triangles, levels as given: linear rates and Algorithm 2 / known-state cycles with V
         and F cycles (F = 0.4), projected and barycentric.
nu:      linear F(nu, nu) rates on the adaptive levels for nu = 1, 2, 3, 4, 6 (and material nu = 0).
Cycle counts and rates do not depend on the machine's load.
"""
import argparse
import os
import pickle
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from bench_json import write_json  # noqa: E402
from linear_multigrid import contraction  # noqa: E402

from contactmg.generators import HERTZ_TOP, hertz_half_disk, hertz_projector  # noqa: E402
from contactmg.hertz import hertz_adaptive_hierarchy, hertz_problem_on  # noqa: E402
from contactmg.hierarchy import MeshHierarchy, boundary_interpolation  # noqa: E402
from contactmg.material import Material  # noqa: E402
from contactmg.mesh import Mesh  # noqa: E402
from contactmg.problem import ContactProblem, Dirichlet, dirichlet_arrays  # noqa: E402

CACHE = os.path.join("out", "cache", "hertz_adaptive_11.pkl")
TOP = (0.0, -0.005)


def adaptive_hierarchy(levels=11):
    """hertz_adaptive_hierarchy(11) built once (40 s loaded) and pickled."""
    if os.path.exists(CACHE):
        with open(CACHE, "rb") as fh:
            h = pickle.load(fh)
        if h.levels >= levels:
            return h.truncated(levels)
    h = hertz_adaptive_hierarchy(max(levels, 11), 0.4)
    os.makedirs(os.path.dirname(CACHE), exist_ok=True)
    with open(CACHE, "wb") as fh:
        pickle.dump(h, fh)
    return h.truncated(levels)


def polygon(h):
    meshes = [h.meshes[0]]
    for m, t in zip(h.meshes[1:], h.transfers):
        meshes.append(Mesh._trusted(t.matrix() @ meshes[-1].points, m.cells, m.cell_type, m.facets, m.facet_tags))
    return MeshHierarchy(meshes, list(h.transfers), h.build_seconds, h.kind, list(h.estimated_error))


def barycentric(h):
    ts = [boundary_interpolation(c, f.points, t) for c, f, t in zip(h.meshes[:-1], h.meshes[1:], h.transfers)]
    return MeshHierarchy(list(h.meshes), ts, h.build_seconds, h.kind, list(h.estimated_error))


VARIANTS = {"projected": lambda h: h, "polygon": polygon, "barycentric": barycentric}


def linear_problem(h, value=(0.0, 0.0), **kw):
    return ContactProblem(h, Material(2000.0, kw.pop("poisson", 0.28)), [Dirichlet([HERTZ_TOP], value)], **kw)


def coarse_lift(h, value=TOP):
    fixed, vals = dirichlet_arrays(h.meshes[0], [Dirichlet([HERTZ_TOP], value)])
    u = np.where(fixed.astype(bool), vals, 0.0)
    for t in h.transfers:
        u = t.matrix() @ u
    return u


def tail_rate(c):
    c = np.asarray(c)
    return float(np.exp(np.mean(np.log(c[-5:] / c[-6:-1])))) if len(c) > 6 else None


def part_linear(full, levels, rows):
    print("linear multigrid (Dirichlet top, no contact): rate F / rate V / cycles from 0 / cycles from coarse lift")
    for name, make in VARIANTS.items():
        hv = make(full)
        for L in levels:
            h = hv.truncated(L)
            r = {"part": "linear", "variant": name, "level": L, "dofs": 2 * h.finest.num_points,
                 "rate_F": contraction(linear_problem(h, cycle="F"))[0], "rate_V": contraction(linear_problem(h, cycle="V"))[0]}
            q = linear_problem(h, TOP)
            a, b = q.solve(tol=1e-11), q.solve(tol=1e-11, u0=coarse_lift(h))
            r.update(cycles_zero=a.cycles, cycles_lift=b.cycles, first_zero=float(a.history["correction_norm"][0]),
                     first_lift=float(b.history["correction_norm"][0]))
            rows.append(r)
            print(f"  {name:11} L{L:<2} {r['dofs']:>8,}  {r['rate_F']:.3f} {r['rate_V']:.3f}  {a.cycles:3d} {b.cycles:3d}  "
                  f"first {r['first_zero']:.2f} / {r['first_lift']:.2f}", flush=True)


def part_alg2(full, levels, frictions, variants, rows):
    print("Algorithm 2 cycles (known-state linear cycles), first correction, tail rate")
    for name in variants:
        hv = VARIANTS[name](full)
        for F in frictions:
            line = []
            for L in levels:
                p = hertz_problem_on(hv.truncated(L), F)
                r = p.solve("nmg", tol=1e-11)
                lin = p.solve("linear", tol=1e-11, reference=r)
                rows.append({"part": "alg2", "variant": name, "F": F, "level": L, "dofs": 2 * p.mesh.num_points,
                             "cycles": r.cycles, "converged": bool(r.converged), "linear_cycles": lin.cycles,
                             "first": float(r.history["correction_norm"][0]), "tail_rate": tail_rate(r.history["correction_norm"])})
                line.append(f"{r.cycles}{'' if r.converged else '!'} ({lin.cycles})")
            print(f"  {name:11} F={F:<5} " + " / ".join(line), flush=True)


def part_uniform(levels, rows):
    print("uniform triangles: linear rate F / V; Algorithm 2 F = 0.4 cycles V / F (known state V / F)")
    for name in ("projected", "barycentric"):
        for L in levels:
            h = MeshHierarchy.build(hertz_half_disk("triangle"), L, projector=hertz_projector())
            h = VARIANTS[name](h)
            r = {"part": "uniform", "variant": name, "level": L, "dofs": 2 * h.finest.num_points,
                 "rate_F": contraction(linear_problem(h, cycle="F"))[0], "rate_V": contraction(linear_problem(h, cycle="V"))[0]}
            for c in "VF":
                p = hertz_problem_on(h, 0.4, cycle=c)
                s = p.solve("nmg", tol=1e-11)
                r[f"alg2_{c}"], r[f"known_{c}"] = s.cycles, p.solve("linear", tol=1e-11, reference=s).cycles
            rows.append(r)
            print(f"  {name:11} L{L} {r['dofs']:>9,}  {r['rate_F']:.3f} {r['rate_V']:.3f}  {r['alg2_V']} / {r['alg2_F']} "
                  f"({r['known_V']} / {r['known_F']})", flush=True)


def part_nu(full, levels, rows):
    print("linear F(nu, nu) rate on the adaptive levels, nu = 1 2 3 4 6; material nu = 0 with F(3,3)")
    for L in levels:
        h = full.truncated(L)
        rates = [contraction(linear_problem(h, cycle="F", nu1=n, nu2=n))[0] for n in (1, 2, 3, 4, 6)]
        r0 = contraction(linear_problem(h, cycle="F", poisson=0.0))[0]
        rows.append({"part": "nu", "level": L, "rates": rates, "rate_poisson0": r0})
        print(f"  L{L:<2} " + " ".join(f"{x:.3f}" for x in rates) + f"   nu=0: {r0:.3f}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", nargs="+", default=["linear", "alg2", "uniform", "nu"])
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 5, 7, 9, 11])
    ap.add_argument("--frictions", type=float, nargs="+", default=[0.08, 0.4, 2.0])
    ap.add_argument("--variants", nargs="+", default=["projected", "barycentric"])
    ap.add_argument("--uniform-levels", type=int, nargs=2, default=[3, 8])
    ap.add_argument("--omega", type=float, default=None)
    ap.add_argument("--omega-post", type=float, default=None,
                    help="ContactProblem.smoother_omega_post: the post-smoothing sweeps' own omega (issue 11, fifth part)")
    ap.add_argument("--json")
    a = ap.parse_args()
    ContactProblem.smoother_omega = a.omega
    ContactProblem.smoother_omega_post = a.omega_post
    rows = []
    full = adaptive_hierarchy(max(a.levels)) if set(a.parts) & {"linear", "alg2", "nu"} else None
    if "linear" in a.parts:
        part_linear(full, a.levels, rows)
    if "alg2" in a.parts:
        part_alg2(full, a.levels, a.frictions, a.variants, rows)
    if "uniform" in a.parts:
        part_uniform(range(a.uniform_levels[0], a.uniform_levels[1] + 1), rows)
    if "nu" in a.parts:
        part_nu(full, a.levels, rows)
    write_json(a.json, rows)


if __name__ == "__main__":
    main()
