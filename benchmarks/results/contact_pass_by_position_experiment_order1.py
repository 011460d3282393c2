"""order1 experiment: Algorithm 2 on adaptive levels with an extra contact pass (env set per run)."""
import os, sys, json, subprocess, time
import numpy as np
ROOT = os.environ.get("ROOT", "/work/wt-perf")
sys.path.insert(0, ROOT + "/benchmarks")

def run(L, F, mode, key):
    env = dict(os.environ)
    env.pop("CMG_EXP_CONTACT_PASS", None)
    if mode:
        env["CMG_EXP_CONTACT_PASS"] = str(mode)
        env["CMG_EXP_CONTACT_ORDER"] = f"/tmp/exp/order_L{L}_{key}.txt"
    out = subprocess.run([sys.executable, __file__, "child", str(L), str(F), key], env=env, capture_output=True, text=True)
    return out.stdout.strip().splitlines()[-1] if out.stdout.strip() else out.stderr[-500:]

if len(sys.argv) > 1 and sys.argv[1] == "child":
    from cycle_growth import adaptive_hierarchy
    from contactmg.hertz import hertz_problem_on
    from contactmg.checks import contact_conditions
    L, F, key = int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
    H = adaptive_hierarchy(11).truncated(L)
    p = hertz_problem_on(H, F)
    x = p.mesh.points[np.asarray(p.contact.nodes), 0]
    for k, (sel, srt) in {"out": (np.abs(x) < 0.05, np.abs(x)), "in": (np.abs(x) < 0.05, -np.abs(x)),
                                 "lr": (np.abs(x) < 0.05, x)}.items():
        idx = np.where(sel)[0]
        idx = idx[np.argsort(srt[idx], kind="stable")]
        fn = f"/tmp/exp/order_L{L}_{k}.txt"
        if not os.path.exists(fn):
            np.savetxt(fn, idx, fmt="%d")
    t0 = time.perf_counter()
    r = p.solve("nmg", tol=1e-11, max_cycles=200, threads=1)
    v = float(contact_conditions(p, r)["max"]) if r.converged else float("nan")
    print(json.dumps({"L": L, "F": F, "cycles": int(r.cycles), "conv": bool(r.converged), "check": v, "s": round(time.perf_counter() - t0, 1)}))
    sys.exit(0)

if __name__ == "__main__":
    levels = [int(a) for a in sys.argv[1].split(",")]
    Fs = [float(a) for a in sys.argv[2].split(",")]
    variants = sys.argv[3].split(",")  # e.g. 0:none,1:out,2:out,1:in
    for L in levels:
        for F in Fs:
            row = []
            for v in variants:
                mode, key = v.split(":")
                row.append((v, run(L, F, int(mode), key)))
            print(L, F, " | ".join(f"{v} {json.loads(r)['cycles'] if r.startswith('{') else r}" for v, r in row), flush=True)
            for v, r in row: print("   ", v, r, flush=True)
