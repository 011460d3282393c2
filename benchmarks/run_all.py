"""Runs every benchmark in its full mode, one after another, each writing its current result file
under benchmarks/results/<folder>/<name>.json (tens of minutes to hours on 2 cores; `make benchmark`).
With --quick every script runs on tiny levels (seconds each) and writes its file under --out.

    python benchmarks/run_all.py [--quick] [--out out/benchmarks] [--only paper/table1 ...]
"""
import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FOLDERS = ("paper", "three_d", "methods", "performance", "model")


def scripts():
    """'<folder>/<name>' of every benchmark script."""
    return [f"{d}/{p.stem}" for d in FOLDERS for p in sorted((HERE / d).glob("*.py"))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny levels; results under --out")
    ap.add_argument("--out", default=os.path.join("out", "benchmarks"), help="result folder of a quick run")
    ap.add_argument("--only", nargs="+", default=None, help="folder/name of the scripts to run")
    a = ap.parse_args()
    failed = []
    for name in a.only or scripts():
        cmd = [sys.executable, str(HERE / f"{name}.py")]
        if a.quick:
            cmd += ["--quick", "--json", os.path.join(a.out, f"{name}.json")]
        print(f"== {name}", flush=True)
        t0 = time.perf_counter()
        r = subprocess.run(cmd)
        print(f"== {name}: exit status {r.returncode}, {time.perf_counter() - t0:.0f} s", flush=True)
        if r.returncode != 0:
            failed.append(name)
    if failed:
        print(f"failed: {' '.join(failed)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
