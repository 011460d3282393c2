"""Runs every benchmark (tens of minutes on 2 cores); each prints its table and writes JSON/PNG.

    python benchmarks/run_all.py [--out out] [--quick]
"""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out")
    ap.add_argument("--quick", action="store_true", help="smaller levels (a few minutes)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    top = 7 if a.quick else 9
    jobs = [
        ["linear_levels.py", "--levels", "3", str(top), "--json", os.path.join(a.out, "linear_levels.json")],
        ["scaling.py", "--cell", "triangle", "--levels", "3", str(top), "--out", a.out],
        ["scaling.py", "--cell", "quad", "--levels", "3", str(top - 1), "--out", a.out],
        ["work_precision.py", "--levels", "5", "6", "7"] + ([] if a.quick else ["8"]) + ["--out", a.out],
        ["skip_work.py", "--level", str(top - 1), "--out", a.out],
        ["stress.py", "--level", str(top - 2), "--out", a.out],
        ["discretization_error.py", "--levels", "3", str(top - 2), "--reference", str(top), "--out", a.out],
        # issue 11: adaptive Table 1 to level 9 (level 11 takes about an hour: Algorithm 1 at F >= 5)
        ["adaptive_table1.py", "--levels", *[str(L) for L in sorted({3, 5, 7, top})], "--reference-level", str(top),
         "--accuracy-adaptive", "3", str(top - 1), "--accuracy-uniform", "2", str(top - 3),
         "--cost-adaptive", *[str(L) for L in range(5, top + 1)], "--cost-uniform", *[str(L) for L in range(4, top)],
         "--out", a.out],
    ]
    if not a.quick:  # issue 4: Algorithm 1 at F = 5 up to the finest uniform level that fits (about 10 minutes)
        jobs.append(["fixed_point_F5.py", "--start", "6", "--stop", "9", "--out", a.out])
    for job in jobs:
        print(f"== {' '.join(job)}", flush=True)
        subprocess.run([sys.executable, os.path.join(HERE, job[0])] + job[1:], check=True)
    print("== table1", flush=True)
    subprocess.run([sys.executable, "-m", "contactmg", "table1", "--json", os.path.join(a.out, "table1.json"),
                    "--plot", os.path.join(a.out, "table1.png"), "-q"], check=True)


if __name__ == "__main__":
    main()
