"""The command line contract: JSON keys, exit statuses, one-line errors."""
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

KEYS = ["problem", "dim", "cell", "levels", "nodes", "dofs", "method", "friction", "tol", "converged", "cycles",
        "outer_iterations", "setup_seconds", "solve_seconds", "history", "contact_nodes", "stick_nodes", "slip_nodes",
        "contact_halfwidth", "stick_halfwidth", "reaction", "max_normal_stress", "peak_rss_mb"]


def run(*args, timeout=120, cwd=None):
    return subprocess.run([sys.executable, "-m", "contactmg", *args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd)


@pytest.mark.parametrize("args,word", [
    (["--levels", "0"], "levels"), (["--frictions", "-0.4"], "frictions"), (["--frictions", "inf"], "frictions"),
    (["--cell", "hexagon"], "cell"), (["--plot", "t.bmp"], "--plot"), (["--json", "a_file/t.json"], "a_file"),
])
def test_table1_bad_arguments_exit_2(args, word, tmp_path):
    (tmp_path / "a_file").write_text("")  # a folder of an output path that is a file
    r = run("table1", *args, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert word in r.stderr.strip().splitlines()[-1]


def test_linear_reference_reports_the_nmg_solve_of_the_same_run():
    """`--method linear` first solves with nmg for the contact state; the JSON carries that solve's
    cycles and seconds and their ratio, all measured in one process."""
    r = run("hertz", "--levels", "5", "--method", "linear", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["nmg_cycles"] >= 10 and d["nmg_solve_seconds"] > 0
    assert d["nmg_over_linear"] == pytest.approx(d["nmg_solve_seconds"] / d["solve_seconds"])


@pytest.mark.parametrize("method", ["nmg", "fixed-point", "linear"])
def test_hertz_json(tmp_path, method):
    r = run("hertz", "--levels", "4", "--method", method, "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert all(k in d for k in KEYS), set(KEYS) - set(d)
    assert d["method"] == method and d["levels"] == 4 and d["dofs"] == 2 * d["nodes"] and d["converged"]
    assert (d["outer_iterations"] is None) == (method != "fixed-point")
    assert len(d["history"]) == d["cycles"] and d["history"][-1]["correction_norm"] <= 1e-11
    assert d["reaction"][1] > 0 and d["contact_nodes"] == d["stick_nodes"] + d["slip_nodes"]
    assert d["stick_halfwidth"] <= d["contact_halfwidth"]


def test_hertz_outputs_and_no_convergence_status(tmp_path):
    js, vtu, png = tmp_path / "h.json", tmp_path / "h.vtu", tmp_path / "h.png"
    r = run("hertz", "--levels", "5", "--cell", "quad", "--max-cycles", "3", "--json", str(js), "--vtu", str(vtu),
            "--plot", str(png), "-q")
    assert r.returncode == 3, r.stderr
    d = json.loads(js.read_text())
    assert d["converged"] is False and d["cycles"] == 3
    assert vtu.stat().st_size > 1000 and png.read_bytes()[:4] == b"\x89PNG"


def test_output_paths_in_missing_folders_are_made(tmp_path):
    """--json, --vtu and --plot into folders that do not exist yet: the folders are made."""
    js, vtu, png = tmp_path / "out" / "h.json", tmp_path / "out" / "deeper" / "h.vtu", tmp_path / "pics" / "h.png"
    r = run("hertz", "--levels", "3", "--json", str(js), "--vtu", str(vtu), "--plot", str(png), "-q")
    assert r.returncode == 0, r.stderr
    assert json.loads(js.read_text())["levels"] == 3
    assert vtu.stat().st_size > 1000 and png.read_bytes()[:4] == b"\x89PNG"


def test_a_refused_command_line_makes_no_output_folder(tmp_path):
    r = run("hertz", "--levels", "0", "--json", "out/h.json", cwd=tmp_path)
    assert r.returncode == 2 and not (tmp_path / "out").exists()


@pytest.mark.parametrize("args,word", [
    (["--friction", "-1"], "friction"), (["--friction", "nan"], "friction"), (["--tol", "0"], "tol"),
    (["--tol", "nan"], "tol"), (["--levels", "0"], "levels"), (["--levels", "50"], "levels"),
    (["--cell", "hexagon"], "cell"), (["--method", "newton"], "method"), (["--max-cycles", "0"], "max-cycles"),
    (["--json", "a_file/dir/x.json"], "a_file"), (["--levels", "x"], "levels"),
    (["--tol", "-1e-9"], "tol"), (["--vtu", "out.txt"], "--vtu"), (["--plot", "out.jpg"], "--plot"),
    (["--nu1", "-1"], "nu1"), (["--cycle", "Z"], "cycle"),
    (["--levels", "14"], "levels"),
])
def test_bad_arguments_exit_2_with_a_message(args, word, tmp_path):
    (tmp_path / "a_file").write_text("")  # a folder of an output path that is a file
    r = run("hertz", *args, cwd=tmp_path)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert word in r.stderr.strip().splitlines()[-1]


def test_table1_json():
    r = run("table1", "--levels", "2", "3", "--frictions", "0.4", "5", "--json", "-", "-q")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    for k in ("levels", "dofs", "frictions", "fixed_point_iterations", "fixed_point_vcycles", "nmg_vcycles"):
        assert k in d
    assert d["levels"] == [2, 3] and d["frictions"] == [0.4, 5.0]
    assert np.array(d["nmg_vcycles"]).shape == (2, 2) and np.array(d["fixed_point_vcycles"]).shape == (2, 2)
    assert all(v > n for fr, nr in zip(d["fixed_point_vcycles"], d["nmg_vcycles"]) for v, n in zip(fr, nr))


def test_ctrl_c_stops_a_long_solve_cleanly():
    """The CLI interrupted inside the solve (the child announces on stderr when the C++ solve is
    entered, so the signal does not land in the setup): exit 130, one line, no traceback."""
    code = ("import sys\n"
            "import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"  # a suite started in the background inherits SIGINT ignored
            "from contactmg import _core\nfrom contactmg.cli import main as cli\n"
            "orig = _core.ContactSolver2D.solve\n"
            "def solve(self, *a, **k):\n"
            "    print('SOLVING', file=sys.stderr, flush=True)\n"
            "    return orig(self, *a, **k)\n"
            "_core.ContactSolver2D.solve = solve\n"
            "sys.exit(cli.main(['hertz', '--levels', '7', '--max-cycles', '100000', '--tol', '1e-300']))\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stderr.readline().strip() == "SOLVING"
    time.sleep(1.0)  # inside the cycles
    t0 = time.time()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert time.time() - t0 < 10
    assert p.returncode == 130 and err.strip() == "contactmg hertz: interrupted", err


def test_solve_releases_the_gil():
    """Another Python thread makes progress *during* the C++ solve: it timestamps its work, and
    samples must fall in the middle half of the solve window (a call that held the GIL would leave
    that window empty: the thread only runs in the switch intervals before and after)."""
    from contactmg.examples import hertz

    p = hertz.hertz_problem("triangle", 7, 0.4)
    p.solver.core  # noqa: B018
    stamps = []
    done = threading.Event()

    def spin():
        k = 0
        while not done.is_set():
            k += 1
            if k % 2000 == 0:
                stamps.append(time.perf_counter())

    t = threading.Thread(target=spin)
    t.start()
    time.sleep(0.05)
    t0 = time.perf_counter()
    p.solve(tol=1e-300, max_cycles=20)
    t1 = time.perf_counter()
    done.set()
    t.join()
    lo, hi = t0 + 0.25 * (t1 - t0), t0 + 0.75 * (t1 - t0)
    inside = sum(lo <= s <= hi for s in stamps)
    assert t1 - t0 > 0.2 and inside >= 10, (t1 - t0, inside, len(stamps))


def test_ctrl_c_inside_the_cycles_stops_the_solve():
    """SIGINT sent while the C++ cycles run ends the solve within a second or two with
    KeyboardInterrupt, not a crash. The child reports every finished cycle through the progress
    callback and says READY after the first one, so the signal reaches the cycles, not the setup;
    the solver is usable afterwards."""
    code = ("import sys, time\n"
            "import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"  # a suite started in the background inherits SIGINT ignored
            "from contactmg.examples import hertz\n"
            "p = hertz.hertz_problem('triangle', 7, 0.4); s = p.solver.core\n"
            "seen = []\n"
            "def progress(rec):\n"
            "    seen.append(rec['cycle'])\n"
            "    if len(seen) == 1: print('READY', flush=True)\n"
            "t = time.time()\n"
            "try:\n"
            "    s.solve(None, dict(tol=1e-300, rtol=0, max_cycles=100000), progress=progress)\n"
            "except KeyboardInterrupt:\n"
            "    r = s.solve(None, dict(max_cycles=2))\n"
            "    print('interrupted after %.1f s, %d cycles; then %d' % (time.time() - t, len(seen), r['cycles']), flush=True)\n"
            "    sys.exit(130)\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "READY"
    time.sleep(1.0)
    t0 = time.time()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=30)
    assert time.time() - t0 < 5, out
    assert p.returncode == 130 and "interrupted after" in out and "Traceback" not in err, (out, err)
    cycles = int(out.split(", ")[1].split()[0])
    assert cycles >= 2 and out.strip().endswith("then 2"), out


def _help(command, capsys):
    from contactmg.cli.main import main

    with pytest.raises(SystemExit) as e:
        main([command, "--help"])
    assert e.value.code == 0
    # argparse wraps at the terminal width: one line per option's text
    return " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("command,shown", [
    ("hertz", ["--levels LEVELS levels in all; level 1 is the coarse mesh (default: 6)",
               "(0: frictionless) (default: 0.4)", "(default: nmg)", "(default: 1e-11)", "(default: triangle)",
               "(default: 200)", "(default: F)", "(default: uniform)"]),
    ("table1", ["(default: 3 5 7 9 11 on the adaptive hierarchy", "(default: the paper's ten",
                "(default: triangle)"]),
    ("sphere", ["(default: 0.4)", "(default: hexahedron)", "(default: nmg)", "(default: 1e-11)", "(default: 0.02)"]),
    ("cork", ["(default: 0.4)", "(default: nmg)", "(default: 3)", "(mm) (default: 0.2)"]),
    ("cylinders", ["(0: frictionless) (default: 0.4)", "(default: 5)", "(default: 2000.0)", "(default: 0.28)"]),
    ("spheres", ["(0: frictionless) (default: 0.4)", "(default: hexahedron)", "(default: 3)"]),
])
def test_help_shows_the_defaults(command, shown, capsys):
    text = _help(command, capsys)
    for s in shown:
        assert s in text, (s, text)
    # no option with a value to show goes without it
    from contactmg.cli.main import _parser

    sub = next(a for a in _parser()._actions if a.dest == "command").choices[command]
    for action in sub._actions:
        if action.option_strings and action.default not in (None, False) and action.dest != "help":
            assert "default" in (sub.formatter_class("x")._get_help_string(action) or ""), action.dest


@pytest.mark.parametrize("command", ["hertz", "sphere", "cork", "cylinders", "spheres"])
def test_every_solve_command_defaults_to_friction_0_4(command):
    from contactmg.cli.main import _parser

    args = _parser().parse_args([command])
    assert args.friction == 0.4


def test_cylinders_without_friction_option_solves_with_coulomb_0_4(tmp_path):
    r = run("cylinders", "--levels", "3", "--json", "-", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    # friction holds some nodes (frictionless, every node in contact slides)
    assert d["friction"] == 0.4 and d["stick_nodes"] > 0
