"""Pickle and ``copy.deepcopy`` support for the bound option and parameter structs.

Every ``*Options``, ``*Parameters``, ``*Scales``, ``*Weights`` and ``*Limits`` class of
``ernest_cpp._core`` is a plain C++ struct with a default constructor whose fields are all
read/write properties, so a copy is rebuilt by default-constructing it and setting each field
(nested structs recurse through the same reducer). Registered with :mod:`copyreg` on import of
the package. This is what makes the environments (``EnvOptions``, ``RoverParameters``) picklable
for multiprocessing and deep-copyable; no C++ change or pickle format to maintain.
"""

from __future__ import annotations

import copyreg
import inspect

from . import _core

_SUFFIXES = ("Options", "Parameters", "Scales", "Weights", "Limits")


def _fields(cls: type) -> list[str]:
    names: list[str] = []
    for klass in reversed(cls.__mro__):
        for name, attr in vars(klass).items():
            if isinstance(attr, property) and attr.fset is not None and name not in names:
                names.append(name)
    return names


def _rebuild(cls: type, state: dict):
    obj = cls()
    for name, value in state.items():
        setattr(obj, name, value)
    return obj


def _reduce(obj):
    cls = type(obj)
    return _rebuild, (cls, {name: getattr(obj, name) for name in _fields(cls)})


def struct_classes() -> list[type]:
    """The bound struct classes given pickle support."""
    out = []
    for _, sub in inspect.getmembers(_core, inspect.ismodule):
        for name, cls in inspect.getmembers(sub, inspect.isclass):
            if name.endswith(_SUFFIXES) and cls.__module__.startswith("ernest_cpp._core"):
                out.append(cls)
    return out


def register() -> None:
    for cls in struct_classes():
        copyreg.pickle(cls, _reduce)


register()
