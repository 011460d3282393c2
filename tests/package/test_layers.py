"""The package is layered: each layer imports only the layers below it, and no module imports
itself back through a cycle."""
import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[2] / "python" / "contactmg"
LAYERS = ["mesh", "model", "results", "solve", "distributed", "examples", "cli"]


def modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG.parent).with_suffix("")
        name = ".".join(rel.parts)
        if name.endswith(".__init__"):
            name = name[: -len(".__init__")]
        yield name, path


def imports(name, path):
    """The contactmg modules that `name` imports (at any depth of its body)."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("contactmg"):
                out.add(target)
                out.update(f"{target}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("contactmg"))
    return out


def layer(module):
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else None


GRAPH = {name: imports(name, path) for name, path in modules()}


@pytest.mark.parametrize("name", sorted(n for n in GRAPH if layer(n) is not None))
def test_imports_only_downward(name):
    mine = layer(name)
    upward = sorted(t for t in GRAPH[name] if layer(t) is not None and layer(t) > mine)
    assert not upward, f"{name} ({LAYERS[mine]}) imports from a higher layer: {upward}"


def test_no_import_cycle():
    known = set(GRAPH)
    edges = {n: {t for t in GRAPH[n] if t in known and t != n and not n.startswith(t + ".")} for n in GRAPH}
    state, stack = {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for t in sorted(edges[n]):
            if state.get(t) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(t):] + [t]))
            if t not in state:
                visit(t)
        stack.pop()
        state[n] = 2

    for n in sorted(GRAPH):
        if n not in state:
            visit(n)
    assert len(state) == len(GRAPH) > 30


CPP = PKG.parents[1] / "cpp"
CPP_LAYERS = ["base", "fem", "laws", "model", "mg", "steps", "solver", "bindings"]
MAX_CPP_LINES = 500


def cpp_sources():
    return sorted(p for p in CPP.rglob("*") if p.suffix in (".hpp", ".cpp"))


def test_every_cpp_folder_is_a_known_layer():
    assert {p.parent.name for p in cpp_sources()} <= set(CPP_LAYERS)


@pytest.mark.parametrize("path", cpp_sources(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_a_cpp_file_includes_only_its_own_layer_and_those_below(path):
    """cpp/README.md's order: base, fem, laws, model, mg, steps, solver, bindings; a folder includes
    from itself and the folders before it, with no exception."""
    own = CPP_LAYERS.index(path.parent.name)
    for line in path.read_text().splitlines():
        if line.startswith('#include "'):
            target = line.split('"')[1]
            layer = target.split("/")[0]
            assert layer in CPP_LAYERS, (path, target)
            assert CPP_LAYERS.index(layer) <= own, f"{path.parent.name}/{path.name} includes {target}"


@pytest.mark.parametrize("path", cpp_sources(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_no_cpp_file_is_over_500_lines(path):
    assert len(path.read_text().splitlines()) <= MAX_CPP_LINES
