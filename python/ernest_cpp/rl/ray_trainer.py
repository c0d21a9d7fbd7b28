"""``ernest train --backend ray``: the learner and replay buffer in this (driver) process, the
simulations in Ray rollout actors (ray_backend.py), in one of two modes (``ray.mode``):

* ``sync``: the workers step in lockstep with the learner exactly like the local trainer's vector
  env: the driver computes all actions in one batch with its actor and exploration generator, the
  workers step their simulations, and the reset seeds are the local ones, so a run equals
  ``--backend local`` with the same ``env.num_envs`` (= num_workers * envs_per_worker) and seed bit
  for bit, and the checkpoints are interchangeable.
* ``async``: throughput first. Each worker collects ``collect_steps`` vector steps at a time with
  its own actor copy (new weights through the object store every ``weight_sync_updates`` learner
  updates) and its own exploration generator; the learner adds each batch when it arrives and
  updates meanwhile. Which batch arrives first depends on timing, so runs are reproducible in
  distribution, not bitwise. The weight lag (learner updates since the weights a batch was
  collected with) is logged per worker.

The learner runs on ``ray.learner_device`` (``auto``: a GPU when torch sees one); the workers'
actor copies stay on their CPUs. Checkpoints hold the same state as the local trainer's (the driver's exploration state is the
reset one a checkpoint cut leaves), so a Ray checkpoint resumes with Ray or locally.
"""

from __future__ import annotations

import time

import numpy as np

from .ray_backend import RayVectorEnv, connect, weights_to_numpy
from .envs_util import make_env, resolve_env_id
from .trainer import Trainer

MODES = ("sync", "async")
IN_FLIGHT = 2  # async: collection calls queued per worker, so it never waits for the learner


def ray_settings(cfg: dict) -> dict:
    """The validated ``ray`` section; env.num_envs must be num_workers * envs_per_worker."""
    rc = dict(cfg["ray"])
    for key in ("num_workers", "envs_per_worker", "collect_steps", "weight_sync_updates",
                "object_store_mb"):
        if not isinstance(rc[key], int) or rc[key] < 1:
            raise ValueError(f"ray.{key} = {rc[key]!r} must be a whole number >= 1")
    dev = rc["learner_device"]
    if not isinstance(dev, str) or not (dev in ("auto", "cpu") or dev.startswith("cuda")):
        raise ValueError(f"ray.learner_device = {dev!r}; choose auto, cpu or cuda[:N]")
    if rc["mode"] not in MODES:
        raise ValueError(f"ray.mode = {rc['mode']!r}; choose sync or async")
    n = rc["num_workers"] * rc["envs_per_worker"]
    if int(cfg["env"]["num_envs"]) != n:
        raise ValueError(f"env.num_envs = {cfg['env']['num_envs']} differs from ray.num_workers * "
                         f"ray.envs_per_worker = {n}")
    return rc


