"""Environments for training and evaluation: scenario names to Gymnasium ids, single and vector
envs (Gymnasium's or the rover's C++ batched stepper), space checks, the observation layout and FTS
noise of an env, the policy-to-env action map, the transitions a vector step gives the replay
buffer, and deterministic evaluation episodes. Used by the trainer, the Ray backend and consolidation.
"""

from __future__ import annotations

import collections

import numpy as np

from . import layout as L


from ..scenarios import SCENARIOS, scenario_env_id  # noqa: F401  (one table of names)


# ---------------------------------------------------------------------------- environments


def resolve_env_id(env_cfg: dict) -> str:
    env_id = env_cfg.get("id")
    if env_cfg.get("scenario"):
        sid = scenario_env_id(env_cfg["scenario"])
        if env_id and env_id != sid:
            raise ValueError(f"env.id {env_id!r} and env.scenario {env_cfg['scenario']!r} disagree")
        env_id = sid
    if not env_id:
        raise ValueError("no environment: give --env ID (any registered Gymnasium id) or "
                         "--scenario NAME")
    return env_id


def ensure_registered(env_id: str) -> None:
    import gymnasium as gym

    if env_id in gym.registry:
        return
    if env_id.startswith("ernest-toy/"):
        from . import toy_envs  # noqa: F401  (registers the toy environments)
    import importlib
    import importlib.util

    have_rover_envs = importlib.util.find_spec("ernest_cpp.envs") is not None
    if have_rover_envs:
        importlib.import_module("ernest_cpp.envs")  # the rover envs register on import
    if env_id not in gym.registry:
        namespace = env_id.split("/", 1)[0] if "/" in env_id else None
        if namespace is not None and not have_rover_envs and namespace == "ernest":
            hint = (" The ERNEST rover environments (ernest/<Scenario>-v0) are provided by "
                    "ernest_cpp.envs, which is not available in this installation.")
        else:
            # name the ids that do exist: those of the same namespace, else every ERNEST one
            known = sorted(k for k in gym.registry if namespace and k.startswith(namespace + "/"))
            known = known or sorted(k for k in gym.registry if k.startswith(("ernest/", "ernest-toy/")))
            hint = f" Registered ids: {', '.join(known)}." if known else ""
        raise ValueError(f"unknown environment id {env_id!r}: it is not registered with "
                         f"Gymnasium.{hint}")


def make_env(env_id: str, kwargs: dict | None = None):
    import gymnasium as gym

    ensure_registered(env_id)
    return gym.make(env_id, **(kwargs or {}))


def make_vector_env(env_id: str, num_envs: int, mode: str = "sync", kwargs: dict | None = None,
                    threads: int | None = None, autoreset: str = "same"):
    """Several simulations behind one vector env: ``sync`` (one process), ``async`` (one process
    each), ``ernest`` (the rover's C++ batched stepper, ``ernest_cpp.envs.make_vec``, stepping in
    ``threads`` threads with the GIL released) or ``auto`` (ernest for ernest/... ids, else sync). Gymnasium's own vector envs use same-step
    autoreset unless ``autoreset="next"``; the trainer handles both."""
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    ensure_registered(env_id)
    if num_envs < 1:
        raise ValueError(f"env.num_envs = {num_envs} must be >= 1")
    if autoreset not in ("same", "next"):
        raise ValueError(f"env.autoreset = {autoreset!r}; choose same or next")
    ar = AutoresetMode.SAME_STEP if autoreset == "same" else AutoresetMode.NEXT_STEP
    fns = [lambda: gym.make(env_id, **(kwargs or {})) for _ in range(num_envs)]
    if mode == "auto":
        mode = "ernest" if env_id.startswith("ernest/") else "sync"
    if mode == "sync":
        return gym.vector.SyncVectorEnv(fns, autoreset_mode=ar)
    if mode == "async":
        return gym.vector.AsyncVectorEnv(fns, autoreset_mode=ar)
    if mode == "ernest":
        if not env_id.startswith("ernest/"):
            raise ValueError(f"env.vector = ernest needs an ernest/... environment, got {env_id}")
        from ernest_cpp.envs import make_vec

        return make_vec(env_id, num_envs, threads, **(kwargs or {}))
    raise ValueError(f"env.vector = {mode!r}; choose auto, sync, async or ernest")


def autoreset_mode(vec) -> str:
    """'same' or 'next' for a vector env (gymnasium's metadata; next-step is its default)."""
    from gymnasium.vector import AutoresetMode

    mode = getattr(vec, "metadata", {}).get("autoreset_mode", AutoresetMode.NEXT_STEP)
    if mode == AutoresetMode.SAME_STEP:
        return "same"
    if mode == AutoresetMode.NEXT_STEP:
        return "next"
    raise ValueError(f"vector env autoreset mode {mode} is not supported (same or next step)")


def check_spaces(obs_space, act_space) -> tuple[int, int, np.ndarray, np.ndarray]:
    from gymnasium.spaces import Box

    if not isinstance(obs_space, Box) or len(obs_space.shape) != 1:
        raise ValueError(f"observation space {obs_space} is not a 1-D Box")
    if not isinstance(act_space, Box) or len(act_space.shape) != 1:
        raise ValueError(f"action space {act_space} is not a 1-D Box")
    if not (np.all(np.isfinite(act_space.low)) and np.all(np.isfinite(act_space.high))):
        raise ValueError(f"action space {act_space} must have finite bounds")
    return obs_space.shape[0], act_space.shape[0], act_space.low.astype(np.float64), \
        act_space.high.astype(np.float64)


