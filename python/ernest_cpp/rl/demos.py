"""Experience from scripted controllers placed in the replay buffer before training.

TD3 is off-policy (seed 004 §4.1): any behaviour policy's transitions are valid training data.
A scripted demonstrator that gets over an obstacle (``envs.climbing``) puts transitions into the
buffer that random and ε-greedy exploration would take very long to find; the learner then trains
on them with the same TD3 updates and replay noise as on its own experience.

Settings (``demos`` section of a preset)::

    demos:
      controller: null   # null (none) | step_climb | bickler_cross | crawling | passive
      episodes: 0        # demonstrator episodes collected before the first update
      seed: 2000000      # episode k uses seed + k
      env: null          # env id of the episodes (null: the training env's)
      kwargs: {}         # env kwargs for the demonstrator's episodes, over env.kwargs
"""

from __future__ import annotations

import time

import numpy as np

CONTROLLERS = ("step_climb", "bickler_cross", "crawling", "passive")


def make_controller(name: str):
    """(controller, passive) for a demonstrator name."""
    from ..envs import baselines, climbing

    if name == "step_climb":
        return climbing.StepClimbController(), False
    if name == "bickler_cross":
        return climbing.BicklerCrossController(), False
    if name == "crawling":
        return baselines.CrawlingGaitController(), False
    if name == "passive":
        return baselines.PassiveController(), True
    raise ValueError(f"demos.controller = {name!r}; choose null or one of {', '.join(CONTROLLERS)}")


def check_settings(cfg: dict) -> tuple[str | None, int]:
    """(controller name or None, episodes), validated."""
    d = cfg.get("demos") or {}
    name, episodes = d.get("controller"), d.get("episodes", 0)
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 0:
        raise ValueError(f"demos.episodes = {episodes!r} must be a whole number >= 0")
    if name is None or episodes == 0:
        return None, 0
    make_controller(name)  # a bad name fails here, before any simulation
    return name, episodes


def collect(env_id: str, cfg: dict, low: np.ndarray, high: np.ndarray, log=print):
    """Run the configured demonstrator; returns (obs, act, rew, next_obs, terminated) arrays with
    actions mapped back into the learner's [-1, 1] space, and per-episode returns."""
    from .envs_util import make_env

    name, episodes = check_settings(cfg)
    if name is None:
        return None, []
    d = cfg["demos"]
    ctrl, passive = make_controller(name)
    kwargs = {} if d.get("env") else dict(cfg["env"].get("kwargs") or {})
    kwargs.update(d.get("kwargs") or {})
    if passive:
        kwargs["passive"] = True
    env = make_env(d.get("env") or env_id, kwargs)
    rows: dict[str, list] = {k: [] for k in ("obs", "act", "rew", "next_obs", "done")}
    returns = []
    t0 = time.perf_counter()
    try:
        for k in range(episodes):
            ctrl.reset()
            obs, _ = env.reset(seed=int(d.get("seed", 2000000)) + k)
            ret, done = 0.0, False
            while not done:
                env_a = np.asarray(ctrl(obs, env), np.float64)
                nxt, r, term, trunc, _ = env.step(env_a.astype(env.action_space.dtype))
                a = 2.0 * (env_a - low) / (high - low) - 1.0  # the learner's action space
                for key, v in (("obs", obs), ("act", a), ("rew", r), ("next_obs", nxt),
                               ("done", float(term))):
                    rows[key].append(v)
                ret += float(r)
                obs, done = nxt, term or trunc
            returns.append(ret)
            log(f"demos: {name} episode {k + 1}/{episodes}, return {ret:.1f} "
                f"({time.perf_counter() - t0:.0f} s)")
    finally:
        env.close()
    return {k: np.asarray(v, np.float32) for k, v in rows.items()}, returns
