"""TorchScript export of a trained actor for the onboard runtime.

The exported module maps a raw (physical-unit) observation to a physical action:

    x = (obs - offset) / scale                 (the normalisation of §4.2, from the run's layout)
    u = actor(x) in [-1, 1]^n_a                (§4.1)
    action = low + (u + 1) / 2 * (high - low)  (Vx in [0, 0.2] m/s, ψ̇ ±20°/s, φ̇ ±10°/s, §4.2)

Metadata (observation layout version, names, sizes, policy rate, normalisation and action ranges)
is stored in the archive as the extra file ``ernest_metadata.json`` and as module attributes. The file
is written to a temporary name, reloaded and compared with the Python actor on a set of inputs,
and only then renamed into place.

Integrity: the metadata carries ``policy_sha256``, the digest of the whole archive (code,
constants, weights and metadata; policy_file.py), and ``weights_sha256`` (:func:`weights_sha256`),
both checked on every load here and in the C++ runtime, so a file whose ``forward()``, weights or
metadata were altered is refused instead of silently giving other actions. Files written before a
digest existed still load, with a warning; ``ernest stamp-policy FILE`` adds the missing ones.
The metadata itself must pass the runtime's checks (policy_file.check_generic on every load,
check_runtime in ``ernest evaluate``).
"""

import copy
import hashlib
import json
import os
import uuid
import warnings

import numpy as np
import torch
from torch import nn

from . import layout as L
from .networks import Actor
from .policy_file import (METADATA_FILE, PLACEHOLDER, POLICY_KEY, ExportError, check_generic,
                          parse_metadata, policy_sha256)
from .policy_file import WEIGHTS_KEY as HASH_KEY


class _quiet_jit:
    """TorchScript is deprecated upstream (torch 2.13 warns) but it is what the C++ runtime loads
    through libtorch; silence only those deprecation warnings."""

    def __enter__(self):
        self._ctx = warnings.catch_warnings()
        self._ctx.__enter__()
        warnings.filterwarnings("ignore", category=DeprecationWarning, message=r".*torch\.jit.*")

    def __exit__(self, *exc):
        self._ctx.__exit__(*exc)
        return False


class ExportedPolicy(nn.Module):
    obs_dim: int
    act_dim: int
    policy_rate_hz: float
    layout_version: str

    def __init__(self, actor: Actor, lay: L.ObservationLayout, policy_rate_hz: float):
        super().__init__()
        self.actor = actor
        self.register_buffer("obs_offset", torch.tensor(lay.offset, dtype=torch.float32))
        self.register_buffer("obs_scale", torch.tensor(lay.scale, dtype=torch.float32))
        self.register_buffer("act_low", torch.tensor(lay.action_low, dtype=torch.float32))
        self.register_buffer("act_high", torch.tensor(lay.action_high, dtype=torch.float32))
        self.obs_dim, self.act_dim = lay.obs_dim, lay.act_dim
        self.policy_rate_hz, self.layout_version = float(policy_rate_hz), lay.version

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        x = (obs - self.obs_offset) / self.obs_scale
        u = self.actor(x)
        return self.act_low + (u + 1.0) * 0.5 * (self.act_high - self.act_low)


class SequentialActor(nn.Module):
    """An actor given as a module mapping the normalised observation to actions in [-1, 1] (e.g.
    Stable-Baselines3 TD3's ``actor.mu``: Linear/ReLU layers ending in tanh), with the sizes
    ``export_actor`` checks against the layout."""

    def __init__(self, net: nn.Module, obs_dim: int, act_dim: int):
        super().__init__()
        self.net, self.obs_dim, self.act_dim = net, int(obs_dim), int(act_dim)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.net(obs)


