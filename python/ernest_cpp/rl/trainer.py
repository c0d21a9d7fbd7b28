"""Specialist training: several simulations (a Gymnasium vector env, in one process or one process
each) feed one TD3 learner (seed 004 §4.1, §4.6: "six simulation instances ... continuously collect
experience while the policy is updated").

Exact resume. A checkpoint holds the networks, targets, optimisers, the TD3 noise generator, the
exploration and sampling generators, the exploration state, the replay buffer in its storage order and
all counters. Simulator state cannot be captured for an arbitrary env, so every checkpoint ends the
current episodes: right after a save, both the continuing run and any run resumed from that save reset
all simulations with seeds derived from (seed, checkpoint segment, simulation index). A resumed run
therefore continues exactly like the uninterrupted one (for deterministic simulators); the episodes
cut at a checkpoint are treated like time-outs (their transitions keep bootstrapping).
"""

from __future__ import annotations

import collections
import dataclasses
import json
import math
import os
import re
import shutil
import time

import numpy as np
import torch
import yaml

from . import layout as L
from .exploration import make_exploration
from .replay import ReplayBuffer
from .storage import AtomicDir, CorruptFileError, clean_stale, read_manifest
from .td3 import TD3, TD3Config

SCENARIOS = {"rockfield": "RockField", "step": "Step", "ripples": "Ripples", "slope": "Slope"}


# ---------------------------------------------------------------------------- environments
def scenario_env_id(scenario: str) -> str:
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario {scenario!r}: choose one of {', '.join(SCENARIOS)}")
    return f"ernest/{SCENARIOS[scenario]}-v0"


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
        importlib.import_module("ernest_cpp.envs")  # the rover envs register on import (issue 5)
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


# ---------------------------------------------------------------------------- checkpoints
def _rng_state(rng: np.random.Generator) -> dict:
    return rng.bit_generator.state


def _set_rng_state(rng: np.random.Generator, state: dict) -> None:
    rng.bit_generator.state = state


def find_checkpoint(path: str) -> str:
    """A checkpoint folder from a run folder (its latest), a checkpoints folder, or itself."""
    if os.path.isfile(os.path.join(path, "manifest.json")):
        return path
    for base in (os.path.join(path, "checkpoints"), path):
        latest = os.path.join(base, "LATEST")
        if os.path.isfile(latest):
            with open(latest) as fh:
                name = fh.read().strip()
            return os.path.join(base, name)
    raise CorruptFileError(f"{path}: no checkpoint found (neither a checkpoint folder nor a run "
                           f"folder with checkpoints/LATEST)")


_STEP_DIR = re.compile(r"^step-\d+$")


def newest_good_checkpoint(ck_root: str, exclude: str = "") -> str | None:
    """The newest ``step-N`` folder of ``ck_root`` (other than ``exclude``) that verifies."""
    try:
        names = sorted((d for d in os.listdir(ck_root) if _STEP_DIR.match(d)),
                       key=lambda d: int(d[5:]), reverse=True)
    except OSError:
        return None
    for d in names:
        p = os.path.join(ck_root, d)
        if os.path.abspath(p) == os.path.abspath(exclude):
            continue
        try:
            read_manifest(p, "checkpoint", verify=True)
            return p
        except CorruptFileError:
            continue
    return None


def load_checkpoint(path: str, with_buffer: bool = True) -> dict:
    """Verify and read a checkpoint: {'state': dict, 'agent': state_dict, 'buffer': ReplayBuffer}.
    If it is damaged, the error names the newest intact checkpoint beside it and how to use it."""
    ck = find_checkpoint(path)
    try:
        return _read_checkpoint(ck, with_buffer)
    except CorruptFileError as exc:
        ck_root = os.path.dirname(os.path.abspath(ck))
        good = newest_good_checkpoint(ck_root, exclude=ck)
        if good is None:
            raise
        raise CorruptFileError(
            f"{exc}. The newest intact checkpoint is {good}: resume from it with "
            f"`echo {os.path.basename(good)} > {os.path.join(ck_root, 'LATEST')}`, or pass it "
            f"as the checkpoint folder") from None


