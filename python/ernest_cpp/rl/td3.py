"""TD3 (Fujimoto et al. 2018, the algorithm of seed 004 §4.1) with the hyperparameters of Tables 4–5.

One update (``TD3.update``) on a minibatch (s, a, r, s', terminated):

* target action  a' = clip(π'(s') + clip(ε, -c, c), -1, 1),  ε ~ N(0, σ²)   (Table 5: σ 0.05, c 0.2)
* target         y  = r + γ (1 - terminated) min(Q1'(s', a'), Q2'(s', a'))  (γ = 0.99)
* critic loss    (Q1(s, a) - y)² + (Q2(s, a) - y)²
* every d-th update (d = 2): actor loss -Q1(s, π(s)), then soft target updates θ' ← τ θ + (1-τ) θ'
  (τ = 5e-3) for actor and both critics.

Where the time goes (benchmarks/bench_learner.py): the matrix products of the 2×512 networks, then
the optimiser and the many small operations around them. Adam runs fused (one kernel over all
tensors of a network) and the soft target update is one ``torch._foreach_lerp_`` over all target
tensors. The two critics stay two ``Critic`` modules: stacking their weights into one module (with a
batched product per layer, or one product per critic) measured no faster on the CPU.
"""

from __future__ import annotations

import copy
import math
import re
from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn.functional as F

from .networks import Actor, TwinCritic


