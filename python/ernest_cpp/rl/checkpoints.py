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


def find_checkpoint(path: str) -> str:
    """A checkpoint folder from a run folder (its latest), a checkpoints folder, or itself."""
    if os.path.isfile(os.path.join(path, "manifest.json")):
        return path
    for base in (os.path.join(path, "checkpoints"), path):
        latest = os.path.join(base, "LATEST")
        if os.path.isfile(latest):
            with open(latest) as fh:
                name = fh.read().strip()
            return os.path.join(base, name)
    raise CorruptFileError(f"{path}: no checkpoint found (neither a checkpoint folder nor a run "
                           f"folder with checkpoints/LATEST)")


STEP_DIR = re.compile(r"^step-\d+$")


def newest_good_checkpoint(ck_root: str, exclude: str = "") -> str | None:
    """The newest ``step-N`` folder of ``ck_root`` (other than ``exclude``) that verifies."""
    try:
        names = sorted((d for d in os.listdir(ck_root) if STEP_DIR.match(d)),
                       key=lambda d: int(d[5:]), reverse=True)
    except OSError:
        return None
    for d in names:
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


def agent_from_checkpoint(ck: dict) -> TD3:
    st = ck["state"]
    agent = TD3(st["obs_dim"], st["act_dim"], TD3Config(**st["td3"]), seed=0)
    agent.load_state_dict(ck["agent"])
    return agent
