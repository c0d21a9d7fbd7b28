"""Environment throughput: policy steps per second (each 0.5 s of simulation) for one Gymnasium
env and for the C++ vector env on 1 and 2 threads, on the rock field and the slope. Random
actions, medians over repeats. Reference in the same run: the single env (Python step loop).
Target (issue 5): >= 1000 policy steps per second on 2 cores.

    ./run bench envs
"""

from __future__ import annotations

import os
import platform
import statistics
import time

import gymnasium as gym
import numpy as np

import ernest_cpp.envs as E


def single_rate(env_id: str, steps: int, repeats: int) -> float:
    env = gym.make(env_id)
    rng = np.random.default_rng(0)
    rates = []
    for r in range(repeats):
        env.reset(seed=r)
        t0 = time.perf_counter()
        for _ in range(steps):
            _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, 3))
            if term or trunc:
                env.reset()
        rates.append(steps / (time.perf_counter() - t0))
    return statistics.median(rates)


def vector_rate(env_id: str, num_envs: int, threads: int, steps: int, repeats: int) -> float:
    vec = E.make_vec(env_id, num_envs, num_threads=threads)
    rng = np.random.default_rng(0)
    rates = []
    for r in range(repeats):
        vec.reset(seed=100 * r)
        t0 = time.perf_counter()
        for _ in range(steps):
            vec.step(rng.uniform(-1, 1, (num_envs, 3)))
        rates.append(steps * num_envs / (time.perf_counter() - t0))
    return statistics.median(rates)


def main():
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}")
    print("| scenario | single env (steps/s) | vector 8 envs, 1 thread | vector 8 envs, 2 threads | "
          "2 threads / single |")
    print("|---|---|---|---|---|")
    for env_id in ("ernest/RockField-v0", "ernest/Slope-v0"):
        s = single_rate(env_id, 200, 5)
        v1 = vector_rate(env_id, 8, 1, 40, 5)
        v2 = vector_rate(env_id, 8, 2, 40, 5)
        print(f"| {env_id} | {s:.0f} | {v1:.0f} | {v2:.0f} | {v2 / s:.2f}x |", flush=True)
    print("target: >= 1000 policy steps per second on 2 cores")


if __name__ == "__main__":
    main()
