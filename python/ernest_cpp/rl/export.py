"""TorchScript export of a trained actor for the onboard runtime.

The exported module maps a raw (physical-unit) observation to a physical action:

    x = (obs - offset) / scale                 (the normalisation of §4.2, from the run's layout)
    u = actor(x) in [-1, 1]^n_a                (§4.1)
    action = low + (u + 1) / 2 * (high - low)  (Vx in [0, 0.2] m/s, ψ̇ ±20°/s, φ̇ ±10°/s, §4.2)

Metadata (observation layout version, names, sizes, policy rate, normalisation and action ranges)
is stored in the archive as the extra file ``ernest_metadata.json`` and as module attributes. The file
is written to a temporary name, reloaded and compared with the Python actor on a set of inputs,
and only then renamed into place.
"""

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


def load_policy(path: str) -> tuple[torch.jit.ScriptModule, dict]:
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
    return mod, meta


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
    path = os.path.abspath(path)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = f"{path}.tmp-{uuid.uuid4().hex[:8]}"
    try:
        with _quiet_jit():
            torch.jit.save(module, tmp, _extra_files={METADATA_FILE: json.dumps(meta)})
        loaded, meta_back = load_policy(tmp)
        if meta_back != json.loads(json.dumps(meta)):
            raise ExportError("metadata read back differs from the metadata written")
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
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    meta["verified_max_abs_error"] = err
    return meta
