"""Exploration strategies, vectorised over several environments.

``MarkovExploration`` is the custom ε-greedy Markov process of seed 004 §4.4 (Fig. 13), with two
states per environment:

* POLICY: this step's action is the policy's. Next step: stay POLICY with probability ½, or switch to
  RANDOM with probability ½, drawing a fresh action uniformly over the full range [-1, 1]^n_a.
* RANDOM: the drawn action is applied. Next step: hold the same random action with probability ½, or
  revert to POLICY with probability ½.

So the chain's transition probabilities are all ½, a random action is held for a geometrically
distributed number of steps, P(k) = 2^-k (k >= 1, mean 2), and half of the steps are random in the
stationary regime. Each environment starts (and restarts at every episode reset) in POLICY, so the
first decision of an episode is already a ½/½ draw.

``GaussianExploration`` (policy + N(0, σ²), clipped) is the usual alternative for comparison.
All randomness comes from the numpy Generator passed in, whose state the trainer checkpoints.
"""

from __future__ import annotations

import numpy as np

POLICY, RANDOM = 0, 1


class Exploration:
    """Interface: ``__call__(policy_actions, rng) -> actions`` for a batch of environments, and
    ``reset(mask)`` at episode boundaries. ``state_dict``/``load_state_dict`` for exact resume."""

    name = "none"

    def __init__(self, num_envs: int, act_dim: int):
        self.num_envs, self.act_dim = num_envs, act_dim

    def __call__(self, policy_actions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.asarray(policy_actions, dtype=np.float64)

    def reset(self, mask=None) -> None:
        pass

    def state_dict(self) -> dict:
        return {}

    def load_state_dict(self, d: dict) -> None:
        pass


class MarkovExploration(Exploration):
    """Seed 004 §4.4: follow the policy or draw a uniform random action (½ each); a random action
    is held for the next step or the policy resumes (½ each)."""

    name = "markov"

    def __init__(self, num_envs: int, act_dim: int, p_random: float = 0.5, p_hold: float = 0.5,
                 low: float = -1.0, high: float = 1.0):
        super().__init__(num_envs, act_dim)
        if not (0.0 <= p_random <= 1.0 and 0.0 <= p_hold < 1.0):
            raise ValueError(f"exploration: p_random = {p_random} must be in [0, 1] and "
                             f"p_hold = {p_hold} in [0, 1)")
        self.p_random, self.p_hold, self.low, self.high = p_random, p_hold, low, high
        self.mode = np.full(num_envs, POLICY, dtype=np.int8)
        self.held = np.zeros((num_envs, act_dim))

    def __call__(self, policy_actions, rng):
        pa = np.asarray(policy_actions, dtype=np.float64).reshape(self.num_envs, self.act_dim)
        u = rng.random(self.num_envs)
        was_random = self.mode == RANDOM
        # POLICY -> RANDOM with p_random; RANDOM -> RANDOM (hold) with p_hold.
        start_random = ~was_random & (u < self.p_random)
        hold = was_random & (u < self.p_hold)
        if start_random.any():
            self.held[start_random] = rng.uniform(self.low, self.high,
                                                  (int(start_random.sum()), self.act_dim))
        random_now = start_random | hold
        self.mode = np.where(random_now, RANDOM, POLICY).astype(np.int8)
        return np.where(random_now[:, None], self.held, pa)

    def reset(self, mask=None):
        m = np.ones(self.num_envs, bool) if mask is None else np.asarray(mask, bool)
        self.mode[m] = POLICY

    def state_dict(self):
        return {"mode": self.mode.tolist(), "held": self.held.tolist()}

    def load_state_dict(self, d):
        self.mode = np.asarray(d["mode"], dtype=np.int8)
        self.held = np.asarray(d["held"], dtype=np.float64).reshape(self.num_envs, self.act_dim)


class GaussianExploration(Exploration):
    """Policy action plus N(0, sigma²) per component, clipped to [low, high]."""

    name = "gaussian"

    def __init__(self, num_envs: int, act_dim: int, sigma: float = 0.1, low: float = -1.0,
                 high: float = 1.0):
        super().__init__(num_envs, act_dim)
        if not sigma >= 0:
            raise ValueError(f"exploration: sigma = {sigma} must be >= 0")
        self.sigma, self.low, self.high = sigma, low, high

    def __call__(self, policy_actions, rng):
        pa = np.asarray(policy_actions, dtype=np.float64).reshape(self.num_envs, self.act_dim)
        return np.clip(pa + rng.normal(0.0, self.sigma, pa.shape), self.low, self.high)


def make_exploration(kind: str, num_envs: int, act_dim: int, **kw) -> Exploration:
    kinds = {"markov": MarkovExploration, "gaussian": GaussianExploration, "none": Exploration}
    if kind not in kinds:
        raise ValueError(f"exploration.kind = {kind!r}; choose one of {sorted(kinds)}")
    return kinds[kind](num_envs, act_dim, **kw)
