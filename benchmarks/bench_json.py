"""The benchmarks' JSON output: `--json PATH` writes the results there (folders made as needed)."""
import json
import os


def write_json(path, data):
    """data to path as indented JSON; nothing when path is empty or None."""
    if not path:
        return
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1)
