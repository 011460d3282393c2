"""The package is layered: each layer imports only the layers below it (but for the imports named in
DEFERRED_UPWARD, made when a function runs), and no module imports itself back through a cycle."""
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


def imports(name, path, where="anywhere"):
    """The contactmg modules that `name` imports: at any depth of its body ("anywhere"), only inside
    functions, when they run ("functions"), or only outside them, when the module is imported
    ("import")."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    tree = ast.parse(path.read_text())
    functions = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
    inside = {id(n) for f in ast.walk(tree) if isinstance(f, functions) for n in ast.walk(f)}
    nodes = [n for n in ast.walk(tree)
             if where == "anywhere" or (id(n) in inside) == (where == "functions")]
    out = set()
    for node in nodes:
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


# The one way up the layers: Problem.solve and Problem.solver (the description's convenience
# solve) run the solve layer, which they import when called, so that importing the model layer loads
# no solver. Allowed only inside function bodies of this module, only from these modules.
DEFERRED_UPWARD = {"contactmg.model.problem": ("contactmg.solve.options", "contactmg.solve.solver")}


def _allowed(name, target):
    return any(target == m or target.startswith(m + ".") for m in DEFERRED_UPWARD.get(name, ())) \
        and target not in AT_IMPORT[name]


def layer(module):
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else None


GRAPH = {name: imports(name, path) for name, path in modules()}
DEFERRED = {name: imports(name, path, "functions") for name, path in modules()}
AT_IMPORT = {name: imports(name, path, "import") for name, path in modules()}


@pytest.mark.parametrize("name", sorted(n for n in GRAPH if layer(n) is not None))
def test_imports_only_downward(name):
    mine = layer(name)
    upward = sorted(t for t in GRAPH[name] if layer(t) is not None and layer(t) > mine and not _allowed(name, t))
    assert not upward, f"{name} ({LAYERS[mine]}) imports from a higher layer: {upward}"


def test_no_import_cycle():
    known = set(GRAPH)
    edges = {n: {t for t in GRAPH[n] if t in known and t != n and not n.startswith(t + ".") and not _allowed(n, t)}
             for n in GRAPH}
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


def test_the_deferred_imports_up_are_in_functions_only():
    """The allowed imports of the solve layer in the model layer are made when a function runs: one
    at module level would load the solver with the description (and fail here)."""
    for name, allowed in DEFERRED_UPWARD.items():
        assert not [t for t in AT_IMPORT[name] if any(t == m or t.startswith(m + ".") for m in allowed)], name
        assert any(t in DEFERRED[name] for t in allowed), f"{name}: no deferred import left: drop it from DEFERRED_UPWARD"


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
            folder = target.split("/")[0]
            assert folder in CPP_LAYERS, (path, target)
            assert CPP_LAYERS.index(folder) <= own, f"{path.parent.name}/{path.name} includes {target}"


@pytest.mark.parametrize("path", cpp_sources(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_no_cpp_file_is_over_500_lines(path):
    assert len(path.read_text().splitlines()) <= MAX_CPP_LINES
