"""Every public name of the package says what it is: the exported names and every public class and
function (and public method of a public class) defined in the layer modules carry a docstring."""
import importlib
import inspect
import pkgutil

import contactmg

LAYERS = ("mesh", "distributed", "model", "results", "solve", "examples", "cli")


def _modules():
    for layer in LAYERS:
        pkg = importlib.import_module(f"contactmg.{layer}")
        yield pkg
        for info in pkgutil.iter_modules(pkg.__path__):
            yield importlib.import_module(f"contactmg.{layer}.{info.name}")


def _missing(obj, name):
    doc = inspect.getdoc(obj)
    return [] if doc and doc.strip() else [name]


def test_exported_names_have_docstrings():
    missing = []
    for name in contactmg.__all__:
        obj = getattr(contactmg, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            missing += _missing(obj, name)
    assert not missing, missing
    assert contactmg.ContactProblem.__doc__ and contactmg.Problem.__doc__ and contactmg.Solver.solve.__doc__


def test_public_functions_classes_and_methods_of_the_layers_have_docstrings():
    missing = []
    for mod in _modules():
        missing += _missing(mod, mod.__name__) if mod.__name__.count(".") > 1 else []
        for name, obj in vars(mod).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
                continue
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            missing += _missing(obj, f"{mod.__name__}.{name}")
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    fn = member.fget if isinstance(member, property) else member
                    if inspect.isfunction(fn) or isinstance(member, (classmethod, staticmethod)):
                        target = fn.__func__ if isinstance(member, (classmethod, staticmethod)) else fn
                        missing += _missing(target, f"{mod.__name__}.{name}.{attr}")
    assert not missing, "no docstring: " + ", ".join(missing)


def test_solve_signatures_stay_short():
    for fn in (contactmg.Solver.solve, contactmg.Problem.solve, contactmg.LoadPath.solve):
        params = [p for p in inspect.signature(fn).parameters.values() if p.kind is not p.VAR_KEYWORD]
        assert len(params) <= 8, (fn.__qualname__, len(params))