class RayTrainer(Trainer):
    def __init__(self, cfg: dict, run_dir: str, resume: bool = False, log=print,
                 override_config: bool = False):
        self.rc = ray_settings(cfg)
        connect(self.rc["address"], self.rc["object_store_mb"])
        super().__init__(cfg, run_dir, resume, log, override_config)

    def _learner_device(self) -> str:
        import torch

        dev = self.rc["learner_device"]
        if dev == "auto":
            return "cuda" if torch.cuda.is_available() else "cpu"
        return dev

    def _make_vec(self):
        probe = self.eval_env if self.eval_env is not None else make_env(
            resolve_env_id(self.cfg["env"]), self.cfg["env"].get("kwargs"))
        vec = RayVectorEnv(self.env_id, self.rc["num_workers"], self.rc["envs_per_worker"],
                           self.cfg["env"], self.cfg["td3"], self.cfg["exploration"],
                           probe.observation_space, probe.action_space)
        self.lag = np.zeros(vec.num_workers)  # learner updates behind, per worker
        vec.log = self.log
        return vec

    # ------------------------------------------------------------------ logging
    def _begin(self, total_steps):
        run = super()._begin(total_steps)
        run.w0 = self.vec.env_steps.copy()
        return run

    def _perf(self, run) -> dict:
        out = super()._perf(run)
        dt = max(time.perf_counter() - run.t0, 1e-9)
        for w in range(self.vec.num_workers):
            out[f"worker{w}/steps_per_second"] = (self.vec.env_steps[w] - run.w0[w]) / dt
            out[f"worker{w}/weight_lag"] = float(self.lag[w])
            out[f"worker{w}/restarts"] = self.vec.restarts[w]
        return out

    def _bar_extra(self, perf: dict) -> str:
        return "; " + ", ".join(f"w{w} {perf[f'worker{w}/steps_per_second']:.0f}/s lag "
                                f"{self.lag[w]:.0f}" for w in range(self.vec.num_workers))

    # ------------------------------------------------------------------ loops
    def train(self, total_steps: int | None = None) -> dict:
        if self.rc["mode"] == "sync":
            return super().train(total_steps)  # lockstep: the local loop on RayVectorEnv
        return self._train_async(total_steps)

    def _publish(self) -> None:
        """Put the actor's weights in the object store once; workers fetch them by reference."""
        self.weights_ref = self.vec.ray.put(weights_to_numpy(self.agent.actor))
        self.version = self.agent.updates

    def _train_async(self, total_steps: int | None) -> dict:
        run = self._begin(total_steps)
        ray, vec, rc = self.vec.ray, self.vec, self.rc
        steps, m = rc["collect_steps"], vec.m
        random_steps = int(self.cfg["random_steps"])
        pending: dict = {}  # object ref -> (worker index, the actor handle called)
        held = [None] * vec.num_workers  # weight version each worker holds

        def submit(w: int) -> None:
            new = held[w] != self.version
            ref = vec.workers[w].collect.remote(steps, self.weights_ref if new else None,
                                                self.version, self.step < random_steps)
            held[w] = self.version
            pending[ref] = (w, vec.workers[w])

        def receive(ref) -> tuple[bool, bool]:
            """Add one batch: (a checkpoint is due, the worker wants a new call)."""
            w, handle = pending.pop(ref)
            try:
                b = ray.get(ref)
            except ray.exceptions.RayActorError:
                self.lost_transitions += steps * m  # each of the dead actor's calls once
                self.log(f"ray worker {w}: {steps * m} env steps lost "
                         f"({self.lost_transitions} in all)")
                if handle is not vec.workers[w]:
                    return False, False  # a queued call of an actor already replaced
                vec.restart(w)
                held[w] = None
                for _ in range(IN_FLIGHT - 1):  # the replacement's queue (the caller adds one)
                    submit(w)
                return False, True
            if len(b["rew"]):
                self.buffer.add(b["obs"], b["act"], b["rew"], b["next_obs"], b["term"])
            for ret, length in b["episodes"]:
                self._episode_done(run, ret, length)
            self.lag[w] = self.agent.updates - b["version"]
            vec.env_steps[w] += b["env_steps"]
            vec.step_seconds[w] += b["seconds"]
            due = self._advance(run, len(b["rew"]))
            if self.agent.updates - self.version >= rc["weight_sync_updates"]:
                self._publish()
            return due, True

        def drain() -> None:
            while pending:
                receive(next(iter(pending)))

        def fill() -> None:
            for k in range(vec.num_workers * IN_FLIGHT if self.step < run.total else 0):
                submit(k % vec.num_workers)

        self._reset_envs()
        self._publish()
        fill()
        while self.step < run.total:
            first, _ = ray.wait(list(pending), num_returns=1)
            # the oldest call among those done: when the learner is the bottleneck, every worker's
            # batches still get their turn (ray.wait's pick could favour one worker)
            done = set(first) | set(ray.wait(list(pending), num_returns=len(pending),
                                              timeout=0)[0])
            ref = next(r for r in pending if r in done)
            w = pending[ref][0]
            due, again = receive(ref)
            if due:
                drain()  # the in-flight batches belong to this segment
                run.last_ck = self.step
                self._checkpoint_and_cut()  # workers reset with the new segment's seeds
                fill()
            elif again and self.step < run.total:
                submit(w)
        drain()
        return self._finish(run)