@dataclass
class TD3Config:
    gamma: float = 0.99  # Table 5
    tau: float = 5e-3  # Table 5
    policy_delay: int = 2  # Table 5
    target_noise: float = 0.05  # Table 5, std of ε
    target_noise_clip: float = 0.2  # Table 5, c
    batch_size: int = 128  # Table 4 (specialists); 512 for consolidation
    actor_lr: float = 1e-5  # Table 4 (specialists); 1e-3 for consolidation
    critic_lr: float = 1e-5
    hidden: int = 512  # §4.1

    def validate(self) -> "TD3Config":
        for name in ("gamma", "tau", "target_noise", "target_noise_clip", "actor_lr", "critic_lr",
                     "policy_delay", "batch_size", "hidden"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValueError(f"td3.{name} = {v!r} is not a number")
        checks = [("gamma", 0.0 <= self.gamma <= 1.0, "[0, 1]"),
                  ("tau", 0.0 < self.tau <= 1.0, "(0, 1]"),
                  ("policy_delay", self.policy_delay >= 1, ">= 1"),
                  ("target_noise", self.target_noise >= 0, ">= 0"),
                  ("target_noise_clip", self.target_noise_clip >= 0, ">= 0"),
                  ("batch_size", self.batch_size >= 1, ">= 1"),
                  ("actor_lr", self.actor_lr > 0, "> 0"), ("critic_lr", self.critic_lr > 0, "> 0"),
                  ("hidden", self.hidden >= 1, ">= 1")]
        for name, ok, rng in checks:
            if not ok:
                raise ValueError(f"td3.{name} = {getattr(self, name)!r} is outside {rng}")
        return self


def _as_tensor(x) -> torch.Tensor:
    if isinstance(x, torch.Tensor):
        return x.float()
    return torch.from_numpy(np.ascontiguousarray(x, dtype=np.float32))


def resolve_device(value, key: str = "learner_device") -> str:
    """The torch device a ``learner_device`` setting names: ``auto`` (``cuda`` when torch sees a GPU,
    else ``cpu``), ``cpu``, ``cuda`` or ``cuda:N``. A GPU is used when present, never required
    (``auto``); naming one that torch does not see is a ValueError."""
    if not isinstance(value, str) or not re.fullmatch(r"auto|cpu|cuda(:[0-9]+)?", value):
        raise ValueError(f"{key} = {value!r}: choose auto, cpu, cuda or cuda:N")
    if value == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if value.startswith("cuda"):
        n = torch.cuda.device_count() if torch.cuda.is_available() else 0
        index = int(value[5:]) if ":" in value else 0
        if index >= n:
            raise ValueError(f"{key} = {value!r}: torch sees {n} GPU(s) (cuda:0 to cuda:{n - 1}); "
                             f"use auto or cpu" if n else
                             f"{key} = {value!r}: torch sees no GPU; use auto or cpu")
    return value


def _adam(params, lr: float) -> torch.optim.Adam:
    """Adam with its fused kernel (CPU and CUDA); the multi-tensor one where fused is missing."""
    params = list(params)
    try:
        return torch.optim.Adam(params, lr=lr, fused=True)
    except RuntimeError:
        return torch.optim.Adam(params, lr=lr, foreach=True)


def _load_adam(opt: torch.optim.Adam, sd: dict) -> None:
    """Load Adam's state but keep this optimiser's kernel (a saved state carries its own
    ``fused``/``foreach`` flags, e.g. the per-tensor loop of checkpoints saved before Adam ran
    fused here)."""
    kernel = {k: opt.param_groups[0].get(k) for k in ("fused", "foreach")}
    sd = {"state": sd["state"], "param_groups": [{**g, **kernel} for g in sd["param_groups"]]}
    opt.load_state_dict(sd)


_CRITIC_KEYS = {f"q{i}.l{k}.{p}" for i in (1, 2) for k in (1, 2, 3) for p in ("weight", "bias")}


def _check_critic_layout(weights: dict, name: str) -> None:
    """Two ``Critic`` modules (``q1.l1.weight`` ... ``q2.l3.bias``); anything else is a ValueError."""
    keys = set(weights)
    if keys != _CRITIC_KEYS:
        raise ValueError(f"checkpoint {name}: incompatible critic layout (keys {sorted(keys)}); "
                         f"expected two critics q1/q2 with layers l1-l3 (weight, bias)")


class TD3:
    """Actor, twin critics, their targets and Adam optimisers; the update counter decides the delay."""

    def __init__(self, obs_dim: int, act_dim: int, config: TD3Config | None = None, seed: int = 0,
                 device: str = "cpu"):
        """``device``: where the networks learn (e.g. ``cuda``); initialisation and target noise
        are drawn on the CPU either way, so the draws do not depend on it."""
        self.config = (config or TD3Config()).validate()
        self.device = torch.device(device)
        self.obs_dim, self.act_dim = obs_dim, act_dim
        c = self.config
        # Initialisation and target noise are drawn from our own generator: reproducible, and
        # independent of whatever else touches torch's global RNG.
        self.gen = torch.Generator().manual_seed(int(seed))
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(seed))
            self.actor = Actor(obs_dim, act_dim, c.hidden)
            self.critic = TwinCritic(obs_dim, act_dim, c.hidden)
        self.actor.to(self.device)
        self.critic.to(self.device)
        self.actor_target = copy.deepcopy(self.actor).requires_grad_(False)
        self.critic_target = copy.deepcopy(self.critic).requires_grad_(False)
        self.actor_opt = _adam(self.actor.parameters(), c.actor_lr)
        self.critic_opt = _adam(self.critic.parameters(), c.critic_lr)
        self._online = list(self.actor.parameters()) + list(self.critic.parameters())
        self._target = list(self.actor_target.parameters()) + list(self.critic_target.parameters())
        self.updates = 0
        self.anchor: tuple[Actor, float] | None = None  # see set_anchor

    def set_anchor(self, actor: Actor | None, weight: float = 0.0) -> None:
        """Keep the actor near a frozen ``actor``: the actor loss gains
        ``weight · mean|Q1| · mean‖π(s) − π_anchor(s)‖²`` (the behaviour-cloning term of TD3+BC,
        scaled by the Q magnitude as there, towards a policy instead of the buffer's actions).
        Used when continuing a consolidated agent, so that what the pool teaches anew (e.g. a
        stronger lateral term) does not wash out skills the pool holds little of. A batch's
        optional ``anchor_mask`` (one 0/1 per row) limits the term to the rows it marks. ``None``
        or a weight of 0 removes it."""
        if actor is None or weight == 0.0:
            self.anchor = None
            return
        if not (math.isfinite(weight) and weight > 0):
            raise ValueError(f"anchor weight = {weight!r} must be finite and > 0")
        frozen = copy.deepcopy(actor).to(self.device).requires_grad_(False)
        self.anchor = (frozen, float(weight))

    @torch.no_grad()
    def act(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic policy action(s) in [-1, 1] for one observation or a batch."""
        o = _as_tensor(obs).to(self.device)
        single = o.dim() == 1
        a = self.actor(o.unsqueeze(0) if single else o)
        a = a.cpu().numpy().astype(np.float64)
        return a[0] if single else a

    def update(self, batch: dict) -> dict:
        c = self.config
        dev = self.device
        obs, act = _as_tensor(batch["obs"]).to(dev), _as_tensor(batch["act"]).to(dev)
        rew, next_obs = _as_tensor(batch["rew"]).to(dev), _as_tensor(batch["next_obs"]).to(dev)
        done = _as_tensor(batch["done"]).to(dev)
        with torch.no_grad():
            eps = (torch.randn(act.shape, generator=self.gen) * c.target_noise).to(dev)
            eps = eps.clamp(-c.target_noise_clip, c.target_noise_clip)
            next_act = (self.actor_target(next_obs) + eps).clamp(-1.0, 1.0)
            tq1, tq2 = self.critic_target(next_obs, next_act)
            target = rew + c.gamma * (1.0 - done) * torch.min(tq1, tq2)
        q1, q2 = self.critic(obs, act)
        critic_loss = F.mse_loss(q1, target) + F.mse_loss(q2, target)
        self.critic_opt.zero_grad(set_to_none=True)
        critic_loss.backward()
        self.critic_opt.step()
        self.updates += 1
        info = {"critic_loss": critic_loss.item(), "q1": q1.mean().item(),
                "q_target": target.mean().item()}
        if self.updates % c.policy_delay == 0:
            # Critic weights are constants for the actor step: skip their weight gradients.
            q1_params = list(self.critic.q1.parameters())
            for p in q1_params:
                p.requires_grad_(False)
            pi = self.actor(obs)
            q = self.critic.q1(obs, pi)
            actor_loss = -q.mean()
            if self.anchor is not None:
                ref, w = self.anchor
                with torch.no_grad():
                    ref_act, scale = ref(obs), q.abs().mean()
                dev2 = (pi - ref_act).pow(2).sum(-1)
                if "anchor_mask" in batch:  # only the rows whose behaviour is to be held
                    dev2 = dev2 * _as_tensor(batch["anchor_mask"]).to(dev)
                actor_loss = actor_loss + w * scale * dev2.mean()
            self.actor_opt.zero_grad(set_to_none=True)
            actor_loss.backward()
            for p in q1_params:
                p.requires_grad_(True)
            self.actor_opt.step()
            self._soft_update()
            info["actor_loss"] = actor_loss.item()
        return info

    @torch.no_grad()
    def _soft_update(self):
        # θ' ← θ' + τ (θ - θ') = τ θ + (1 - τ) θ', all target tensors in one call.
        torch._foreach_lerp_(self._target, self._online, self.config.tau)

    # ---------------------------------------------------------------- persistence
    def state_dict(self) -> dict:
        return {"actor": self.actor.state_dict(), "critic": self.critic.state_dict(),
                "actor_target": self.actor_target.state_dict(),
                "critic_target": self.critic_target.state_dict(),
                "actor_opt": self.actor_opt.state_dict(), "critic_opt": self.critic_opt.state_dict(),
                "gen": self.gen.get_state(), "updates": torch.tensor(self.updates),
                "dims": torch.tensor([self.obs_dim, self.act_dim, self.config.hidden])}

    def load_state_dict(self, sd: dict) -> None:
        dims = [int(v) for v in sd["dims"]]
        if dims != [self.obs_dim, self.act_dim, self.config.hidden]:
            raise ValueError(f"checkpoint networks have (obs, act, hidden) = {tuple(dims)}, this "
                             f"agent has {(self.obs_dim, self.act_dim, self.config.hidden)}")
        for name in ("critic", "critic_target"):
            _check_critic_layout(sd[name], name)
        self.actor.load_state_dict(sd["actor"])
        self.critic.load_state_dict(sd["critic"])
        self.actor_target.load_state_dict(sd["actor_target"])
        self.critic_target.load_state_dict(sd["critic_target"])
        _load_adam(self.actor_opt, sd["actor_opt"])
        _load_adam(self.critic_opt, sd["critic_opt"])
        self.gen.set_state(sd["gen"])
        self.updates = int(sd["updates"])

    def config_dict(self) -> dict:
        return asdict(self.config)
