"""Comments and pages that point to a decision record point to one that exists."""
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LINK = re.compile(r"decisions/(\d{4}-[a-z0-9-]*[a-z0-9])")


def test_every_decision_link_resolves():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    records = {p.stem for p in (ROOT / "docs" / "dev" / "decisions").glob("[0-9]*.md")}
    assert len(records) >= 18
    seen, broken = 0, []
    for name in files:
        path = ROOT / name
        if path.suffix not in (".py", ".hpp", ".cpp", ".md", ".yml", ".txt") or not path.is_file():
            continue
        for m in LINK.finditer(path.read_text(errors="replace")):
            seen += 1
            if m.group(1) not in records:
                broken.append(f"{name}: {m.group(1)}")
    assert seen > 0
    assert not broken, broken
