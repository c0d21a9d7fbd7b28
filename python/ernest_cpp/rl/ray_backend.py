"""Ray plumbing for training beyond one machine: the cluster connection, the rollout
worker actor, a vector env whose simulations live in those actors, and a fan-out of independent
episodes (``ernest evaluate`` / ``ernest consolidate`` with ``--backend ray``).

Ray is an optional extra (``pip install 'ernest-cpp[ray]'``) imported only here and only when a Ray
backend is chosen, so the base install never needs it.

A worker holds our native batched vector env (``env.vector``: the C++ stepper for ``ernest/...``
ids) with ``envs_per_worker`` simulations and a CPU copy of the actor. In sync mode the driver sends
the actions (computed for all simulations in one batch with the learner's actor and the trainer's
exploration generator, exactly as the local trainer does) and gets the step back as numpy arrays;
in async mode a worker collects batches of transitions with its own actor copy (ray_trainer.py).

A worker that dies is replaced by a new actor whose simulations are reset with seeds derived from
the last reset seeds, i.e. from (seed, checkpoint segment, simulation index), and the restart count:
``SeedSequence([segment_seed_i, restarts])``. The env steps it had in flight are lost and counted.
"""

from __future__ import annotations

import os
import time

import numpy as np

EXTRA_HINT = "the optional extra ernest-cpp[ray] (pip install 'ernest-cpp[ray]')"


def import_ray():
    try:
        import ray
    except ImportError:
        raise ValueError(f"--backend ray needs the ray package: install {EXTRA_HINT}") from None
    return ray


def connect(address: str | None = None, object_store_mb: int = 200):
    """Join the cluster at ``address`` (``auto``, ``host:port`` of ``ray start --head``) or start
    one on this machine; an already connected driver (tests) is reused."""
    ray = import_ray()
    if not ray.is_initialized():
        kw = {"include_dashboard": False, "log_to_driver": False, "configure_logging": False}
        if address:
            ray.init(address=address, **kw)
        else:
            # "local": a new cluster even if RAY_ADDRESS or a `ray start` node is around
            ray.init(address="local", object_store_memory=int(object_store_mb) << 20, **kw)
    return ray


def restart_seeds(seeds, restarts: int) -> list[int]:
    """Reset seeds for the simulations of a restarted worker: from their segment seeds (derived
    from (seed, segment, index), see Trainer._reset_seeds) and how often the worker restarted."""
    return [int(np.random.SeedSequence([int(s), int(restarts)]).generate_state(1)[0])
            for s in seeds]


def weights_to_numpy(module) -> dict:
    """A state dict as numpy arrays: zero-copy in Ray's object store."""
    return {k: v.detach().cpu().numpy() for k, v in module.state_dict().items()}


