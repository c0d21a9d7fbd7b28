"""Training checkpoints on disk: finding one (a run folder, a checkpoints folder or the checkpoint
itself), verifying and reading it, naming the newest intact one when it is damaged, and rebuilding
the TD3 agent it holds. Writing is the trainer's (``Trainer.save_checkpoint``, atomic).
"""

from __future__ import annotations

import json
import os
import re

import torch

from .replay import ReplayBuffer
from .storage import CorruptFileError, read_manifest
from .td3 import TD3, TD3Config

STEP_DIR = re.compile(r"^step-\d+$")


def find_checkpoint(path: str) -> str:
    """A checkpoint folder from a run folder (its latest), a checkpoints folder, or itself.

    The latest is the one ``LATEST`` names (a ``step-N`` folder, or a consolidation's
    ``consolidated``); when ``LATEST`` is missing, empty, or does not name such a folder that
    exists, it is the newest ``step-N`` folder that verifies, or else ``consolidated``."""
    if os.path.isfile(os.path.join(path, "manifest.json")):
        return path
    for base in (os.path.join(path, "checkpoints"), path):
        latest = os.path.join(base, "LATEST")
        name = ""
        if os.path.isfile(latest):
            try:
                with open(latest, errors="replace") as fh:
                    name = fh.read(256).strip()
            except OSError:
                name = ""
            # a step-N folder, or a consolidation's final agent (``consolidated``) beside LATEST
            if (STEP_DIR.match(name) or name == "consolidated") and os.path.isdir(
                    os.path.join(base, name)):
                return os.path.join(base, name)
        good = newest_good_checkpoint(base)
        if good is not None:
            return good
        steps = _step_dirs(base)
        if not steps and os.path.isdir(os.path.join(base, "consolidated")):
            return os.path.join(base, "consolidated")  # a consolidation's final agent
        if steps:  # step-N folders, none of them intact: say why the newest is not
            try:
                read_manifest(os.path.join(base, steps[0]), "checkpoint", verify=True)
            except CorruptFileError as exc:
                raise CorruptFileError(f"{path}: no intact checkpoint among the {len(steps)} "
                                       f"step-N folders of {base} (the newest: {exc})") from None
        if os.path.isfile(latest):
            raise CorruptFileError(f"{latest}: names {name[:80]!r}, not a step-N checkpoint folder "
                                   f"beside it, and there is no intact one to fall back on")
    raise CorruptFileError(f"{path}: no checkpoint found (neither a checkpoint folder nor a run "
                           f"folder with checkpoints/LATEST or an intact checkpoints/step-N)")


def _step_dirs(ck_root: str) -> list[str]:
    """The ``step-N`` folder names of ``ck_root``, newest first (none if it cannot be read)."""
    try:
        return sorted((d for d in os.listdir(ck_root) if STEP_DIR.match(d) and
                       os.path.isdir(os.path.join(ck_root, d))),
                      key=lambda d: int(d[5:]), reverse=True)
    except OSError:
        return []


def newest_good_checkpoint(ck_root: str, exclude: str = "") -> str | None:
    """The newest ``step-N`` folder of ``ck_root`` (other than ``exclude``) that verifies."""
    for d in _step_dirs(ck_root):
        p = os.path.join(ck_root, d)
        if os.path.abspath(p) == os.path.abspath(exclude):
            continue
        try:
            read_manifest(p, "checkpoint", verify=True)
            return p
        except CorruptFileError:
            continue
    return None


def load_checkpoint(path: str, with_buffer: bool = True) -> dict:
    """Verify and read a checkpoint: {'state': dict, 'agent': state_dict, 'buffer': ReplayBuffer}.
    If it is damaged, the error names the newest intact checkpoint beside it and how to use it."""
    ck = find_checkpoint(path)
    try:
        return _read_checkpoint(ck, with_buffer)
    except CorruptFileError as exc:
        ck_root = os.path.dirname(os.path.abspath(ck))
        good = newest_good_checkpoint(ck_root, exclude=ck)
        if good is None:
            raise
        raise CorruptFileError(
            f"{exc}. The newest intact checkpoint is {good}: resume from it with "
            f"`echo {os.path.basename(good)} > {os.path.join(ck_root, 'LATEST')}`, or pass it "
            f"as the checkpoint folder") from None


