"""The guide's table of solver options is checked against SolverOptions, the one place the fields
and their defaults are written: every field has a row, no row names another, and each row's
default is the field's."""
import ast
import dataclasses
import re
from pathlib import Path

from contactmg.solve.options import SolverOptions

PAGE = Path(__file__).resolve().parents[2] / "docs" / "guide" / "solver-options.md"


def rows():
    """(field names, their defaults as written) of each row of the options table."""
    out = []
    for line in PAGE.read_text().splitlines():
        if not line.startswith("| `"):
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        names = re.findall(r"`([a-z_0-9]+)`", cells[0])
        written = re.split(r"[(:]", cells[1], maxsplit=1)[0]
        defaults = [ast.literal_eval(t) for t in re.findall(r"`([^`]+)`", written)]
        if len(defaults) == 1:
            defaults *= len(names)
        out.append((names, defaults))
    return out


def test_every_field_has_one_row_and_no_row_names_another():
    named = [n for names, _ in rows() for n in names]
    fields = [f.name for f in dataclasses.fields(SolverOptions)]
    assert sorted(named) == sorted(fields)


def test_each_row_gives_the_fields_default():
    defaults = {f.name: f.default for f in dataclasses.fields(SolverOptions)}
    for names, written in rows():
        assert len(written) == len(names), names
        for name, value in zip(names, written):
            assert value == defaults[name] and type(value) is type(defaults[name]), (name, value, defaults[name])
