"""Training settings: YAML presets (``quick``, ``paper``) overridden by a user YAML file and by
``key.sub=value`` assignments from the command line. Unknown keys are errors, so a typo never
silently trains with a default."""

from __future__ import annotations

import copy
import os
import re

import yaml

PRESETS = ("quick", "paper")


class _Loader(yaml.SafeLoader):
    """YAML 1.1 reads ``1e-5`` as a string; settings want it as a number."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def _load_yaml(stream):
    return yaml.load(stream, Loader=_Loader)
_PRESET_DIR = os.path.join(os.path.dirname(__file__), "presets")


def load_preset(name: str) -> dict:
    if name not in PRESETS:
        raise ValueError(f"preset {name!r}: choose one of {', '.join(PRESETS)}")
    with open(os.path.join(_PRESET_DIR, f"{name}.yaml")) as fh:
        return _load_yaml(fh)


def _merge(base: dict, over: dict, where: str = "") -> dict:
    out = copy.deepcopy(base)
    for k, v in (over or {}).items():
        key = f"{where}{k}"
        if k not in out:
            raise ValueError(f"unknown setting {key!r}; known at this level: "
                             f"{', '.join(sorted(out))}")
        if isinstance(out[k], dict) and k != "kwargs":
            if not isinstance(v, dict):
                raise ValueError(f"setting {key!r} is a section; give {key}.<name>=value")
            out[k] = _merge(out[k], v, key + ".")
        else:
            out[k] = copy.deepcopy(v)
    return out


def parse_assignment(text: str) -> dict:
    """``a.b.c=value`` -> {"a": {"b": {"c": value}}}, the value parsed as YAML (numbers, lists...)."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise ValueError(f"override {text!r}: expected key.sub=value")
    value = _load_yaml(raw) if raw.strip() else None
    out: dict = {}
    node = out
    parts = key.strip().split(".")
    for p in parts[:-1]:
        node = node.setdefault(p, {})
    node[parts[-1]] = value
    return out


def build_config(preset: str = "quick", yaml_file: str | None = None,
                 overrides: list[str] | None = None) -> dict:
    cfg = load_preset(preset)
    if yaml_file:
        try:
            with open(yaml_file) as fh:
                user = _load_yaml(fh) or {}
        except OSError as exc:
            raise ValueError(f"--config {yaml_file}: {exc.strerror or exc}") from None
        except yaml.YAMLError as exc:
            where = getattr(exc, "problem_mark", None)
            at = f" at line {where.line + 1}, column {where.column + 1}" if where else ""
            raise ValueError(f"--config {yaml_file}: not valid YAML{at} "
                             f"({getattr(exc, 'problem', None) or type(exc).__name__})") from None
        if not isinstance(user, dict):
            raise ValueError(f"{yaml_file}: expected a mapping of settings")
        cfg = _merge(cfg, user)
    for o in overrides or []:
        cfg = _merge(cfg, parse_assignment(o))
    return cfg


def merge(base: dict, over: dict) -> dict:
    return _merge(base, over)
