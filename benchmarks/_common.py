"""Shared pieces of the benchmark scripts: the command line every script has (--quick, --json) and
the result file, stamped with the commit, the date and the machine it was measured on.

Every script is run as `python benchmarks/<folder>/<name>.py [--quick] [--json PATH]`. Without
--json a full run writes benchmarks/results/<folder>/<name>.json (the current result file) and a
quick run writes nothing (pass --json to keep it)."""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import resource
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def script_id(script: str) -> str:
    """'<folder>/<name>' of a benchmark script path (e.g. 'paper/table1')."""
    p = Path(script).resolve()
    return f"{p.parent.name}/{p.stem}"


def parser(doc: str) -> argparse.ArgumentParser:
    """An argument parser with the script's docstring as help and the common --quick and --json."""
    ap = argparse.ArgumentParser(description=(doc or "").split("\n\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="tiny levels: seconds, for the tests")
    ap.add_argument("--json", default=None,
                    help="result file (default: benchmarks/results/<folder>/<name>.json on a full run, "
                         "none on a quick one)")
    return ap


def stamp() -> dict:
    """The commit (git rev-parse HEAD, '+dirty' with uncommitted changes), the UTC date and the machine."""
    def git(*args):
        try:
            return subprocess.run(["git", "-C", str(HERE), *args], capture_output=True, text=True,
                                  timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""
    commit = git("rev-parse", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+dirty"
    return {"commit": commit,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": {"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
                        "cores": os.cpu_count(), "python": platform.python_version()}}


def write_result(script: str, args: argparse.Namespace, results) -> str | None:
    """Writes {"benchmark", "mode", "argv", commit, date, machine, "results"} to args.json (default:
    the script's current result file on a full run, nothing on a quick run). Returns the path."""
    path = args.json
    if path is None and not args.quick:
        path = str(RESULTS / f"{script_id(script)}.json")
    if not path:
        return None
    data = {"benchmark": script_id(script), "mode": "quick" if args.quick else "full", "argv": sys.argv[1:]}
    data.update(stamp())
    data["results"] = _finite(results)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1, default=_plain, allow_nan=False)
        fh.write("\n")
    print(f"wrote {path}")
    return path


def _finite(x):
    """x with every NaN or infinite float replaced by None (strict JSON has no NaN)."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if hasattr(x, "tolist") and not isinstance(x, (str, bytes)):
        return _finite(x.tolist())
    return x


def _plain(x):
    """numpy scalars and arrays as JSON numbers and lists."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"not JSON serializable: {type(x).__name__}")


def peak_rss_mb() -> float:
    """This process's peak resident memory in MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run_child(code: str, *argv, timeout: float | None = None) -> dict:
    """Runs `code` in a fresh interpreter (so that its peak memory is its own) with argv; the last
    line of its standard output is JSON, returned as a dict ({"error": ...} when it failed)."""
    try:
        r = subprocess.run([sys.executable, "-c", code, *map(str, argv)], capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"did not finish within {timeout:.0f} s"}
    if r.returncode != 0 or not r.stdout.strip():
        tail = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else f"exit status {r.returncode}"
        return {"error": tail}
    return json.loads(r.stdout.strip().splitlines()[-1])


def gmsh_mesh(build, classify, size, dim, one_region: bool = False):
    """The mesh gmsh makes of the geometry `build()` adds (OpenCASCADE), with physical groups: each
    boundary entity tagged classify(its centre of mass), and every volume (surface in 2D) its own
    region tag 1, 2, ... (one_region: all of them region 1). `size`: a number (element sizes between
    size / 2 and size) or a callable (x, y, z) -> element size. gmsh is a dependency of contactmg."""
    import tempfile

    import gmsh
    import numpy as np

    import contactmg as cm

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("m")
        build()
        gmsh.model.occ.synchronize()
        if callable(size):
            gmsh.model.mesh.setSizeCallback(lambda d, t, x, y, z, lc: size(x, y, z))
            for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
                gmsh.option.setNumber(f"Mesh.{option}", 0)
        else:
            gmsh.option.setNumber("Mesh.MeshSizeMax", size)
            gmsh.option.setNumber("Mesh.MeshSizeMin", size / 2)
        volumes = gmsh.model.getEntities(dim)
        if one_region:
            gmsh.model.addPhysicalGroup(dim, [t for _, t in volumes], 1)
        else:
            for k, (_, tag) in enumerate(volumes):
                gmsh.model.addPhysicalGroup(dim, [tag], k + 1)
        groups = {}
        for _, tag in gmsh.model.getBoundary(volumes, combined=False, oriented=False):
            groups.setdefault(classify(np.array(gmsh.model.occ.getCenterOfMass(dim - 1, abs(tag)))), set()).add(abs(tag))
        for ptag, tags in groups.items():
            gmsh.model.addPhysicalGroup(dim - 1, sorted(tags), ptag)
        gmsh.model.mesh.generate(dim)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "m.msh")
            gmsh.write(path)
            return cm.read_mesh(path, dim=dim)
    finally:
        gmsh.finalize()