def _read_checkpoint(ck: str, with_buffer: bool) -> dict:
    read_manifest(ck, "checkpoint", verify=True)
    try:
        with open(os.path.join(ck, "state.json")) as fh:
            state = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise CorruptFileError(f"{ck}/state.json: unreadable ({exc})") from None
    try:
        agent_sd = torch.load(os.path.join(ck, "agent.pt"), weights_only=True,
                              map_location="cpu")  # a GPU learner's checkpoint loads anywhere
    except Exception as exc:  # torch raises several types for damaged zip archives
        raise CorruptFileError(f"{ck}/agent.pt: unreadable network file ({exc})") from None
    out = {"path": ck, "state": state, "agent": agent_sd}
    if with_buffer and os.path.isdir(os.path.join(ck, "buffer")):
        out["buffer"] = ReplayBuffer.load(os.path.join(ck, "buffer"), verify=False)
    return out


# Settings a resumed run may change without ``override``: how long it runs, what it logs, how many
# checkpoints it keeps, where its Ray cluster is, and the consolidation's settings (which training
# does not read). None of them changes what the run learns.
RESUME_FREE = ("total_steps", "log", "checkpoint.keep", "ray.address", "ray.object_store_mb",
               "consolidate")
_UNSET = object()


def saved_settings(saved: dict) -> dict:
    """A run's saved settings completed with those newer than the run (ray, learner_device,
    demos): the quick preset's values; a run from before learner_device learned on the CPU."""
    from .config import load_preset

    cfg = dict(saved)
    newer = {k: v for k, v in load_preset("quick").items() if k not in cfg}
    if "learner_device" in newer:
        newer["learner_device"] = "cpu"
    cfg.update(newer)
    return cfg


def config_changes(saved: dict, cfg: dict) -> list[str]:
    """``key: saved -> new`` for every setting of ``cfg`` that differs from a run's ``saved``
    ones, other than those in RESUME_FREE. A preset setting newer than the run (absent from
    ``saved``, or from both) counts with its quick-preset value (see saved_settings)."""
    from .config import load_preset

    def free(key: str) -> bool:
        return any(key == f or key.startswith(f + ".") for f in RESUME_FREE)

    def show(v) -> str:
        return "(not set)" if v is _UNSET else json.dumps(v, default=str)

    out: list[str] = []

    def walk(a, b, ref, prefix: str) -> None:
        for k in sorted(set(a) | set(b), key=str):
            key = f"{prefix}{k}"
            if free(key):
                continue
            va, vb = a.get(k, _UNSET), b.get(k, _UNSET)
            if isinstance(ref, dict) and k in ref:  # a setting newer than the run: its default
                va = ref[k] if va is _UNSET else va
                vb = ref[k] if vb is _UNSET else vb
            if isinstance(va, dict) and isinstance(vb, dict):
                walk(va, vb, ref.get(k) if isinstance(ref, dict) else None, key + ".")
            elif va != vb:
                out.append(f"{key}: {show(va)} -> {show(vb)}")

    walk(saved_settings(saved), cfg, load_preset("quick"), "")
    return out


def check_resume_config(saved: dict, cfg: dict, where: str, override: bool = False) -> list[str]:
    """Refuse (ValueError) to resume the run saved in ``where`` with settings other than its own,
    unless ``override``; returns the changes (those RESUME_FREE leaves out)."""
    changes = config_changes(saved, cfg)
    if changes and not override:
        raise ValueError(
            f"{where}: these settings differ from the ones the run was trained with: "
            f"{'; '.join(changes)}. A resumed run continues with its saved settings (only "
            f"{', '.join(RESUME_FREE)} may change); pass --override-config (Trainer: "
            f"override_config=True) to continue it with the new ones, or train a new run in "
            f"another --run-dir")
    return changes


def agent_from_checkpoint(ck: dict) -> TD3:
    st = ck["state"]
    agent = TD3(st["obs_dim"], st["act_dim"], TD3Config(**st["td3"]), seed=0)
    agent.load_state_dict(ck["agent"])
    return agent
