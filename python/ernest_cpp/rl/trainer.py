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
import shutil
import time

import numpy as np
import torch
import yaml

from .._csv import bare, header as csv_header
from .checkpoints import STEP_DIR, check_resume_config, load_checkpoint
from .envs_util import (autoreset_mode, check_spaces, env_layout, evaluate, make_env,
                        make_vector_env, noise_for, resolve_env_id, step_transitions, to_env_action)
from . import demos
from .exploration import make_exploration
from .replay import ReplayBuffer
from .storage import AtomicDir, clean_stale
from .td3 import TD3, TD3Config, resolve_device


def _rng_state(rng: np.random.Generator) -> dict:
    return rng.bit_generator.state


def _set_rng_state(rng: np.random.Generator, state: dict) -> None:
    rng.bit_generator.state = state


#: Units of eval.csv's columns (its header reads ``name [unit]``); an info key not listed here (an
#: env's own) is written with ``[?]``.
EVAL_UNITS = {"step": "transitions", "elapsed_s": "s", "return": "-", "return_std": "-",
              "length": "policy steps", "path_progress": "m", "episode_metrics.progress": "m",
              "episode_metrics.expected_progress": "m", "episode_metrics.distance": "m",
              "episode_metrics.travel_reduction": "-", "episode_metrics.cost_of_transport": "-",
              "episode_metrics.energy": "J", "episode_metrics.time": "s",
              "episode_metrics.mean_abs_roll_torque": "N m"}


class Trainer:
    """``resume``: continue the run saved in ``run_dir``. ``cfg`` must then be the run's saved
    settings, changed at most in those checkpoints.RESUME_FREE lists (the length of the run,
    logging, checkpoints kept); other changes are refused unless ``override_config``."""

    def __init__(self, cfg: dict, run_dir: str, resume: bool = False, log=print,
                 override_config: bool = False):
        self.cfg, self.run_dir, self.log = cfg, run_dir, log
        self.override_config = bool(override_config)
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
        self.demo_transitions = 0  # scripted demonstrator transitions in the buffer (demos)
        self.elapsed = 0.0  # wall seconds of training over all resumes (learning curves)
        self._t_start = None  # perf_counter at the start of the current train() call
        demos.check_settings(cfg)
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
        # Runs saved before the setting existed learned on the CPU: resume them there.
        return resolve_device(self.cfg.get("learner_device", "cpu"))

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
                "demo_transitions": self.demo_transitions,
                "elapsed": self._elapsed(),
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
        older = sorted((d for d in os.listdir(ck_root) if STEP_DIR.match(d) and
                        int(d[5:]) < self.step), key=lambda d: int(d[5:]))
        for d in older[:max(0, len(older) - (keep - 1))]:
            shutil.rmtree(os.path.join(ck_root, d), ignore_errors=True)
        return os.path.join(ck_root, name)

    def _restore(self) -> None:
        clean_stale(os.path.join(self.run_dir, "checkpoints"))
        ck = load_checkpoint(self.run_dir)
        st = ck["state"]
        changed = check_resume_config(st["config"], self.cfg, ck["path"],
                                      self.override_config) if "config" in st else []
        if changed:
            self.log(f"resuming {ck['path']} with changed settings (--override-config): "
                     f"{'; '.join(changed)}")
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
        self.demo_transitions = st.get("demo_transitions", 0)
        self.elapsed = float(st.get("elapsed", 0.0))
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
        header = [bare(h) for h in lines[0].split(",")]
        if "step" not in header:
            return
        col = header.index("step")

        def before(ln: str) -> bool:  # a partial row of a writer killed mid-line goes too
            cells = ln.split(",")
            try:
                return len(cells) == len(header) and float(cells[col]) <= self.step
            except ValueError:
                return False

        keep = [lines[0]] + [ln for ln in lines[1:] if before(ln)]
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
        res["elapsed_s"] = self._elapsed()
        self.last_eval = res
        path = os.path.join(self.run_dir, "eval.csv")
        new = not os.path.exists(path)
        keys = sorted(res)
        with open(path, "a") as fh:
            if new:
                fh.write(",".join(csv_header(keys, EVAL_UNITS, "?")) + "\n")
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
    def _elapsed(self) -> float:
        """Wall seconds of training so far, over all resumes."""
        if self._t_start is None:
            return self.elapsed
        return self.elapsed + time.perf_counter() - self._t_start

    def _write_progress(self, run, perf: dict) -> None:
        """<run>/progress.json (atomically): where the run is and how fast it goes, for
        ``ernest train-default`` and anyone watching a run."""
        rec = {"step": self.step, "total": run.total, "updates": self.agent.updates,
               "episodes": self.episodes, "demo_transitions": self.demo_transitions,
               "elapsed_s": round(self._elapsed(), 1),
               "transitions_per_s": round(perf["steps_per_second"], 2),
               "updates_per_s": round(perf["updates_per_second"], 2),
               "recent_return": float(np.mean(self.recent)) if self.recent else None,
               "last_eval": self.last_eval}
        path = os.path.join(self.run_dir, "progress.json")
        with open(path + ".tmp", "w") as fh:
            json.dump(rec, fh)
        os.replace(path + ".tmp", path)

    def _begin(self, total_steps: int | None):
        cfg = self.cfg
        self._t_start = time.perf_counter()
        total = int(total_steps if total_steps is not None else cfg["total_steps"])
        if total < 1:  # nothing to train on would end in a NaN summary
            raise ValueError(f"total_steps = {total}: must be at least 1")
        run = _Run(total=total, stats=collections.defaultdict(list), t0=time.perf_counter(),
                   s0=self.step, u0=self.agent.updates, last_ck=self.step)
        run.writer = _writer(os.path.join(self.run_dir, "tb")) if cfg["log"]["tensorboard"] \
            else None
        run.bar = _bar(total, self.step, cfg["log"]["progress_bar"])
        run.baseline = self.run_baseline()
        self._fill_demos()
        if run.baseline and run.writer:
            for key, v in run.baseline.items():
                if key != "action":
                    run.writer.add_scalar(f"eval/baseline_{key}", v, self.step)
        return run

    def _fill_demos(self) -> None:
        """Scripted demonstrator episodes into the replay buffer, once per run (``demos``
        settings, :mod:`.demos`); a resumed run has them in its saved buffer already."""
        if self.demo_transitions or self.step > 0:
            return
        data, returns = demos.collect(self.env_id, self.cfg, self.low, self.high, self.log)
        if data is None:
            return
        self.buffer.add(**data)
        self.demo_transitions = len(data["rew"])
        self.log(f"demos: {self.demo_transitions} transitions from {len(returns)} episodes "
                 f"(mean return {np.mean(returns):.1f}) in the replay buffer")

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
            self._write_progress(run, perf)
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
        self.elapsed, self._t_start = self._elapsed(), None
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
