"""Train a small TD3 with ernest_cpp.rl and with Stable-Baselines3 on the same task, and compare.

Shows: the training API behind ``ernest train`` (``rl.config.build_config`` with ``--set``-style
overrides, ``rl.trainer.Trainer``), evaluating a policy on fixed seeds (``rl.envs_util.evaluate``)
and SB3's ``TD3`` with the same network size, batch, exploration noise and step count.

    python examples/td3_vs_sb3.py --out out/examples [--steps 3000] [--env ernest-toy/PointMass-v0]

The default task is the toy point mass (reach a target on a line in 10 steps; its best return has
a closed form), so both learners show progress in seconds. Any Gymnasium id with Box spaces
works, e.g. ``--env ernest/Slope-v0 --steps 50000`` for the rover (minutes to hours). Writes
OUT/td3_vs_sb3.csv (one row per learner) and OUT/td3_vs_sb3/ (our run folder: config, checkpoint,
eval.csv). Needs the ``sb3`` extra (``pip install ernest-cpp[sb3]``). Takes ~20 s on 2 cores.
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import time

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import TD3 as SB3TD3
from stable_baselines3.common.noise import NormalActionNoise

from ernest_cpp.rl.config import build_config
from ernest_cpp.rl.envs_util import ensure_registered, evaluate, make_env
from ernest_cpp.rl.trainer import Trainer

EVAL_SEED, EVAL_EPISODES = 1000, 20


def train_ours(env_id: str, steps: int, hidden: int, run_dir: str):
    cfg = build_config("quick", overrides=[
        f"env.id={env_id}", "env.num_envs=1", f"total_steps={steps}",
        "random_steps=500", "learning_starts=500", f"td3.hidden={hidden}",
        "exploration.kind=gaussian", "exploration.sigma=0.1",  # SB3's usual action noise
        "eval.every_steps=0", f"checkpoint.every_steps={steps}",
        "log.tensorboard=false", "log.progress_bar=false"])
    shutil.rmtree(run_dir, ignore_errors=True)  # a Trainer refuses a folder holding a run
    tr = Trainer(cfg, run_dir, log=lambda *a: None)
    try:
        tr.train()
    finally:
        tr.close()
    return tr.agent.act


def train_sb3(env_id: str, steps: int, hidden: int):
    env = gym.make(env_id)
    n = env.action_space.shape[0]
    model = SB3TD3("MlpPolicy", env, learning_starts=500, batch_size=128, buffer_size=steps,
                   policy_kwargs={"net_arch": [hidden, hidden]}, seed=0, device="cpu", verbose=0,
                   action_noise=NormalActionNoise(np.zeros(n), 0.1 * np.ones(n)))
    model.learn(total_timesteps=steps)
    env.close()
    return lambda obs: model.predict(obs, deterministic=True)[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--env", default="ernest-toy/PointMass-v0", help="Gymnasium id")
    ap.add_argument("--steps", type=int, default=3000, help="transitions collected by each")
    ap.add_argument("--hidden", type=int, default=64, help="hidden units per layer")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    torch.set_num_threads(1)  # small networks: one thread is fastest on a shared machine
    ensure_registered(args.env)

    eval_env = make_env(args.env, None)
    rows = []
    rng = np.random.default_rng(0)
    random_policy = lambda obs: rng.uniform(-1, 1, eval_env.action_space.shape)  # noqa: E731
    for name, train in (("untrained (random actions)", lambda: random_policy),
                        ("ernest_cpp.rl TD3", lambda: train_ours(
                            args.env, args.steps, args.hidden, os.path.join(args.out, "td3_vs_sb3"))),
                        ("Stable-Baselines3 TD3", lambda: train_sb3(args.env, args.steps, args.hidden))):
        t0 = time.perf_counter()
        policy = train()
        seconds = time.perf_counter() - t0
        res = evaluate(policy, eval_env, EVAL_EPISODES, EVAL_SEED)
        rows.append({"learner": name, "steps": 0 if "random" in name else args.steps,
                     "train_s": round(seconds, 2), "mean_return": round(res["return"], 3)})
        print(f"{name:28s}: mean return {res['return']:8.3f} over {EVAL_EPISODES} episodes "
              f"(trained in {seconds:.1f} s)")
    if args.env == "ernest-toy/PointMass-v0":
        from ernest_cpp.rl.toy_envs import optimal_return

        best = []
        for k in range(EVAL_EPISODES):
            eval_env.reset(seed=EVAL_SEED + k)
            best.append(optimal_return(eval_env.unwrapped.x, eval_env.unwrapped.g))
        print(f"{'best possible':28s}: mean return {np.mean(best):8.3f}")
    path = os.path.join(args.out, "td3_vs_sb3.csv")
    with open(path, "w", newline="") as fh:
        units = {"learner": "-", "steps": "transitions", "train_s": "s", "mean_return": "-"}
        w = csv.writer(fh)
        w.writerow([f"{k} [{units[k]}]" for k in rows[0]])  # each header names its unit
        w.writerows([r[k] for k in rows[0]] for r in rows)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