def _read_checkpoint(ck: str, with_buffer: bool) -> dict:
    read_manifest(ck, "checkpoint", verify=True)
    try:
        with open(os.path.join(ck, "state.json")) as fh:
            state = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise CorruptFileError(f"{ck}/state.json: unreadable ({exc})") from None
    try:
        agent_sd = torch.load(os.path.join(ck, "agent.pt"), weights_only=True,
                              map_location="cpu")  # a GPU learner's checkpoint loads anywhere
    except Exception as exc:  # torch raises several types for damaged zip archives
        raise CorruptFileError(f"{ck}/agent.pt: unreadable network file ({exc})") from None
    out = {"path": ck, "state": state, "agent": agent_sd}
    if with_buffer and os.path.isdir(os.path.join(ck, "buffer")):
        out["buffer"] = ReplayBuffer.load(os.path.join(ck, "buffer"), verify=False)
    return out


def agent_from_checkpoint(ck: dict) -> TD3:
    st = ck["state"]
    agent = TD3(st["obs_dim"], st["act_dim"], TD3Config(**st["td3"]), seed=0)
    agent.load_state_dict(ck["agent"])
    return agent


# ---------------------------------------------------------------------------- trainer
class Trainer:
    def __init__(self, cfg: dict, run_dir: str, resume: bool = False, log=print):
        self.cfg, self.run_dir, self.log = cfg, run_dir, log
        self.eval_env = self.vec = None
        try:
            self._setup(resume)
        except BaseException:
            self.close()  # no orphaned simulation processes on a bad config or checkpoint
            raise

    def _setup(self, resume: bool) -> None:
        cfg, run_dir = self.cfg, self.run_dir
        torch.set_num_threads(int(cfg["torch_threads"]))
        self.env_id = resolve_env_id(cfg["env"])
        ec = cfg["env"]
        self.eval_env = make_env(self.env_id, ec.get("kwargs"))
        self.layout = env_layout(self.eval_env)
        self.vec = self._make_vec()
        self.autoreset = autoreset_mode(self.vec)
        self.n = self.vec.num_envs
        self.obs_dim, self.act_dim, self.low, self.high = check_spaces(
            self.vec.single_observation_space, self.vec.single_action_space)
        self.td3_cfg = TD3Config(**cfg["td3"]).validate()
        seed = int(cfg["seed"])
        self.agent = TD3(self.obs_dim, self.act_dim, self.td3_cfg, seed=seed,
                         device=self._learner_device())
        self.buffer = ReplayBuffer(int(cfg["buffer_size"]), self.obs_dim, self.act_dim)
        self.buffer.set_noise(*noise_for(cfg["noise"], self.layout))
        ex = cfg["exploration"]
        kw = ({"p_random": ex["p_random"], "p_hold": ex["p_hold"]} if ex["kind"] == "markov"
              else {"sigma": ex["sigma"]} if ex["kind"] == "gaussian" else {})
        self.exploration = make_exploration(ex["kind"], self.n, self.act_dim, **kw)
        ss = np.random.SeedSequence(seed)
        e_seq, s_seq = ss.spawn(2)
        self.explore_rng = np.random.default_rng(e_seq)
        self.sample_rng = np.random.default_rng(s_seq)
        self.step = 0  # transitions collected
        self.segment = 0  # checkpoint segments: the env reset seeds of each segment are fixed
        self.episodes = 0
        self.update_acc = 0.0
        self.lost_transitions = 0  # env steps of Ray workers that died (never in a local run)
        self.recent = collections.deque(maxlen=int(cfg["log"]["recent_episodes"]))
        self.last_eval: dict = {}
        if resume:
            self._restore()
        elif os.path.isdir(os.path.join(run_dir, "checkpoints")):
            raise ValueError(f"{run_dir} already holds checkpoints; use --resume to continue it "
                             f"or choose another --run-dir")
        os.makedirs(run_dir, exist_ok=True)
        with open(os.path.join(run_dir, "config.yaml"), "w") as fh:
            yaml.safe_dump(cfg, fh, sort_keys=False)

    def _learner_device(self) -> str:
        return "cpu"

    def _make_vec(self):
        ec = self.cfg["env"]
        return make_vector_env(self.env_id, int(ec["num_envs"]), ec["vector"], ec.get("kwargs"),
                               ec.get("threads"), ec.get("autoreset", "same"))

    # ------------------------------------------------------------------ state
    def _reset_seeds(self) -> list[int]:
        base = int(self.cfg["seed"])
        return [int(np.random.SeedSequence([base, self.segment, i]).generate_state(1)[0])
                for i in range(self.n)]

    def _reset_envs(self) -> np.ndarray:
        obs, _ = self.vec.reset(seed=self._reset_seeds())
        self.exploration.reset()
        self.pending_reset = np.zeros(self.n, bool)  # next-step autoreset: no transition next step
        self.ep_ret = np.zeros(self.n)
        self.ep_len = np.zeros(self.n, np.int64)
        return np.asarray(obs, np.float32)

    def _state(self) -> dict:
        return {"env_id": self.env_id, "obs_dim": self.obs_dim, "act_dim": self.act_dim,
                "td3": self.agent.config_dict(), "layout": self.layout.to_dict(),
                "step": self.step, "segment": self.segment, "episodes": self.episodes,
                "update_acc": self.update_acc, "updates": self.agent.updates,
                "lost_transitions": self.lost_transitions,
                "explore_rng": _rng_state(self.explore_rng),
                "sample_rng": _rng_state(self.sample_rng),
                "exploration": self.exploration.state_dict(), "recent": list(self.recent),
                "last_eval": self.last_eval, "config": self.cfg}

    def save_checkpoint(self) -> str:
        ck_root = os.path.join(self.run_dir, "checkpoints")
        clean_stale(ck_root)  # temporaries of a writer killed mid-save
        name = f"step-{self.step:012d}"
        with AtomicDir(os.path.join(ck_root, name), "checkpoint",
                       {"step": self.step, "env_id": self.env_id}) as tmp:
            torch.save(self.agent.state_dict(), os.path.join(tmp, "agent.pt"))
            with open(os.path.join(tmp, "state.json"), "w") as fh:
                json.dump(self._state(), fh)
            self.buffer.save(os.path.join(tmp, "buffer"))
        latest_tmp = os.path.join(ck_root, "LATEST.tmp")
        with open(latest_tmp, "w") as fh:
            fh.write(name + "\n")
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(latest_tmp, os.path.join(ck_root, "LATEST"))
        # Prune only checkpoints older than the one just written (which is the newest good one):
        # those with a higher step are from beyond a resume point (e.g. a corrupt one the user
        # stepped back from) and are left for the user to inspect.
        keep = max(1, int(self.cfg["checkpoint"]["keep"]))
        older = sorted((d for d in os.listdir(ck_root) if _STEP_DIR.match(d) and
                        int(d[5:]) < self.step), key=lambda d: int(d[5:]))
        for d in older[:max(0, len(older) - (keep - 1))]:
            shutil.rmtree(os.path.join(ck_root, d), ignore_errors=True)
        return os.path.join(ck_root, name)

    def _restore(self) -> None:
        clean_stale(os.path.join(self.run_dir, "checkpoints"))
        ck = load_checkpoint(self.run_dir)
        st = ck["state"]
        if st["env_id"] != self.env_id or st["obs_dim"] != self.obs_dim or \
                st["act_dim"] != self.act_dim:
            raise ValueError(f"checkpoint {ck['path']} was made on {st['env_id']} "
                             f"({st['obs_dim']}/{st['act_dim']}), this run uses {self.env_id}")
        if st["td3"] != self.agent.config_dict():
            raise ValueError(f"checkpoint {ck['path']}: TD3 settings differ from this run's "
                             f"({st['td3']} vs {self.agent.config_dict()})")
        if self.n != len(st["exploration"].get("mode", [0] * self.n)):
            raise ValueError("checkpoint was made with a different env.num_envs")
        self.agent.load_state_dict(ck["agent"])
        buf = ck["buffer"]
        if buf.capacity != self.buffer.capacity:
            raise ValueError(f"checkpoint buffer capacity {buf.capacity} differs from "
                             f"buffer_size {self.buffer.capacity}")
        buf.set_noise(self.buffer.noise_idx, self.buffer.noise_std)
        self.buffer = buf
        self.step, self.segment, self.episodes = st["step"], st["segment"], st["episodes"]
        self.update_acc = st["update_acc"]
        self.lost_transitions = st.get("lost_transitions", 0)
        _set_rng_state(self.explore_rng, st["explore_rng"])
        _set_rng_state(self.sample_rng, st["sample_rng"])
        self.exploration.load_state_dict(st["exploration"])
        self.recent.extend(st["recent"])
        self.last_eval = st.get("last_eval", {})
        self._trim_eval_log()
        self.log(f"resumed {ck['path']} at step {self.step} ({self.agent.updates} updates)")

    def _trim_eval_log(self) -> None:
        """Drop evaluation rows written after the checkpoint we resume from (they will be redone)."""
        path = os.path.join(self.run_dir, "eval.csv")
        if not os.path.exists(path):
            return
        with open(path) as fh:
            lines = fh.read().splitlines()
        if not lines:
            return
        col = lines[0].split(",").index("step") if "step" in lines[0].split(",") else None
        if col is None:
            return
        keep = [lines[0]] + [ln for ln in lines[1:] if float(ln.split(",")[col]) <= self.step]
        with open(path + ".tmp", "w") as fh:
            fh.write("\n".join(keep) + "\n")
        os.replace(path + ".tmp", path)

    # ------------------------------------------------------------------ loop
    def _policy(self, obs: np.ndarray) -> np.ndarray:
        return self.agent.act(obs)

    def run_eval(self) -> dict:
        ev = self.cfg["eval"]
        res = evaluate(self._policy, self.eval_env, int(ev["episodes"]), int(ev["seed"]),
                       ev.get("info_keys") or ())
        res["step"] = self.step
        self.last_eval = res
        path = os.path.join(self.run_dir, "eval.csv")
        new = not os.path.exists(path)
        keys = sorted(res)
        with open(path, "a") as fh:
            if new:
                fh.write(",".join(keys) + "\n")
            fh.write(",".join(f"{res[k]:.6g}" for k in keys) + "\n")
        return res

    def run_baseline(self) -> dict | None:
        """Fixed-action episodes on the evaluation seeds (e.g. the passive-bogie baseline of
        seed 004 Table 6: full forward speed, gimbal still), computed once per run."""
        spec = self.cfg["eval"].get("baseline")
        if not spec:
            return None
        path = os.path.join(self.run_dir, "baseline.json")
        if os.path.exists(path):
            with open(path) as fh:
                return json.load(fh)
        if not isinstance(spec, dict) or "action" not in spec:
            raise ValueError("eval.baseline must be a mapping with 'action' (and optional 'kwargs')")
        action = np.asarray(spec["action"], np.float64).reshape(-1)
        if action.shape != (self.act_dim,) or np.any(np.abs(action) > 1):
            raise ValueError(f"eval.baseline.action must have {self.act_dim} values in [-1, 1], "
                             f"got {spec['action']}")
        kwargs = dict(self.cfg["env"].get("kwargs") or {})
        kwargs.update(spec.get("kwargs") or {})
        env = make_env(self.env_id, kwargs)
        ev = self.cfg["eval"]
        try:
            res = evaluate(lambda obs: action, env, int(ev["episodes"]), int(ev["seed"]),
                           ev.get("info_keys") or ())
        finally:
            env.close()
        res["action"] = action.tolist()
        with open(path + ".tmp", "w") as fh:
            json.dump(res, fh, indent=1)
        os.replace(path + ".tmp", path)
        return res

    def train(self, total_steps: int | None = None) -> dict:
        run = self._begin(total_steps)
        random_steps = int(self.cfg["random_steps"])
        obs = self._reset_envs()
        while self.step < run.total:
            if self.step < random_steps:
                a = self.explore_rng.uniform(-1.0, 1.0, (self.n, self.act_dim))
            else:
                a = self.exploration(self.agent.act(obs), self.explore_rng)
            env_a = to_env_action(a, self.low, self.high).astype(self.vec.single_action_space.dtype)
            nxt, r, term, trunc, info = self.vec.step(env_a)
            nxt = np.asarray(nxt, np.float32)
            r = np.asarray(r, np.float64)
            lost = info.get("lost") if isinstance(info, dict) else None  # Ray: restarted worker
            valid, real_next, done, self.pending_reset = step_transitions(
                nxt, term, trunc, info, self.autoreset, self.pending_reset, lost)
            if lost is not None:
                self.lost_transitions += int(np.sum(lost))
                self.log(f"{int(np.sum(lost))} env steps lost ({self.lost_transitions} in all)")
                self.ep_ret[lost], self.ep_len[lost] = 0.0, 0  # the episode is gone, not counted
            if valid.all():
                self.buffer.add(obs, a, r, real_next, term)
            elif valid.any():
                self.buffer.add(obs[valid], a[valid], r[valid], real_next[valid],
                                np.asarray(term)[valid])
            self.ep_ret += np.where(valid, r, 0.0)
            self.ep_len += valid
            for i in np.flatnonzero(done):
                self._episode_done(run, self.ep_ret[i], self.ep_len[i])
                self.ep_ret[i], self.ep_len[i] = 0.0, 0
            if done.any() or not valid.all():  # episodes start in the POLICY state (§4.4)
                self.exploration.reset(done | ~valid)
            obs = nxt
            if self._advance(run, int(valid.sum())):
                obs = self._checkpoint_and_cut()
        return self._finish(run)

    # The loop's bookkeeping, shared with the Ray trainers (ray_trainer.py).
    def _begin(self, total_steps: int | None):
        cfg = self.cfg
        total = int(total_steps if total_steps is not None else cfg["total_steps"])
        if total < 1:  # nothing to train on would end in a NaN summary
            raise ValueError(f"total_steps = {total}: must be at least 1")
        run = _Run(total=total, stats=collections.defaultdict(list), t0=time.perf_counter(),
                   s0=self.step, u0=self.agent.updates, last_ck=self.step)
        run.writer = _writer(os.path.join(self.run_dir, "tb")) if cfg["log"]["tensorboard"] \
            else None
        run.bar = _bar(total, self.step, cfg["log"]["progress_bar"])
        run.baseline = self.run_baseline()
        if run.baseline and run.writer:
            for key, v in run.baseline.items():
                if key != "action":
                    run.writer.add_scalar(f"eval/baseline_{key}", v, self.step)
        return run

    def _episode_done(self, run, ret: float, length: int) -> None:
        self.recent.append(float(ret))
        self.episodes += 1
        if run.writer:
            run.writer.add_scalar("train/episode_return", ret, self.step)
            run.writer.add_scalar("train/episode_length", length, self.step)

    def _learn(self, run, added: int) -> None:
        """The learner's share of ``added`` new transitions (updates_per_step each)."""
        if self.step >= int(self.cfg["learning_starts"]) and len(self.buffer) >= 1:
            self.update_acc += added * float(self.cfg["updates_per_step"])
            k = int(self.update_acc)
            self.update_acc -= k
            for _ in range(k):
                m = self.agent.update(self.buffer.sample(self.td3_cfg.batch_size, self.sample_rng))
                for key, v in m.items():
                    run.stats[key].append(v)

    def _perf(self, run) -> dict:
        """Throughput figures for the progress bar and TensorBoard (perf/<name>)."""
        dt = max(time.perf_counter() - run.t0, 1e-9)
        return {"steps_per_second": (self.step - run.s0) / dt,
                "updates_per_second": (self.agent.updates - run.u0) / dt,
                "lost_transitions": self.lost_transitions}

    def _bar_extra(self, perf: dict) -> str:
        return ""

    def _advance(self, run, added: int) -> bool:
        """Count ``added`` transitions, learn, log, evaluate; True when a checkpoint is due (the
        caller then saves it and cuts the episodes)."""
        cfg, prev = self.cfg, self.step
        self.step += added
        self._learn(run, added)
        run.bar.update(self.step - prev)
        log_every = int(cfg["log"]["every_steps"])
        ev_every, ck_every = int(cfg["eval"]["every_steps"]), int(cfg["checkpoint"]["every_steps"])
        log_now = self.step // log_every > prev // log_every
        if log_now or self.step >= run.total:
            perf = self._perf(run)
            if run.writer and log_now:
                for key, v in perf.items():
                    run.writer.add_scalar(f"perf/{key}", v, self.step)
                run.writer.add_scalar("perf/updates", self.agent.updates, self.step)
                for key, v in run.stats.items():
                    run.writer.add_scalar(f"train/{key}", float(np.mean(v)), self.step)
                run.stats.clear()
            rec = f"{np.mean(self.recent):.2f}" if self.recent else "-"
            extra = (f", lost {self.lost_transitions}" if self.lost_transitions else "") + \
                self._bar_extra(perf)
            run.bar.set_postfix_str(f"{perf['steps_per_second']:.0f} steps/s, "
                                    f"{perf['updates_per_second']:.0f} updates/s, return(last "
                                    f"{len(self.recent)}) {rec}{extra}")
        if ev_every > 0 and self.step // ev_every > prev // ev_every:
            res = self.run_eval()
            if run.writer:
                for key, v in res.items():
                    if key != "step":
                        run.writer.add_scalar(f"eval/{key}", v, self.step)
                for key, v in (run.baseline or {}).items():  # flat reference line on the plots
                    if key != "action":
                        run.writer.add_scalar(f"eval/baseline_{key}", v, self.step)
        if ck_every > 0 and self.step // ck_every > prev // ck_every:
            run.last_ck = self.step
            return True
        return False

    def _finish(self, run) -> dict:
        if run.last_ck != self.step:
            self._checkpoint_and_cut()
        run.bar.close()
        if run.writer:
            run.writer.close()
        return {"step": self.step, "updates": self.agent.updates, "episodes": self.episodes,
                "recent_return": float(np.mean(self.recent)) if self.recent else math.nan,
                "lost_transitions": self.lost_transitions,
                "last_eval": self.last_eval, "baseline": run.baseline}

    def _checkpoint_and_cut(self) -> np.ndarray:
        self.segment += 1  # saved with the new segment: a resume resets exactly like we do now
        self.save_checkpoint()
        return self._reset_envs()

    def close(self) -> None:
        for env in (self.vec, self.eval_env):
            if env is not None:
                env.close()
        self.vec = self.eval_env = None


@dataclasses.dataclass
class _Run:
    """One train() call's totals, timers, statistics, writer and bar."""
    total: int
    stats: dict
    t0: float
    s0: int
    u0: int
    last_ck: int
    writer: object = None
    bar: object = None
    baseline: dict | None = None


def _writer(path: str):
    try:
        from torch.utils.tensorboard import SummaryWriter
    except ImportError:
        return None
    return SummaryWriter(path)


class _NoBar:
    def update(self, n):
        pass

    def set_postfix_str(self, s):
        pass

    def close(self):
        pass


def _bar(total: int, initial: int, enabled: bool):
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="step", dynamic_ncols=True)
