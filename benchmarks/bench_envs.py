"""Environment throughput: policy steps per second (each 0.5 s of simulation) for one Gymnasium
env and for the C++ vector env on 1 and 2 threads, on the rock field and the slope. Random
actions, medians over repeats. Reference in the same run: the single env (Python step loop).
Target: >= 1000 policy steps per second on 2 cores. Then the batched stepper alone:
rover-steps per second on rocks for 1 and 2 threads, against one process per core.

    ./run bench envs
"""

from __future__ import annotations

import multiprocessing
import os
import platform
import statistics
import time

import gymnasium as gym
import numpy as np

import ernest_cpp.envs as E
from ernest_cpp import dynamics as D
from bench_util import rolling_rover


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


def _rovers(n: int, first: int = 0):
    """Rovers first .. first + n - 1: each drives 0.15 m/s on M90 through its own field of 20
    box rocks (seed 100 + index), rolling after 20 steps; with their start snapshots."""
    sims = []
    for i in range(first, first + n):
        sim = rolling_rover(D.rock_field(20, seed=100 + i), 0.15)
        sim.step_n(20)
        sims.append(sim)
    return sims, [s.snapshot() for s in sims]


def _timed_repeats(batch, sims, starts, chunk: int, steps: int, repeats: int, barrier=None):
    """Seconds of each repeat of `steps` physics steps in calls of `chunk`, every repeat from the
    same start; with a barrier, every repeat starts together with the other process's."""
    times = []
    for _ in range(repeats):
        for s, snap in zip(sims, starts):
            s.restore(snap)
        if barrier is not None:
            barrier.wait()
        t0 = time.perf_counter()
        for _ in range(steps // chunk):
            batch.step(None, chunk)
        times.append(time.perf_counter() - t0)
    return times


def batch_rate(n: int, threads: int, chunk: int, steps: int, repeats: int) -> float:
    """Rover-steps per second of a BatchStepper over n rovers on `threads` threads, `chunk`
    physics steps per call (40 = one policy step); every repeat from the same start."""
    sims, starts = _rovers(n)
    batch = D.BatchStepper(sims, threads)
    return n * steps / statistics.median(_timed_repeats(batch, sims, starts, chunk, steps, repeats))


def _process_half(first, n, chunk, steps, repeats, barrier, out):
    """One process of the process-per-core reference: rovers first .. first + n - 1 on one
    thread, each repeat started together with the other process (barrier)."""
    sims, starts = _rovers(n, first)
    out.put((first, _timed_repeats(D.BatchStepper(sims, 1), sims, starts, chunk, steps, repeats,
                                   barrier)))


def process_rate(n: int, chunk: int, steps: int, repeats: int) -> float:
    """The same n rovers as one process per core (rovers 0 .. n/2 - 1 in one, the rest in the
    other, nothing shared), each repeat started by a barrier in both: rover-steps per second of a
    repeat = n * steps / the slower process's time; median over repeats. Process start-up and
    set-up are outside the timing."""
    ctx = multiprocessing.get_context("spawn")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    half = n // 2
    procs = [ctx.Process(target=_process_half,
                         args=(first, m, chunk, steps, repeats, barrier, out))
             for first, m in ((0, half), (half, n - half))]
    for p in procs:
        p.start()
    results = dict(out.get() for _ in procs)
    for p in procs:
        p.join()
    walls = [max(a, b) for a, b in zip(results[0], results[half])]
    return n * steps / statistics.median(walls)


def batch_scaling(n: int = 8, steps: int = 400, repeats: int = 5):
    """The batched stepper from 1 to 2 threads on rocks, and the reference measured in
    the same run: the same rovers as one process per core (each half of them on one thread)."""
    print(f"\nBatchStepper, {n} rovers on M90 + 20 rocks (RockField-like), {steps} physics steps "
          f"each, medians of {repeats}; load average {os.getloadavg()[0]:.1f}")
    print("| steps per call | 1 thread (rover-steps/s) | 2 threads | speed-up | "
          "2 processes x 1 thread (reference) | speed-up |")
    print("|---|---|---|---|---|---|")
    for chunk in (4, 40):
        r1 = batch_rate(n, 1, chunk, steps, repeats)
        r2 = batch_rate(n, 2, chunk, steps, repeats)
        rp = process_rate(n, chunk, steps, repeats)
        print(f"| {chunk} | {r1:.0f} | {r2:.0f} | **{r2 / r1:.2f}x** | {rp:.0f} | {rp / r1:.2f}x |",
              flush=True)


def schedule_bound(n: int = 8, chunk: int = 4, calls: int = 100):
    """What the thread schedule alone allows, whatever the machine's load: each rover's CPU time
    per call (thread CPU time: preemption by other processes does not count) measured on its own,
    one after the other, then per call the 2-thread makespan of a fixed
    share (rover i on thread i % 2), of handing rovers out in index order to
    whichever thread is free (ThreadPool), and of handing them out costliest first by the last
    call's constraint solves (what BatchStepper does); speed-up bound = total work / makespan summed
    over calls."""
    sims, _ = _rovers(n)
    total = fixed = greedy = longest = 0.0
    cost = [0] * n  # constraint solves of each rover in the last call (BatchStepper's order)

    def makespan(order, t):
        free = [0.0, 0.0]
        for i in order:
            k = free.index(min(free))
            free[k] += t[i]
        return max(free)

    for _ in range(calls):
        t, order = [], sorted(range(n), key=lambda i: (-cost[i], i))
        for i, sim in enumerate(sims):
            s0 = sim.solver_stats.sparse_solves + sim.solver_stats.dense_solves
            t0 = time.thread_time()
            sim.step_n(chunk)
            t.append(time.thread_time() - t0)
            cost[i] = sim.solver_stats.sparse_solves + sim.solver_stats.dense_solves - s0
        total += sum(t)
        fixed += max(sum(t[0::2]), sum(t[1::2]))
        greedy += makespan(range(n), t)
        longest += makespan(order, t)
    print(f"\nschedule bound, {n} rovers on rocks, {chunk} steps per call, {calls} calls: fixed "
          f"share {total / fixed:.2f}x, dynamic in index order {total / greedy:.2f}x, dynamic "
          f"longest first (by the last call's solves, BatchStepper) {total / longest:.2f}x "
          f"(2 threads, perfect cores)")


def main():
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}")
    print("| scenario | single env (steps/s) | vector 8 envs, 1 thread | vector 8 envs, 2 threads | "
          "2 threads / 1 thread | 2 threads / single |")
    print("|---|---|---|---|---|---|")
    for env_id in ("ernest/RockField-v0", "ernest/Slope-v0"):
        s = single_rate(env_id, 200, 5)
        v1 = vector_rate(env_id, 8, 1, 40, 5)
        v2 = vector_rate(env_id, 8, 2, 40, 5)
        print(f"| {env_id} | {s:.0f} | {v1:.0f} | {v2:.0f} | {v2 / v1:.2f}x | {v2 / s:.2f}x |",
              flush=True)
    print("target: >= 1000 policy steps per second on 2 cores")
    batch_scaling()
    schedule_bound(chunk=4)
    schedule_bound(chunk=40, calls=20)


if __name__ == "__main__":
    main()