class RolloutWorker:
    """One Ray actor: a vector env of ``num_envs`` simulations and a CPU actor network."""

    def __init__(self, env_id: str, num_envs: int, env_cfg: dict, td3: dict, exploration: dict,
                 obs_dim: int, act_dim: int):
        import torch

        from .exploration import make_exploration
        from .networks import Actor
        from .envs_util import autoreset_mode, check_spaces, make_vector_env

        torch.set_num_threads(1)  # one core per worker (the actor requests num_cpus=1)
        self.vec = make_vector_env(env_id, num_envs, env_cfg.get("vector", "auto"),
                                   env_cfg.get("kwargs"), env_cfg.get("threads") or 1,
                                   env_cfg.get("autoreset", "same"))
        self.autoreset = autoreset_mode(self.vec)
        self.n = num_envs
        _, self.act_dim, self.low, self.high = check_spaces(self.vec.single_observation_space,
                                                            self.vec.single_action_space)
        if self.act_dim != act_dim:
            raise ValueError(f"worker env has {self.act_dim} actions, the learner {act_dim}")
        self.actor = Actor(obs_dim, act_dim, int(td3["hidden"])).requires_grad_(False)
        ex = exploration
        kw = ({"p_random": ex["p_random"], "p_hold": ex["p_hold"]} if ex["kind"] == "markov"
              else {"sigma": ex["sigma"]} if ex["kind"] == "gaussian" else {})
        self.exploration = make_exploration(ex["kind"], num_envs, act_dim, **kw)
        self.version = -1  # learner update count of the weights held
        self.obs = None

    def pid(self) -> int:
        return os.getpid()

    def autoreset_mode(self) -> str:
        return self.autoreset

    def reset(self, seeds, explore_seed: int) -> np.ndarray:
        obs, _ = self.vec.reset(seed=[int(s) for s in seeds])
        self.obs = np.asarray(obs, np.float32)
        self.rng = np.random.default_rng(int(explore_seed))  # async mode's exploration draws
        self.exploration.reset()
        self.pending = np.zeros(self.n, bool)
        self.ep_ret, self.ep_len = np.zeros(self.n), np.zeros(self.n, np.int64)
        return self.obs

    def step(self, env_actions: np.ndarray):
        """Sync mode: one step of every simulation with the driver's actions, as numpy arrays."""
        t = time.perf_counter()
        nxt, r, term, trunc, info = self.vec.step(env_actions)
        done = np.logical_or(term, trunc)
        final = None
        if self.autoreset == "same" and done.any():
            final = np.zeros((self.n,) + np.shape(nxt)[1:], np.float32)
            for i in np.flatnonzero(done):
                final[i] = info["final_obs"][i]
        return (np.asarray(nxt, np.float32), np.asarray(r, np.float64), np.asarray(term, bool),
                np.asarray(trunc, bool), final, time.perf_counter() - t)

    def collect(self, steps: int, weights, version: int, random_actions: bool) -> dict:
        """Async mode: ``steps`` vector steps with this worker's actor (new ``weights`` if given)
        and exploration; the valid transitions and finished episodes as numpy arrays."""
        import torch

        from .envs_util import step_transitions, to_env_action

        t = time.perf_counter()
        if weights is not None:
            self.actor.load_state_dict({k: torch.from_numpy(np.array(v)) for k, v in
                                        weights.items()})
            self.version = int(version)
        parts, episodes = [], []
        for _ in range(int(steps)):
            obs = self.obs
            if random_actions:
                a = self.rng.uniform(-1.0, 1.0, (self.n, self.act_dim))
            else:
                with torch.no_grad():
                    pa = self.actor(torch.from_numpy(obs)).numpy().astype(np.float64)
                a = self.exploration(pa, self.rng)
            env_a = to_env_action(a, self.low, self.high).astype(self.vec.single_action_space.dtype)
            nxt, r, term, trunc, info = self.vec.step(env_a)
            nxt, r = np.asarray(nxt, np.float32), np.asarray(r, np.float64)
            valid, real_next, done, self.pending = step_transitions(
                nxt, term, trunc, info, self.autoreset, self.pending)
            parts.append((obs[valid], a[valid], r[valid], real_next[valid],
                          np.asarray(term, bool)[valid]))
            self.ep_ret += np.where(valid, r, 0.0)
            self.ep_len += valid
            for i in np.flatnonzero(done):
                episodes.append((float(self.ep_ret[i]), int(self.ep_len[i])))
                self.ep_ret[i], self.ep_len[i] = 0.0, 0
            if done.any() or not valid.all():
                self.exploration.reset(done | ~valid)
            self.obs = nxt
        cat = [np.concatenate(c) for c in zip(*parts)]
        return {"obs": cat[0], "act": cat[1], "rew": cat[2], "next_obs": cat[3], "term": cat[4],
                "episodes": episodes, "version": self.version, "env_steps": int(steps) * self.n,
                "seconds": time.perf_counter() - t}

    def close(self) -> None:
        self.vec.close()


