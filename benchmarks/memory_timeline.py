"""Issue 15: where the peak resident memory of a Hertz solve happens.

    python benchmarks/memory_timeline.py [--level 9] [--dim 2] [--interval 0.01] [--json out.json]

A thread samples VmRSS every `interval` seconds and, whenever it sees a new maximum, records the
main thread's Python stack at that moment (the innermost frames: the call that holds the peak; a
peak inside the core shows the Python line that called it). Runs the CLI's path (problem, core
solver, solve, results, output) in this process and prints the top of the timeline: the highest
samples with their stacks and the RSS at each stage boundary.
"""
from __future__ import annotations

import argparse
import json
import sys
import threading
import time
import traceback


def rss_bytes() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


class Sampler(threading.Thread):
    def __init__(self, interval: float):
        super().__init__(daemon=True)
        self.interval, self.stop, self.peak, self.peak_stack, self.samples = interval, False, 0, "", []
        self.main = threading.main_thread().ident
        self.t0 = time.perf_counter()

    def run(self):
        while not self.stop:
            r = rss_bytes()
            t = time.perf_counter() - self.t0
            self.samples.append((t, r))
            if r > self.peak:
                self.peak = r
                frame = sys._current_frames().get(self.main)
                self.peak_stack = "".join(traceback.format_stack(frame, limit=6)) if frame else ""
            time.sleep(self.interval)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--level", type=int, default=9)
    ap.add_argument("--dim", type=int, default=2)
    ap.add_argument("--interval", type=float, default=0.01)
    ap.add_argument("--json")
    args = ap.parse_args()
    s = Sampler(args.interval)
    s.start()
    marks = []

    def mark(name):
        marks.append((name, time.perf_counter() - s.t0, rss_bytes()))

    from contactmg import cli
    mark("imports")
    argv = (["hertz", "--levels", str(args.level), "--friction", "0.4"] if args.dim == 2 else
            ["sphere", "--cell", "hexahedron", "--levels", str(args.level)]) + ["--json", "/dev/null", "-q"]
    rc = cli.main(argv)
    mark("cli done")
    s.stop = True
    s.join()
    dofs = None
    print(f"exit status {rc}; peak RSS {s.peak / 2**20:.1f} MiB at:\n{s.peak_stack}")
    for name, t, r in marks:
        print(f"{name:12s} t = {t:7.2f} s  rss {r / 2**20:8.1f} MiB")
    # a coarse profile: the max over each second
    prof = {}
    for t, r in s.samples:
        prof[int(t)] = max(prof.get(int(t), 0), r)
    print(" ".join(f"{k}s:{v / 2**20:.0f}" for k, v in sorted(prof.items())))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"peak": s.peak, "stack": s.peak_stack, "marks": marks, "profile": prof}, fh, indent=1)


if __name__ == "__main__":
    main()