def env_layout(env) -> L.ObservationLayout:
    """The observation layout of an env: its own ``observation_layout`` if it publishes one, the
    paper's for a 45/3 env with a [-1, 1] action space, else an identity layout."""
    obs_dim, act_dim, low, high = check_spaces(env.observation_space, env.action_space)
    own = getattr(env.unwrapped, "observation_layout", None)
    if own is not None:
        lay = own if isinstance(own, L.ObservationLayout) else L.ObservationLayout.from_dict(own)
        if lay.obs_dim != obs_dim or lay.act_dim != act_dim:
            raise ValueError(f"env's observation_layout has sizes {lay.obs_dim}/{lay.act_dim}, "
                             f"its spaces {obs_dim}/{act_dim}")
        return lay
    if obs_dim == 45 and act_dim == 3 and np.allclose(low, -1) and np.allclose(high, 1):
        return L.paper_layout()
    return L.generic_layout(obs_dim, low, high)


def noise_for(cfg_noise: dict, lay: L.ObservationLayout) -> tuple[np.ndarray, np.ndarray]:
    """(indices, std in normalised units) of the FTS noise injection from the ``noise`` settings."""
    enabled = cfg_noise.get("enabled", "auto")
    groups = (L.parse_noise_groups(cfg_noise["groups"]) if cfg_noise.get("groups") is not None
              else lay.noise_groups)
    if enabled == "auto":
        enabled = bool(groups)
    if enabled not in (True, False):
        raise ValueError(f"noise.enabled = {enabled!r}; use auto, true or false")
    if not enabled:
        return np.zeros(0, np.int64), np.zeros(0)
    if not groups:
        raise ValueError("noise.enabled is true but no noise groups are defined for this "
                         "observation layout; give noise.groups")
    scale = lay.scale
    if cfg_noise.get("obs_scale") is not None:
        scale = np.broadcast_to(np.asarray(cfg_noise["obs_scale"], np.float64),
                                (lay.obs_dim,)).copy()
    probe = L.ObservationLayout(lay.version, lay.names, lay.offset, scale, lay.action_low,
                                lay.action_high, list(groups))
    return probe.noise_std_normalised()


def to_env_action(a: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Policy action in [-1, 1] -> the env's Box (affine)."""
    return low + (np.clip(a, -1.0, 1.0) + 1.0) * 0.5 * (high - low)


def step_transitions(nxt: np.ndarray, term, trunc, info, autoreset: str,
                     pending_reset: np.ndarray, lost=None):
    """What one vector step gives the replay buffer: (valid, real_next, done, pending_reset).
    ``valid`` marks envs whose step is a transition: not the reset step after a next-step
    autoreset, nor an env ``lost`` this step (a restarted Ray worker's, reset instead of stepped).
    ``real_next`` has the final observations of same-step autoresets in place of the reset ones."""
    done = np.logical_or(term, trunc)
    if autoreset == "same":
        valid = np.ones(len(done), bool)
        real_next = nxt.copy()
        if done.any():
            fo = info["final_obs"]
            for i in np.flatnonzero(done):
                real_next[i] = fo[i]
    else:  # next-step: obs at `done` is the final one; the step after it only resets
        valid = ~pending_reset
        real_next = nxt
        done = done & valid
        pending_reset = done.copy()
    if lost is not None and np.any(lost):
        valid, done, pending_reset = valid & ~lost, done & ~lost, pending_reset & ~lost
    return valid, real_next, done, pending_reset


def info_value(info: dict, key: str):
    """A scalar from an info dict; dotted keys reach nested dicts (episode_metrics.progress)."""
    v = info
    for part in key.split("."):
        if not isinstance(v, dict) or part not in v:
            return None
        v = v[part]
    return float(v) if np.isscalar(v) and not isinstance(v, str) else None


def evaluate(policy, env, episodes: int, seed: int, info_keys=()) -> dict:
    """Deterministic episodes with seeds seed, seed+1, ...; mean return, length and info values."""
    _, _, low, high = check_spaces(env.observation_space, env.action_space)
    returns, lengths, infos = [], [], collections.defaultdict(list)
    for k in range(episodes):
        obs, info = env.reset(seed=int(seed) + k)
        ret, n, done = 0.0, 0, False
        while not done:
            a = policy(np.asarray(obs, np.float32))
            obs, r, term, trunc, info = env.step(to_env_action(a, low, high).astype(
                env.action_space.dtype))
            ret += float(r)
            n += 1
            done = term or trunc
        returns.append(ret)
        lengths.append(n)
        for key in info_keys:
            v = info_value(info, key)
            if v is not None:
                infos[key].append(v)
    out = {"return": float(np.mean(returns)), "return_std": float(np.std(returns)),
           "length": float(np.mean(lengths))}
    out.update({k: float(np.mean(v)) for k, v in infos.items()})
    return out