class RayVectorEnv:
    """The simulations of ``num_workers`` rollout actors seen as one vector env (the trainer's
    ``vec``): simulation ``w * envs_per_worker + j`` is env ``j`` of worker ``w``."""

    def __init__(self, env_id: str, num_workers: int, envs_per_worker: int, env_cfg: dict,
                 td3: dict, exploration: dict, obs_space, act_space):
        from .envs_util import check_spaces

        self.ray = import_ray()
        self.num_workers, self.m = int(num_workers), int(envs_per_worker)
        if self.num_workers < 1 or self.m < 1:
            raise ValueError(f"ray.num_workers = {num_workers} and ray.envs_per_worker = "
                             f"{envs_per_worker} must be >= 1")
        self.num_envs = self.num_workers * self.m
        self.single_observation_space, self.single_action_space = obs_space, act_space
        obs_dim, act_dim, _, _ = check_spaces(obs_space, act_space)
        self._args = (env_id, self.m, env_cfg, td3, exploration, obs_dim, act_dim)
        self._cls = self.ray.remote(num_cpus=1, max_restarts=0)(RolloutWorker)
        self.workers = [self._cls.remote(*self._args) for _ in range(self.num_workers)]
        self.restarts = [0] * self.num_workers
        self.step_seconds = np.zeros(self.num_workers)  # time in env.step, per worker
        self.env_steps = np.zeros(self.num_workers, np.int64)
        ar = self.ray.get(self.workers[0].autoreset_mode.remote())
        from gymnasium.vector import AutoresetMode

        self.metadata = {"autoreset_mode": AutoresetMode.SAME_STEP if ar == "same"
                         else AutoresetMode.NEXT_STEP}
        self.log = print
        self.seeds = [0] * self.num_envs
        self.explore_seeds = [0] * self.num_workers

    def _slice(self, w: int) -> slice:
        return slice(w * self.m, (w + 1) * self.m)

    def reset(self, seed=None, options=None):
        if seed is None or np.isscalar(seed):
            raise ValueError("RayVectorEnv.reset needs one seed per simulation")
        self.seeds = [int(s) for s in seed]
        # async exploration generator of worker w: from the seeds of its simulations
        self.explore_seeds = [int(np.random.SeedSequence(self.seeds[self._slice(w)] + [0xE7])
                                  .generate_state(1)[0]) for w in range(self.num_workers)]
        refs = [wk.reset.remote(self.seeds[self._slice(w)], self.explore_seeds[w])
                for w, wk in enumerate(self.workers)]
        obs = []
        for w, ref in enumerate(refs):
            try:
                obs.append(self.ray.get(ref))
            except self.ray.exceptions.RayActorError:
                obs.append(self.restart(w))
        return np.concatenate(obs), {}

    def restart(self, w: int) -> np.ndarray:
        """Replace dead worker ``w``; its simulations restart from fresh seeds (module doc)."""
        self.ray.kill(self.workers[w], no_restart=True)
        self.restarts[w] += 1
        self.log(f"ray worker {w} died: restarting it (restart {self.restarts[w]}), its "
                 f"simulations reseeded")
        self.workers[w] = self._cls.remote(*self._args)
        seeds = restart_seeds(self.seeds[self._slice(w)], self.restarts[w])
        ex = restart_seeds([self.explore_seeds[w]], self.restarts[w])[0]
        return self.ray.get(self.workers[w].reset.remote(seeds, ex))

    def step(self, actions: np.ndarray):
        refs = [wk.step.remote(actions[self._slice(w)]) for w, wk in enumerate(self.workers)]
        n = self.num_envs
        obs = r = None
        term, trunc, lost = np.zeros(n, bool), np.zeros(n, bool), np.zeros(n, bool)
        final = None
        for w, ref in enumerate(refs):
            sl = self._slice(w)
            try:
                o, rw, te, tr, fo, dt = self.ray.get(ref)
                self.step_seconds[w] += dt
                self.env_steps[w] += self.m
            except self.ray.exceptions.RayActorError:
                o, rw = self.restart(w), np.zeros(self.m)
                te = tr = np.zeros(self.m, bool)
                fo = None
                lost[sl] = True
            if obs is None:
                obs, r = np.zeros((n,) + o.shape[1:], np.float32), np.zeros(n)
            obs[sl], r[sl], term[sl], trunc[sl] = o, rw, te, tr
            if fo is not None:
                final = np.zeros_like(obs) if final is None else final
                final[sl] = fo
        info = {"final_obs": final}
        if lost.any():
            info["lost"] = lost
        return obs, r, term, trunc, info

    def pids(self) -> list[int]:
        return self.ray.get([wk.pid.remote() for wk in self.workers])

    def close(self) -> None:
        for wk in self.workers:
            try:
                self.ray.kill(wk, no_restart=True)
            except Exception:  # already gone
                pass
        self.workers = []


def fan_out(fn, arg_lists: list, address: str | None = None, object_store_mb: int = 200) -> list:
    """``[fn(*args) for args in arg_lists]`` as Ray tasks (one CPU each), results in order.
    ``fn`` must be importable on every node (a module-level function of ernest_cpp)."""
    ray = connect(address, object_store_mb)
    task = ray.remote(num_cpus=1)(fn)
    return ray.get([task.remote(*a) for a in arg_lists])
