"""Small environments for tests, examples and smoke runs of the training stack (no rover needed).

``ernest-toy/PointMass-v0``: a velocity-commanded point mass on a line must reach a target.
    x_{k+1} = clip(x_k + step * a_0, -2, 2), reward -|x_{k+1} - g|, 10 steps (truncation),
    x_0 and g uniform in [-1, 1]; observation (x, g) padded with zeros to ``obs_dim``; extra action
    components are ignored. With ``obs_dim=45, act_dim=3`` it has the ERNEST policy's sizes.
``info['path_progress']`` is minus the distance to the target. The optimal return has a closed form (move ``step`` towards g each step), which tests use.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from .._repr import arguments_repr, keeps_arguments


class PointMassEnv(gym.Env):
    metadata = {"render_modes": []}

    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, obs_dim: int = 2, act_dim: int = 1, horizon: int = 10, step: float = 0.2):
        if obs_dim < 2 or act_dim < 1:
            raise ValueError(f"PointMass: obs_dim = {obs_dim} must be >= 2, act_dim = {act_dim} >= 1")
        self.obs_dim, self.act_dim, self.horizon, self.step_size = obs_dim, act_dim, horizon, step
        self.observation_space = spaces.Box(-np.inf, np.inf, (obs_dim,), np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, (act_dim,), np.float32)
        self.x = self.g = 0.0
        self.t = 0

    def _obs(self):
        o = np.zeros(self.obs_dim, np.float32)
        o[0], o[1] = self.x, self.g
        return o

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.x, self.g = (float(v) for v in self.np_random.uniform(-1.0, 1.0, 2))
        self.t = 0
        return self._obs(), {}

    def step(self, action):
        a = float(np.clip(np.asarray(action, np.float64).reshape(-1)[0], -1.0, 1.0))
        self.x = float(np.clip(self.x + self.step_size * a, -2.0, 2.0))
        self.t += 1
        dist = abs(self.x - self.g)
        return self._obs(), -dist, False, self.t >= self.horizon, {"path_progress": -dist}


def optimal_return(x0: float, g: float, horizon: int = 10, step: float = 0.2) -> float:
    d = abs(x0 - g)
    return -sum(max(d - step * k, 0.0) for k in range(1, horizon + 1))


if "ernest-toy/PointMass-v0" not in gym.registry:
    gym.register("ernest-toy/PointMass-v0", entry_point=PointMassEnv)
