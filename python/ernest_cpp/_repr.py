"""Readable reprs for the Python classes configured by their constructor (controllers, envs):
``Type(arg=value, ...)`` with the arguments that differ from the defaults, so that evaluating the
text builds an equal object (numbers print as Python's shortest round-trip repr)."""

from __future__ import annotations

import functools
import inspect

_UNSET = object()


def keeps_arguments(init):
    """Decorate ``__init__``: the arguments of the outermost constructor call (a subclass's, not
    its ``super().__init__``'s) are kept for ``arguments_repr``."""
    sig = inspect.signature(init)

    @functools.wraps(init)
    def wrapper(self, *args, **kwargs):
        if "_init_arguments" not in self.__dict__:
            bound = sig.bind(self, *args, **kwargs)
            shown = {}
            for name, value in list(bound.arguments.items())[1:]:
                p = sig.parameters[name]
                if p.kind is p.VAR_KEYWORD:
                    shown.update(value)
                elif p.kind is not p.VAR_POSITIONAL and not _same(value, p.default):
                    shown[name] = value
            self.__dict__["_init_arguments"] = shown
        init(self, *args, **kwargs)

    return wrapper


def _same(value, default) -> bool:
    if default is inspect.Parameter.empty:
        return False
    try:
        return bool(value == default) and type(value) is type(default)
    except Exception:  # arrays and the like: shown
        return False


def arguments_repr(self, *leading) -> str:
    """``Type(leading..., arg=value, ...)`` from the kept constructor arguments."""
    args = [repr(v) for v in leading]
    args += [f"{k}={v!r}" for k, v in self.__dict__.get("_init_arguments", {}).items()]
    return f"{type(self).__name__}({', '.join(args)})"
