"""The type stubs (``ernest_cpp/*.pyi``) and ``py.typed`` ship with the package and list exactly
what each module and each of its classes has at run time, so they cannot drift from the bindings."""

from __future__ import annotations

import ast
import importlib
import inspect
import os
import pkgutil

import pytest

import ernest_cpp

PACKAGE = os.path.dirname(os.path.abspath(ernest_cpp.__file__))
STUBS = sorted(os.path.relpath(os.path.join(d, f), PACKAGE)
               for d, _, files in os.walk(PACKAGE) for f in files if f.endswith(".pyi"))
# Imported helpers are not part of a module's interface.
FOREIGN = ("typing", "collections", "numpy", "enum", "abc", "builtins", "math", "gymnasium")


def _defined(body) -> set[str]:
    names = set()
    for node in body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign) and not ast.unparse(node.value).startswith(("np", "npt")):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))  # not type aliases
        elif isinstance(node, ast.ImportFrom):  # explicit re-exports: `from x import A as A`
            names.update(a.asname for a in node.names if a.asname == a.name)
    return {n for n in names if not n.startswith("_")}


def _public(module) -> set[str]:
    names = set()
    for name in dir(module):
        obj = getattr(module, name)
        if name.startswith("_") or name == "annotations" or inspect.ismodule(obj):
            continue
        if (getattr(obj, "__module__", None) or "").split(".")[0] in FOREIGN:
            continue
        names.add(name)
    return names


def _module(stub: str):
    return importlib.import_module("ernest_cpp." + stub[:-4].replace(os.sep, "."))


def _from_core(obj) -> bool:
    return (getattr(obj, "__module__", None) or "").startswith("ernest_cpp._core")


def _stub(name: str) -> ast.Module:
    with open(os.path.join(PACKAGE, name), encoding="utf-8") as fh:
        return ast.parse(fh.read(), name)


def test_package_is_marked_typed():
    assert os.path.isfile(os.path.join(PACKAGE, "py.typed"))


def test_every_module_exposing_the_core_has_a_stub():
    for info in pkgutil.walk_packages(ernest_cpp.__path__, "ernest_cpp."):
        if info.name.startswith("ernest_cpp._core") or "ray" in info.name:
            continue
        module = importlib.import_module(info.name)
        core = sorted(n for n in _public(module) if _from_core(getattr(module, n)))
        if core:
            assert os.path.isfile(module.__file__[:-3] + ".pyi"), (info.name, core)


@pytest.mark.parametrize("stub", STUBS)
def test_stub_lists_the_module_public_names(stub):
    module = _module(stub)
    stubbed, actual = _defined(_stub(stub).body), _public(module)
    assert not actual - stubbed, f"{stub} lacks {sorted(actual - stubbed)}"
    assert not stubbed - actual, f"{stub} lists names the module lacks: {sorted(stubbed - actual)}"


@pytest.mark.parametrize("stub", STUBS)
def test_stub_classes_list_their_members(stub):
    module = _module(stub)
    for node in _stub(stub).body:
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(module, node.name)
        if issubclass(cls, BaseException) or not _from_core(cls):
            continue  # Python classes: their own annotations are the reference
        actual = (set(cls.__members__) if hasattr(cls, "__members__")
                  else {n for n in dir(cls) if not n.startswith("_")})
        stubbed = _defined(node.body)
        assert stubbed == actual, (f"{stub}: {node.name} lacks {sorted(actual - stubbed)}, "
                                   f"lists {sorted(stubbed - actual)} it lacks")
