"""TorchScript export of a trained actor for the onboard runtime.

The exported module maps a raw (physical-unit) observation to a physical action:

    x = (obs - offset) / scale                 (the normalisation of §4.2, from the run's layout)
    u = actor(x) in [-1, 1]^n_a                (§4.1)
    action = low + (u + 1) / 2 * (high - low)  (Vx in [0, 0.2] m/s, ψ̇ ±20°/s, φ̇ ±10°/s, §4.2)

Metadata (observation layout version, names, sizes, policy rate, normalisation and action ranges)
is stored in the archive as the extra file ``ernest_metadata.json`` and as module attributes. The file
is written to a temporary name, reloaded and compared with the Python actor on a set of inputs,
and only then renamed into place.

Integrity: the metadata carries ``weights_sha256`` (:func:`weights_sha256`), checked on every load
here and in the C++ runtime (cpp/runtime/policy.cpp computes the same digest), so a file whose
weights were altered is refused instead of silently giving other actions. Files exported before
the digest existed still load, with a warning; ``ernest stamp-policy FILE`` adds it.
"""

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

METADATA_FILE = "ernest_metadata.json"
HASH_KEY = "weights_sha256"


class ExportError(ValueError):
    pass


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


def metadata(lay: L.ObservationLayout, policy_rate_hz: float, extra: dict | None = None) -> dict:
    return {"format": "ernest-policy-v1", "layout_version": lay.version,
            "obs_dim": lay.obs_dim, "act_dim": lay.act_dim, "policy_rate_hz": policy_rate_hz,
            "observation_names": list(lay.names), "obs_offset": lay.offset.tolist(),
            "obs_scale": lay.scale.tolist(), "action_low": lay.action_low.tolist(),
            "action_high": lay.action_high.tolist(), **(extra or {})}


def reference_actions(actor: Actor, lay: L.ObservationLayout, obs_raw: np.ndarray) -> np.ndarray:
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
    try:
        meta = json.loads(extra[METADATA_FILE])
    except json.JSONDecodeError:
        raise ExportError(f"{path}: missing or invalid {METADATA_FILE}") from None
    if not isinstance(meta, dict):
        raise ExportError(f"{path}: {METADATA_FILE} is not a JSON object")
    return mod, meta


def load_policy(path: str) -> tuple[torch.jit.ScriptModule, dict]:
    """Load an exported policy and check its weights against the metadata's digest. A file
    without a digest (exported before it existed) loads with a warning."""
    mod, meta = _read(path)
    want = meta.get(HASH_KEY)
    if want is None:
        warnings.warn(f"{path}: no {HASH_KEY} in its metadata, its weights cannot be checked; "
                      f"add it with `ernest stamp-policy {path}`", stacklevel=2)
    elif weights_sha256(mod) != want:
        raise ExportError(f"{path}: its weights do not match the {HASH_KEY} in its metadata "
                          f"(file altered or corrupt; got {weights_sha256(mod)[:16]}..., "
                          f"expected {str(want)[:16]}...)")
    return mod, meta


def check_replaceable(path: str) -> None:
    """``path`` must be a regular file or not exist yet: a policy is written beside it and renamed
    into its place, which would put a regular file where a device (/dev/null), a pipe or a folder
    was."""
    if os.path.lexists(path) and not os.path.isfile(path):
        raise ExportError(f"cannot write {path}: not a regular file (a policy is written beside "
                          f"it and renamed into its place); give a .pt file path")


def _save_verified(module, meta: dict, path: str, check) -> None:
    """Save to a temporary sibling, reload it, run ``check(loaded, meta_back)``, rename (``path``:
    see ``check_replaceable``)."""
    check_replaceable(path)
    tmp = f"{path}.tmp-{uuid.uuid4().hex[:8]}"
    try:
        try:
            with _quiet_jit():
                torch.jit.save(module, tmp, _extra_files={METADATA_FILE: json.dumps(meta)})
        except Exception as exc:  # torch raises RuntimeError for a file it cannot write
            raise ExportError(f"cannot write {path}: {exc}") from None
        loaded, meta_back = load_policy(tmp)
        if meta_back != json.loads(json.dumps(meta)):
            raise ExportError("metadata read back differs from the metadata written")
        check(loaded)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def stamp_policy(path: str) -> dict:
    """Add ``weights_sha256`` to a policy exported without it, in place (atomically); the
    rewritten file must give bit-identical actions. Returns the metadata."""
    mod, meta = _read(path)
    digest = weights_sha256(mod)
    if HASH_KEY in meta:
        if meta[HASH_KEY] != digest:
            raise ExportError(f"{path}: already has a {HASH_KEY} and its weights do not match it "
                              f"(file altered or corrupt); not re-stamping")
        return meta
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


def export_actor(actor: Actor, lay: L.ObservationLayout, path: str,
                 policy_rate_hz: float = L.POLICY_RATE_HZ, extra_meta: dict | None = None,
                 atol: float = 1e-5) -> dict:
    """Script, save, reload and verify; returns the metadata. Raises ExportError on mismatch."""
    if actor.obs_dim != lay.obs_dim or actor.act_dim != lay.act_dim:
        raise ExportError(f"actor sizes {actor.obs_dim}/{actor.act_dim} do not match the layout "
                          f"{lay.obs_dim}/{lay.act_dim}")
    src = actor
    actor = Actor(src.obs_dim, src.act_dim, src.hidden)
    actor.load_state_dict(src.state_dict())
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
