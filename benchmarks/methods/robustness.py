"""Robustness of Algorithm 2: numerical stress scenes and hard Coulomb cases, each result checked
against the discrete contact conditions (contactmg.results.checks.contact_conditions; a relative violation
<= VIOLATION_TOL counts as verified).

scenes   the Hertz half disk at one level with F from 0 to 1000, nearly incompressible material
         (nu = 0.45, 0.49), an obstacle out of reach, a push that brings the whole arc into contact,
         an initial penetration, and a flat layer of quadrilaterals of aspect ratio 1, 8, 32 pressed
         and sheared with friction: outcome, cycles, asymptotic contraction, solve seconds.
coulomb  large friction coefficients on the adaptive Hertz hierarchy (levels 9 and 11, F up to 100),
         the uniform triangles at F = 5 (levels 8, 9) and the tetrahedral sphere (F = 0.4 and 40).
held     bodies held only by their contacts, gaps to close, thin parts and lone meshes
         (benchmarks/held_scenes.py): a block pushed sideways (levels 3-7; default, nmg, tnnmg), a
         half plate on a cylinder (levels 3-6; frictionless, Coulomb) and the whole plate balanced on
         it (Coulomb, no supports), a block falling 0.5 onto the
         floor (levels 3-6; and lone meshes of 2n x n cells, n = 8-64), a thin plate pressed across
         a gap (structured and two gmsh meshes, levels 2-5, start zero and nested), lone meshes of
         30 to 2e5 dofs: cycles and the balance of load, reactions and contact forces.

    python benchmarks/methods/robustness.py [--parts scenes coulomb held] [--level 7]
        [--cases adaptive9 uniform8 sphere3] [--quick] [--json PATH]
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _common import parser, write_result  # noqa: E402

import contactmg as cm  # noqa: E402
from contactmg.results.checks import VIOLATION_TOL, contact_conditions  # noqa: E402
from contactmg.examples.hertz import hertz_adaptive_hierarchy, hertz_problem  # noqa: E402
from contactmg.solve.options import with_cycle  # noqa: E402


def hertz_scene(h, F=0.4, nu=0.28, push=-0.005, plane_y=0.0):
    """The Hertz half disk on hierarchy h with another material, push or obstacle position."""
    # the solve defaults of the recorded results: nmg F(3,3), the absolute stop 1e-11
    return with_cycle(cm.Problem(cm.Body(h, cm.Material(2000.0, nu), [cm.Dirichlet([cm.HERTZ_TOP], (0.0, push))],
                                         contact_tags=[cm.HERTZ_ARC]),
                                 obstacle=cm.PlaneObstacle((0.0, plane_y), (0.0, -1.0)),
                                 friction=cm.Coulomb(F) if F > 0 else cm.Frictionless()))


def layer(aspect, level=5):
    """4 x 4 quads of aspect ratio `aspect` (long and flat), refined, pressed and sheared with
    friction onto the rigid plane."""
    h = cm.MeshHierarchy.build(cm.rectangle(4, 4, lx=aspect * 1.0, ly=1.0, cell="quad"), level)
    # the solve defaults of the recorded results: nmg F(3,3), the absolute stop 1e-11
    return with_cycle(cm.Problem(cm.Body(h, cm.Material(100.0, 0.3), [cm.Dirichlet([cm.RECT_TOP], (0.01, -0.01))],
                                         contact_tags=[cm.RECT_BOTTOM]),
                                 obstacle=cm.PlaneObstacle((0.0, 0.0), (0.0, -1.0)), friction=cm.Coulomb(0.3)))


def rate(c):
    """Geometric mean of the last four correction ratios (nan when too few)."""
    c = np.asarray(c)
    return float(np.exp(np.mean(np.log(c[-4:] / c[-5:-1])))) if len(c) > 5 and np.all(c[-5:] > 0) else float("nan")


def scenes(level, layer_level):
    """(name, problem factory) of the stress scenes."""
    h = hertz_problem("triangle", level, 0.4).hierarchy
    out = [(f"F = {F:g}", lambda F=F: hertz_scene(h, F=F)) for F in (0.0, 1e-3, 0.4, 5.0, 40.0, 1e3)]
    out += [("nu = 0.45", lambda: hertz_scene(h, nu=0.45)), ("nu = 0.49", lambda: hertz_scene(h, nu=0.49)),
            ("gap 1.0: nothing touches", lambda: hertz_scene(h, plane_y=-1.0)),
            ("push 0.2: whole arc touches", lambda: hertz_scene(h, push=-0.2)),
            ("negative gap 0.002 (penetration)", lambda: hertz_scene(h, plane_y=0.002))]
    out += [(f"layer, quads aspect {s}", lambda s=s: layer(s, layer_level)) for s in (1, 8, 32)]
    return out


def coulomb_cases(names, adaptive_levels=(9, 11), uniform_levels=(8, 9), sphere_level=3):
    """(name, problem factory) of the hard Coulomb cases selected by names."""
    lo, hi = adaptive_levels
    if f"adaptive{lo}" in names or f"adaptive{hi}" in names:
        h = hertz_adaptive_hierarchy(hi if f"adaptive{hi}" in names else lo, 0.4)
        if f"adaptive{lo}" in names:
            for F in (5.0, 8.0, 20.0, 40.0, 100.0):
                yield (f"adaptive L{lo} F={F:g}",
                       lambda F=F: hertz_problem(friction=F, hierarchy=h.truncated(lo), coulomb_at_zero=True))
        if f"adaptive{hi}" in names:
            for F in (5.0, 8.0, 40.0):
                yield f"adaptive L{hi} F={F:g}", lambda F=F: hertz_problem(friction=F, hierarchy=h, coulomb_at_zero=True)
    for L in uniform_levels:
        if f"uniform{L}" in names:
            yield f"uniform tri L{L} F=5", lambda L=L: hertz_problem(levels=L, friction=5.0)
    if f"sphere{sphere_level}" in names:
        from contactmg.examples.sphere import sphere_problem
        for F in (0.4, 40.0):
            yield f"sphere tetra L{sphere_level} F={F:g}", lambda F=F: sphere_problem("tetra", sphere_level, F)


def run(cases, max_cycles):
    """Solves every case; rows with the outcome and the check."""
    rows = []
    print(f"{'case':34s} {'dofs':>9s} {'status':>10s} {'cycles':>6s} {'rate':>6s} {'violation':>9s} {'seconds':>8s}")
    for name, make in cases:
        p = make()
        t = time.perf_counter()
        r = p.solve(max_cycles=max_cycles)
        sec = time.perf_counter() - t
        v = contact_conditions(p, r)["max"]
        ok = bool(r.converged and v <= VIOLATION_TOL)
        rows.append({"case": name, "dofs": int(p.load.size), "converged": r.converged, "verified": ok,
                     "status": r.status, "cycles": r.cycles, "rate": rate(r.history["correction_norm"]),
                     "violation": v, "seconds": sec, "contact_nodes": r.counts()["contact_nodes"],
                     "finite": bool(np.all(np.isfinite(r.displacement)))})
        print(f"{name:34s} {p.load.size:9d} {('verified' if ok else r.status[:10]):>10s} {r.cycles:6d} "
              f"{rows[-1]['rate']:6.3f} {v:9.1e} {sec:8.2f}", flush=True)
    return rows


def held(quick):
    """Rows of the scenes of held_scenes.py: scene, level (or cells), options, cycles of the finest
    level, the nested start's work in finest cycles, converged, balance, violation, seconds."""
    import held_scenes as hs

    def one(scene, level, make, options=None):
        p = make()
        t = time.perf_counter()
        r = cm.Solver(p, options or {}).solve()
        sec = time.perf_counter() - t
        row = {"scene": scene, "level": level, "options": ", ".join(f"{k}={v}" for k, v in (options or {}).items())
               or "default", "dofs": int(p.load.size), "cycles": r.cycles, "start": r.options["start"],
               "start_work": round(float(r.extra.get("nested_start", {}).get("work", 0.0)), 2),
               "converged": r.converged, "balance": hs.balance(r), "violation": contact_conditions(p, r)["max"],
               "seconds": sec}
        print(f"{scene:24s} {str(level):>6s} {row['options']:22s} {row['dofs']:8d} {r.cycles:4d}{'' if r.converged else '!'} "
              f"{row['start']:>6s} {row['start_work']:6.2f} {row['balance']:9.1e} {sec:7.2f}", flush=True)
        return row

    sideways, plate, falling, thin = ((3, 4), (3, 4), (3, 4), (2, 3)) if quick else \
        ((3, 4, 5, 6, 7), (3, 4, 5, 6), (3, 4, 5, 6), (2, 3, 4, 5))
    meshes = [("structured", None)] + ([] if quick else [("gmsh h 0.07", 0.07), ("gmsh h 0.05", 0.05)])
    lone2, lone3 = ((2, 8), (1, 5)) if quick else ((2, 5, 16, 64, 220), (1, 3, 8, 18, 30))
    falling_lone = (8,) if quick else (8, 16, 32, 64)
    rows = []
    for L in sideways:
        for o in (None, {"method": "nmg"}, {"method": "tnnmg"}):
            rows.append(one("sideways block", L, lambda: hs.sideways_block(L), o))
    for L in plate:
        rows.append(one("plate on cylinder", L, lambda: hs.plate_on_cylinder(L)))
        rows.append(one("plate on cylinder F 0.3", L, lambda: hs.plate_on_cylinder(L, cm.Coulomb(0.3))))
        rows.append(one("whole plate, cylinder, F 0.3", L, lambda: hs.whole_plate_on_cylinder(L)))
    for L in falling:
        rows.append(one("falling block", L, lambda: hs.falling_block(L)))
    for n in falling_lone:
        rows.append(one("falling block, lone mesh", f"n={n}", lambda: hs.falling_lone_block(n)))
    for name, h in meshes:
        mesh = hs.thin_plate_mesh(h)
        for L in thin:
            for o in ({"start": "zero"}, {"start": "nested"}):
                rows.append(one(f"thin plate, {name}", L, lambda: hs.thin_plate(mesh, L), o))
    for dim, sizes in ((2, lone2), (3, lone3)):
        for n in sizes:
            rows.append(one(f"lone mesh {dim}D", f"n={n}", lambda: hs.lone_block(n, dim)))
    return rows