def actor_from_sb3(model) -> SequentialActor:
    """The deterministic actor of a Stable-Baselines3 TD3 model (an object or the path of its
    ``.zip``), for ``export_actor``. The model must have been trained on an ernest env directly
    (45 normalised observation values, 3 actions in [-1, 1]; no VecNormalize, whose statistics
    live outside the zip): then its ``actor.mu`` is the whole policy, as for our own actor.
    Raises ExportError otherwise."""
    if isinstance(model, (str, os.PathLike)):
        try:
            from stable_baselines3 import TD3
        except ImportError:
            raise ExportError("reading a Stable-Baselines3 model needs stable-baselines3 "
                              "(pip install ernest-cpp[sb3])") from None
        try:
            model = TD3.load(os.fspath(model), device="cpu")
        except Exception as exc:  # a zip of another algorithm, or not a model at all
            raise ExportError(f"{os.fspath(model)}: not a Stable-Baselines3 TD3 model "
                              f"({type(exc).__name__}: {exc})") from None
    obs_space, act_space = model.observation_space, model.action_space
    if len(getattr(obs_space, "shape", ())) != 1 or len(getattr(act_space, "shape", ())) != 1:
        raise ExportError(f"the model's spaces {obs_space} / {act_space} are not flat Boxes")
    low, high = np.asarray(act_space.low), np.asarray(act_space.high)
    if not (np.allclose(low, -1.0) and np.allclose(high, 1.0)):
        raise ExportError(f"the model's action space is [{low.tolist()}, {high.tolist()}]; the "
                          "ernest environments' is [-1, 1] (the export scales it to commands)")
    actor = getattr(getattr(model, "policy", None), "actor", None)
    if actor is None or not hasattr(actor, "mu"):
        raise ExportError(f"{type(model).__name__} has no deterministic actor (policy.actor.mu): "
                          "only TD3 (and DDPG) models can be exported")
    if not isinstance(actor.features_extractor, nn.Flatten) and \
            type(actor.features_extractor).__name__ != "FlattenExtractor":
        raise ExportError(f"the model's features extractor {type(actor.features_extractor).__name__} "
                          "is not the plain flatten of MlpPolicy")
    net = copy.deepcopy(actor.mu).to("cpu").float().eval()
    return SequentialActor(net, obs_space.shape[0], act_space.shape[0])


def metadata(lay: L.ObservationLayout, policy_rate_hz: float, extra: dict | None = None) -> dict:
    return {"format": "ernest-policy-v1", "layout_version": lay.version,
            "obs_dim": lay.obs_dim, "act_dim": lay.act_dim, "policy_rate_hz": policy_rate_hz,
            "observation_names": list(lay.names), "obs_offset": lay.offset.tolist(),
            "obs_scale": lay.scale.tolist(), "action_low": lay.action_low.tolist(),
            "action_high": lay.action_high.tolist(), **(extra or {})}


def reference_actions(actor: nn.Module, lay: L.ObservationLayout, obs_raw: np.ndarray) -> np.ndarray:
    """The Python path: normalise in numpy, run the actor, scale the action in numpy."""
    x = (obs_raw.astype(np.float64) - lay.offset) / lay.scale
    with torch.no_grad():
        u = actor(torch.from_numpy(x.astype(np.float32))).numpy().astype(np.float64)
    return lay.action_low + (u + 1.0) * 0.5 * (lay.action_high - lay.action_low)


