"""The benchmark pages are generated from benchmarks/results: every recorded JSON gets a section with
its stamp, and the numbers in the tables are the recorded ones."""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "docs" / "gen_benchmark_pages.py"
RESULTS = ROOT / "benchmarks" / "results"


def _generate(tmp_path, results=RESULTS):
    out = tmp_path / "bench"
    run = subprocess.run([sys.executable, str(SCRIPT), "--results", str(results), "--out", str(out)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return out


def test_every_result_has_a_stamped_section(tmp_path):
    out = _generate(tmp_path)
    files = sorted(RESULTS.glob("**/*.json"))
    assert files
    for f in files:
        data = json.loads(f.read_text())
        text = (out / f"{f.parent.name}.md").read_text()
        assert f"## {data['benchmark']}" in text
        assert f"at commit `{data['commit'][:10]}`" in text
        assert data["date"] in text
    index = (out / "index.md").read_text()
    for group in {f.parent.name for f in files}:
        assert f"({group}.md)" in index


def test_matrix_tables_are_indexed_friction_by_level(tmp_path):
    # A synthetic result with distinct values: the rendered table must put each value in its cell.
    res = tmp_path / "results" / "paper"
    res.mkdir(parents=True)
    (res / "t.json").write_text(json.dumps({
        "benchmark": "paper/t", "mode": "quick", "commit": "0123456789abcdef", "date": "2026-01-01",
        "machine": {"cores": 2}, "results": {"levels": [3, 5, 7], "frictions": [0.4, 2.0],
                                              "cycles": [[11, 12, 13], [21, 22, 23]]}}))
    text = (_generate(tmp_path, tmp_path / "results") / "paper.md").read_text()
    assert "| frictions \\ levels | 3 | 5 | 7 |" in text
    assert "| 0.4 | 11 | 12 | 13 |" in text
    assert "| 2 | 21 | 22 | 23 |" in text


def test_records_become_rows_with_the_recorded_values(tmp_path):
    out = _generate(tmp_path)
    data = json.loads((RESULTS / "paper" / "algorithm1_vs_2.json").read_text())
    text = (out / "paper.md").read_text()
    for row in data["results"]["rows"]:
        assert f"| {row['level']} | {row['cell']} |" in text
        assert f" {row['nmg_cycles']} |" in text


def test_missing_results_folder_is_exit_status_2(tmp_path):
    run = subprocess.run([sys.executable, str(SCRIPT), "--results", str(tmp_path / "none")],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "no results folder" in run.stderr