def main():
    ap = parser(__doc__)
    ap.add_argument("--parts", nargs="+", choices=["scenes", "coulomb", "held"], default=["scenes", "coulomb", "held"])
    ap.add_argument("--level", type=int, default=7, help="Hertz level of the scenes")
    ap.add_argument("--layer-level", type=int, default=5)
    ap.add_argument("--cases", nargs="+", default=["adaptive9", "uniform8", "sphere3"],
                    help="adaptive9 adaptive11 uniform8 uniform9 sphere3")
    ap.add_argument("--max-cycles", type=int, default=300)
    a = ap.parse_args()
    kw = {}
    if a.quick:
        a.level, a.layer_level, a.cases = 3, 2, ["adaptive5", "uniform4", "sphere1"]
        kw = {"adaptive_levels": (5, 6), "uniform_levels": (4,), "sphere_level": 1}
    out = {"violation_tol": VIOLATION_TOL}
    if "scenes" in a.parts:
        out["scenes"] = run(scenes(a.level, a.layer_level), a.max_cycles)
    if "coulomb" in a.parts:
        out["coulomb"] = run(coulomb_cases(a.cases, **kw), a.max_cycles)
    if "held" in a.parts:
        out["held"] = held(a.quick)
    write_result(__file__, a, out)


if __name__ == "__main__":
    main()