def probe_inputs(lay: L.ObservationLayout, n: int = 256, seed: int = 0) -> np.ndarray:
    """Raw observations spanning ±1.5 normalised units around the offset, plus the offset itself."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.5, 1.5, (n, lay.obs_dim))
    x[0] = 0.0
    return (lay.offset + x * lay.scale).astype(np.float32)


def weights_sha256(module: nn.Module) -> str:
    """SHA-256 of every parameter and buffer of ``module``, in name order. Per tensor: the dotted
    name, a newline, the shape as comma-separated integers, a newline, then the values as
    little-endian float32. cpp/runtime/policy.cpp (weights_sha256) hashes the same bytes."""
    tensors = dict(module.named_parameters())
    tensors.update(dict(module.named_buffers()))
    h = hashlib.sha256()
    for name in sorted(tensors):
        t = tensors[name].detach().to(torch.float32).contiguous().cpu()
        h.update(f"{name}\n{','.join(str(d) for d in t.shape)}\n".encode())
        h.update(t.numpy().astype("<f4", copy=False).tobytes())
    return h.hexdigest()


def _read(path: str) -> tuple[torch.jit.ScriptModule, dict]:
    extra = {METADATA_FILE: ""}
    try:
        with _quiet_jit():
            mod = torch.jit.load(path, _extra_files=extra)
    except Exception as exc:
        raise ExportError(f"{path}: not a loadable TorchScript policy ({exc})") from None
    if not extra[METADATA_FILE]:
        raise ExportError(f"{path}: the archive has no {METADATA_FILE} (export it with "
                          "`ernest export`)")
    return mod, parse_metadata(extra[METADATA_FILE], path)


def load_policy(path: str, check=check_generic) -> tuple[torch.jit.ScriptModule, dict]:
    """Load an exported policy: its metadata must pass ``check`` (policy_file.check_generic, or
    check_runtime for the runtime's own expectations), its weights must match ``weights_sha256``
    and its archive ``policy_sha256``. A digest the file lacks (written before it existed) is a
    warning."""
    mod, meta = _read(path)
    check(meta, path)
    want = meta.get(HASH_KEY)
    if want is None:
        warnings.warn(f"{path}: no {HASH_KEY} in its metadata, its weights cannot be checked; "
                      f"add it with `ernest stamp-policy {path}`", stacklevel=2)
    elif weights_sha256(mod) != want:
        raise ExportError(f"{path}: its weights do not match the {HASH_KEY} in its metadata "
                          f"(file altered or corrupt; got {weights_sha256(mod)[:16]}..., "
                          f"expected {str(want)[:16]}...)")
    want = meta.get(POLICY_KEY)
    if want is None:
        warnings.warn(f"{path}: no {POLICY_KEY} in its metadata, its code and metadata cannot be "
                      f"checked; add it with `ernest stamp-policy {path}`", stacklevel=2)
    elif policy_sha256(path, want) != want:
        raise ExportError(f"{path}: its archive (code, constants, weights or metadata) does not "
                          f"match the {POLICY_KEY} in its metadata (file altered or corrupt)")
    return mod, meta


def check_replaceable(path: str) -> None:
    """``path`` must be a regular file or not exist yet: a policy is written beside it and renamed
    into its place, which would put a regular file where a device (/dev/null), a pipe or a folder
    was."""
    if os.path.lexists(path) and not os.path.isfile(path):
        raise ExportError(f"cannot write {path}: not a regular file (a policy is written beside "
                          f"it and renamed into its place); give a .pt file path")


def save_stamped(module, meta_text: str, path: str) -> None:
    """torch.jit.save with ``policy_sha256`` filled in: ``meta_text`` holds the placeholder
    (64 "0") as that field's value; the archive is written with it, digested, and written again
    with the digest (saving one module twice gives the same records)."""
    with _quiet_jit():
        torch.jit.save(module, path, _extra_files={METADATA_FILE: meta_text})
        digest = policy_sha256(path, PLACEHOLDER)
        torch.jit.save(module, path,
                       _extra_files={METADATA_FILE: meta_text.replace(PLACEHOLDER, digest)})


def _save_verified(module, meta: dict, path: str, check) -> None:
    """Save to a temporary sibling with its digest (``meta[POLICY_KEY]`` is set), reload it, run
    ``check(loaded)``, rename (``path``: see ``check_replaceable``)."""
    check_replaceable(path)
    tmp = f"{path}.tmp-{uuid.uuid4().hex[:8]}"
    try:
        meta[POLICY_KEY] = PLACEHOLDER
        try:
            save_stamped(module, json.dumps(meta), tmp)
        except ExportError:
            raise
        except Exception as exc:  # torch raises RuntimeError for a file it cannot write
            raise ExportError(f"cannot write {path}: {exc}") from None
        loaded, meta_back = load_policy(tmp)
        meta[POLICY_KEY] = meta_back[POLICY_KEY]
        if meta_back != json.loads(json.dumps(meta)):
            raise ExportError("metadata read back differs from the metadata written")
        check(loaded)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def stamp_policy(path: str) -> dict:
    """Add the digests a policy lacks (``weights_sha256``, ``policy_sha256``), in place
    (atomically); the rewritten file must give bit-identical actions. A digest the file has must
    match it (else ExportError: an altered file is never blessed). Returns the metadata."""
    mod, meta = _read(path)
    check_generic(meta, path)
    digest = weights_sha256(mod)
    if HASH_KEY in meta and meta[HASH_KEY] != digest:
        raise ExportError(f"{path}: already has a {HASH_KEY} and its weights do not match it "
                          f"(file altered or corrupt); not re-stamping")
    if POLICY_KEY in meta:
        if policy_sha256(path, meta[POLICY_KEY]) != meta[POLICY_KEY]:
            raise ExportError(f"{path}: already has a {POLICY_KEY} and its archive does not match "
                              f"it (file altered or corrupt); not re-stamping")
        if HASH_KEY in meta:
            return meta
        del meta[POLICY_KEY]  # re-stamped below with the weights digest added
    meta[HASH_KEY] = digest
    obs = torch.zeros(1, int(meta.get("obs_dim", 45)))
    obs = torch.cat([obs, torch.from_numpy(np.random.default_rng(0).normal(
        size=(16, obs.shape[1])).astype(np.float32))])
    with torch.no_grad():
        want = mod(obs)

    def same(loaded):
        with torch.no_grad():
            if not torch.equal(loaded(obs), want):
                raise ExportError("the re-saved policy gives different actions")

    _save_verified(mod, meta, os.path.abspath(path), same)
    return meta


def export_actor(actor: nn.Module, lay: L.ObservationLayout, path: str,
                 policy_rate_hz: float = L.POLICY_RATE_HZ, extra_meta: dict | None = None,
                 atol: float = 1e-5) -> dict:
    """Script, save, reload and verify; returns the metadata. ``actor``: our ``Actor`` or any
    module with ``obs_dim``/``act_dim`` mapping normalised observations to [-1, 1] actions
    (``SequentialActor``, ``actor_from_sb3``). Raises ExportError on mismatch or on a policy rate
    that is not a finite number > 0."""
    if not (isinstance(policy_rate_hz, (int, float)) and np.isfinite(policy_rate_hz)
            and policy_rate_hz > 0):
        raise ExportError(f"policy_rate_hz = {policy_rate_hz!r} must be a finite number > 0 [Hz]")
    if actor.obs_dim != lay.obs_dim or actor.act_dim != lay.act_dim:
        raise ExportError(f"actor sizes {actor.obs_dim}/{actor.act_dim} do not match the layout "
                          f"{lay.obs_dim}/{lay.act_dim}")
    if isinstance(actor, Actor):
        src = actor
        actor = Actor(src.obs_dim, src.act_dim, src.hidden)
        actor.load_state_dict(src.state_dict())
    else:  # the caller's module stays untouched (and on its device)
        actor = copy.deepcopy(actor).to("cpu")
    actor.eval()
    meta = metadata(lay, policy_rate_hz, extra_meta)
    with _quiet_jit():
        module = torch.jit.script(ExportedPolicy(actor, lay, policy_rate_hz))
    meta[HASH_KEY] = weights_sha256(module)
    path = os.path.abspath(path)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    err = float("nan")

    def check(loaded):
        nonlocal err
        obs = probe_inputs(lay)
        with torch.no_grad():
            got = loaded(torch.from_numpy(obs)).numpy().astype(np.float64)
            single = loaded(torch.from_numpy(obs[1])).numpy().astype(np.float64)
        want = reference_actions(actor, lay, obs)
        err = float(np.max(np.abs(got - want)))
        span = lay.action_high - lay.action_low
        if got.shape != want.shape or not err <= atol * float(np.max(span)):
            raise ExportError(f"reloaded policy differs from the Python actor by {err:.3g} "
                              f"(tolerance {atol} of the action range)")
        if not np.max(np.abs(single - got[1])) <= atol * float(np.max(span)):
            raise ExportError("single-observation and batched outputs differ")

    _save_verified(module, meta, path, check)
    meta["verified_max_abs_error"] = err
    return meta
