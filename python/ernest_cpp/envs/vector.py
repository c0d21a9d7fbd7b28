"""Vector environment backed by the C++ batched stepper (threads, GIL released)."""

from __future__ import annotations

import numbers
import os

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from .._core import envs as _envs
from .core import ErnestEnv, as_actions, check_reset_options
from .core import check_seed as _check_seed


class ErnestVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` ERNEST episodes stepped in parallel in C++ with one call per batch step.

    Autoreset mode: NEXT_STEP (gymnasium's default): the step after an episode ends resets that
    environment and returns its first observation with reward 0, ``terminated`` and
    ``truncated`` False and ``info["reset"]`` True. Seeds: ``reset(seed=s)`` seeds env i with
    ``s + i`` (as gymnasium's SyncVectorEnv does), so both give the same episodes.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int, num_threads: int | None = None, scenario: str = "rockfield",
                 **kwargs):
        if num_envs < 1:
            raise ValueError(f"num_envs = {num_envs} must be >= 1")
        template = ErnestEnv(scenario, **kwargs)
        self.num_envs = num_envs
        self.single_observation_space = template.observation_space
        self.single_action_space = template.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        threads = num_threads if num_threads is not None else min(num_envs, os.cpu_count() or 1)
        self.core = _envs.VecRoverEnv(template.params, template.options, num_envs, threads)
        self.render_mode = None
        self._started = False

    def reset(self, *, seed=None, options=None):
        check_reset_options(options)
        if seed is None:
            rng = np.random.default_rng()
            seeds = [int(s) for s in rng.integers(0, 2**63 - 1, self.num_envs)]
        elif isinstance(seed, numbers.Integral):  # int, numpy integers (not bool: an Integral too)
            seeds = [_check_seed(seed, "seed", self.num_envs - 1) + i for i in range(self.num_envs)]
        else:
            try:
                seeds = [_check_seed(s, f"seed[{i}]") for i, s in enumerate(seed)]
            except TypeError:
                raise ValueError("seed must be None, an integer in [0, 2**64 - num_envs] or a "
                                 f"sequence of {self.num_envs} integers in [0, 2**64 - 1], got "
                                 f"{seed!r}") from None
            if len(seeds) != self.num_envs:
                raise ValueError(f"need {self.num_envs} seeds, got {len(seeds)}")
        obs = self.core.reset(seeds)
        self._started = True
        return obs.astype(np.float32), {}

    def step(self, actions):
        if not self._started:  # like the single env, instead of an implicit autoreset
            raise RuntimeError("ErnestVectorEnv.step: call reset() first")
        a = as_actions(actions, "actions")
        if a.size != self.num_envs * 3:
            raise ValueError(f"actions must be ({self.num_envs}, 3), got {np.shape(actions)}")
        a = a.reshape(self.num_envs, 3)
        obs, reward, terminated, truncated, info = self.core.step(a)
        return obs.astype(np.float32), reward, terminated, truncated, info


def make_vec(env_id: str, num_envs: int, num_threads: int | None = None, **kwargs):
    """A C++-backed vector env for a registered ``ernest/...`` id (its kwargs plus yours)."""
    spec = gym.spec(env_id)
    if not str(spec.entry_point).startswith("ernest_cpp.envs"):
        raise ValueError(f"{env_id} is not an ernest environment")
    merged = dict(spec.kwargs)
    merged.update(kwargs)
    return ErnestVectorEnv(num_envs, num_threads, **merged)
