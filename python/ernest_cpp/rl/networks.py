"""Actor and twin critics of seed 004 §4.1 (Fig. 10).

* Actor: s -> 512 ReLU -> 512 ReLU -> n_a tanh (actions in [-1, 1]).
* Critic: [s, a] -> 512 ReLU -> [h1, a] -> 512 ReLU -> 1 linear ("the action vector is also
  reintroduced at the second layer").
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
