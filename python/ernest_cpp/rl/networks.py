"""Actor and twin critics of seed 004 §4.1 (Fig. 10).

* Actor: s -> 512 ReLU -> 512 ReLU -> n_a tanh (actions in [-1, 1]).
* Critic: [s, a] -> 512 ReLU -> [h1, a] -> 512 ReLU -> 1 linear ("the action vector is also
  reintroduced at the second layer").

``TwinCritic`` holds TD3's two critics as two ``Critic`` modules; ``FusedTwinCritic`` is the same pair
with each layer's two weight matrices stacked in one tensor, so that the optimiser and the soft
target update see 6 tensors instead of 12. It computes the same function as the ``TwinCritic`` it is
made from (to float rounding) and is what ``td3.TD3`` trains (benchmarks/bench_learner.py measures
what it saves).
"""

from __future__ import annotations

import torch
from torch import nn


class Actor(nn.Module):
    def __init__(self, obs_dim: int, act_dim: int, hidden: int = 512):
        super().__init__()
        self.obs_dim, self.act_dim, self.hidden = obs_dim, act_dim, hidden
        self.l1 = nn.Linear(obs_dim, hidden)
        self.l2 = nn.Linear(hidden, hidden)
        self.l3 = nn.Linear(hidden, act_dim)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        h = torch.relu(self.l1(obs))
        h = torch.relu(self.l2(h))
        return torch.tanh(self.l3(h))


class Critic(nn.Module):
    def __init__(self, obs_dim: int, act_dim: int, hidden: int = 512):
        super().__init__()
        self.l1 = nn.Linear(obs_dim + act_dim, hidden)
        self.l2 = nn.Linear(hidden + act_dim, hidden)  # action re-injected at layer 2 (§4.1)
        self.l3 = nn.Linear(hidden, 1)

    def forward(self, obs: torch.Tensor, act: torch.Tensor) -> torch.Tensor:
        h = torch.relu(self.l1(torch.cat([obs, act], dim=-1)))
        h = torch.relu(self.l2(torch.cat([h, act], dim=-1)))
        return self.l3(h).squeeze(-1)


class TwinCritic(nn.Module):
    """The two independent critics of TD3 (clipped double-Q)."""

    def __init__(self, obs_dim: int, act_dim: int, hidden: int = 512):
        super().__init__()
        self.q1 = Critic(obs_dim, act_dim, hidden)
        self.q2 = Critic(obs_dim, act_dim, hidden)

    def forward(self, obs: torch.Tensor, act: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.q1(obs, act), self.q2(obs, act)


class FusedTwinCritic(nn.Module):
    """Both critics in one module: layer k of critic i is ``x @ w{k}[i] + b{k}[i]``.

    Parameters (i = 0 for Q1, 1 for Q2; ``n = obs_dim + act_dim``, ``h = hidden``):
    ``w1`` [2, n, h], ``b1`` [2, 1, h], ``w2`` [2, h + act_dim, h] (the last ``act_dim`` rows take
    the re-injected action), ``b2`` [2, 1, h], ``w3`` [2, h, 1], ``b3`` [2, 1, 1]; ``w{k}[i]`` is
    ``Critic.l{k}.weight`` transposed. A new one is initialised exactly like ``TwinCritic`` (same
    draws from torch's generator, in the same order).
    """

    NAMES = ("w1", "b1", "w2", "b2", "w3", "b3")

    def __init__(self, obs_dim: int, act_dim: int, hidden: int = 512):
        super().__init__()
        self.obs_dim, self.act_dim, self.hidden = obs_dim, act_dim, hidden
        sd = self.stack_twin_state_dict(TwinCritic(obs_dim, act_dim, hidden).state_dict())
        for name in self.NAMES:
            self.register_parameter(name, nn.Parameter(sd[name]))

    @staticmethod
    def stack_twin_state_dict(twin: dict) -> dict:
        """A ``TwinCritic`` state dict (``q1.l1.weight``, ...) in this module's layout. It also
        converts tensors shaped like the parameters (Adam's moments) the same way."""
        out = {}
        for k in (1, 2, 3):
            out[f"w{k}"] = torch.stack([twin[f"q{i}.l{k}.weight"].t() for i in (1, 2)]).contiguous()
            out[f"b{k}"] = torch.stack([twin[f"q{i}.l{k}.bias"].unsqueeze(0) for i in (1, 2)])
        return out

    def twin_state_dict(self) -> dict:
        """The weights as a ``TwinCritic`` state dict (two separate ``Critic`` modules)."""
        out = {}
        for i in (1, 2):
            for k in (1, 2, 3):
                out[f"q{i}.l{k}.weight"] = getattr(self, f"w{k}")[i - 1].detach().t().contiguous()
                out[f"q{i}.l{k}.bias"] = getattr(self, f"b{k}")[i - 1, 0].detach().clone()
        return out

    def forward(self, obs: torch.Tensor, act: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = torch.cat([obs, act], dim=-1)
        # One matrix product per critic and layer on views of the stacked weights (``unbind``: one
        # gradient tensor per parameter on the way back). A batched product over both critics
        # (baddbmm) was measured slower at minibatch 512 (benchmarks/bench_learner.py --ablation).
        q1, q2 = (self._q(x, act, *w) for w in zip(*(getattr(self, n).unbind(0)
                                                     for n in self.NAMES)))
        return q1, q2

    @staticmethod
    def _q(x, act, w1, b1, w2, b2, w3, b3) -> torch.Tensor:
        h = torch.relu(torch.addmm(b1, x, w1))
        h = torch.relu(torch.addmm(b2, torch.cat([h, act], dim=-1), w2))
        return torch.addmm(b3, h, w3).squeeze(-1)

    def q1(self, obs: torch.Tensor, act: torch.Tensor) -> torch.Tensor:
        """Q1 alone (the actor's objective)."""
        return self._q(torch.cat([obs, act], dim=-1), act, *(getattr(self, n)[0] for n in self.NAMES))
