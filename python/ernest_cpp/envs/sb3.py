"""Stable-Baselines3 ``VecEnv`` over the C++ batched environments.

``ErnestSB3VecEnv("ernest/Slope-v0", num_envs=8)`` steps all simulations in one C++ call (threads,
GIL released) and presents SB3's conventions, so its algorithms train on it unmodified:

- same-step autoreset: when an episode ends, ``step_wait`` returns the next episode's first
  observation, the last one in ``infos[i]["terminal_observation"]`` and
  ``infos[i]["TimeLimit.truncated"]`` for a time-limit end (SB3 bootstraps through it);
- seeds: ``seed(s)`` then ``reset()`` starts env i from seed s + i, like SB3's DummyVecEnv of the
  single env, and later episodes follow each env's own seed sequence, so both give the same
  transitions (tests/python/test_sb3.py);
- ``get_attr``/``env_method`` reach each C++ episode core (``RoverEnv``: ``metrics``,
  ``episode_seed``...).

Needs the ``sb3`` extra (``pip install ernest-cpp[sb3]``).
"""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from .._repr import arguments_repr, keeps_arguments
from .core import check_reset_options
from .vector import make_vec


class ErnestSB3VecEnv(VecEnv):
    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, env_id: str = "ernest/RockField-v0", num_envs: int = 4,
                 num_threads: int | None = None, **kwargs):
        self.venv = make_vec(env_id, num_envs, num_threads, **kwargs)
        self.core = self.venv.core
        super().__init__(num_envs, self.venv.single_observation_space,
                         self.venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self):
        rng = np.random.default_rng()
        seeds = [int(s) if s is not None else int(rng.integers(0, 2**63 - 1)) for s in self._seeds]
        for opt in self._options:
            check_reset_options(opt)  # refuses unknown keys (the envs take none)
        obs, _ = self.venv.reset(seed=seeds)
        self.reset_infos = [{"episode_seed": s} for s in seeds]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, -1)

    def step_wait(self):
        if self._actions is None:
            raise RuntimeError("ErnestSB3VecEnv.step_wait: call step_async first")
        obs, reward, term, trunc, info = self.venv.step(self._actions)
        self._actions = None
        obs = np.array(obs, dtype=np.float32)
        dones = np.logical_or(term, trunc)
        infos: list[dict] = []
        for i in range(self.num_envs):
            d = {"progress": float(info["progress"][i]),
                 "lateral_deviation": float(info["lateral_deviation"][i]),
                 "diverged": bool(info["diverged"][i])}
            if dones[i]:
                env = self.core.env(i)
                d["terminal_observation"] = obs[i].copy()
                d["TimeLimit.truncated"] = bool(trunc[i] and not term[i])
                d["episode_metrics"] = env.metrics
                obs[i] = np.asarray(env.reset_next(), dtype=np.float32)  # same-step autoreset
            infos.append(d)
        return obs, np.asarray(reward, dtype=np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    # -- per-env access (the C++ RoverEnv of each simulation)
    def get_attr(self, attr_name: str, indices=None) -> list:
        if attr_name == "render_mode":
            return [None for _ in self._get_indices(indices)]
        return [getattr(self.core.env(i), attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value, indices=None) -> None:
        for i in self._get_indices(indices):
            setattr(self.core.env(i), attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list:
        return [getattr(self.core.env(i), method_name)(*method_args, **method_kwargs)
                for i in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]
