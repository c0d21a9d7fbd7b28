"""Ray backend throughput: environment steps per second collected on the rock field by
the local trainer (its vector env on one thread, one core) and by ``--backend ray`` with 1 and 2
rollout workers, and the Ray path's overhead per transition. Reference in the same run: the local
trainer. Policy actions with the §4.4 exploration (random_steps 0), no learning (the collection
rate), interleaved repeats, medians.

Overhead per transition of the Ray path: 1/rate(Ray) - 1/rate(local) in wall time (medians of
the paired repeats), against a policy step = 1/rate(local) (simulation, actor, exploration,
replay), both with 4 simulations in one simulation process; and the same in CPU time (driver and
worker processes, from /proc). Both only mean something on an idle machine: under load, more
processes get more time slices (the script prints the load average).
Targets: Ray 2 workers >= 1.7x local; overhead <= 10 % of a policy step.

    ./run bench ray [--steps 640] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import tempfile
import time

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # as `ernest train` (commands.py)

import ray  # noqa: E402
import torch  # noqa: E402

from ernest_cpp.rl.config import build_config  # noqa: E402
from ernest_cpp.rl.ray_trainer import RayTrainer  # noqa: E402
from ernest_cpp.rl.trainer import Trainer  # noqa: E402

ENVS = 4  # simulations per process (the local trainer's vector env, each Ray worker's)


def config(workers: int, mode: str) -> dict:
    sets = ["env.scenario=rockfield", f"env.num_envs={ENVS * workers}", "env.threads=1",
            "random_steps=0", "learning_starts=1000000000", "eval.every_steps=0",
            "checkpoint.every_steps=0", "log.progress_bar=false", "log.tensorboard=false",
            "buffer_size=50000", f"ray.num_workers={workers}", f"ray.envs_per_worker={ENVS}",
            f"ray.mode={mode}", "ray.collect_steps=8"]
    return build_config("quick", None, sets)


TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process, all its threads (Linux /proc)."""
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def rate(tr: Trainer, steps: int) -> tuple[float, float]:
    """(transitions per wall second, CPU seconds per transition) of one stretch of collection."""
    pids = [os.getpid()] + (tr.vec.pids() if isinstance(tr, RayTrainer) else [])
    c0 = sum(cpu_seconds(p) for p in pids)
    s0, t0 = tr.step, time.perf_counter()
    tr.train(total_steps=tr.step + steps)
    n = tr.step - s0
    return n / (time.perf_counter() - t0), (sum(cpu_seconds(p) for p in pids) - c0) / n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=640)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    torch.set_num_threads(1)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}")
    # Logical CPUs only: the idle trainers' workers wait without using a core.
    ray.init(address="local", num_cpus=6, include_dashboard=False, object_store_memory=200 << 20,
             log_to_driver=False, configure_logging=False)
    tmp = tempfile.mkdtemp(prefix="bench_ray_")
    variants = {"local (1 core)": (Trainer, config(1, "sync")),
                "Ray sync, 1 worker": (RayTrainer, config(1, "sync")),
                "Ray async, 1 worker": (RayTrainer, config(1, "async")),
                "Ray async, 2 workers": (RayTrainer, config(2, "async"))}
    trainers = {}
    for name, (cls, cfg) in variants.items():
        tr = cls(cfg, os.path.join(tmp, str(len(trainers))), log=lambda *a: None)
        tr._checkpoint_and_cut = tr._reset_envs  # time the collection, not checkpoint writing
        rate(tr, ENVS * 8 * 2)  # warm-up: actors built, first batches through
        trainers[name] = tr
    rates = {name: [] for name in trainers}
    cpus = {name: [] for name in trainers}
    for _ in range(args.repeats):
        for name, tr in trainers.items():
            r, c = rate(tr, args.steps)
            rates[name].append(r)
            cpus[name].append(c)
    med = {name: statistics.median(r) for name, r in rates.items()}
    cpu = {name: statistics.median(c) * 1e6 for name, c in cpus.items()}
    loc = med["local (1 core)"]
    print(f"\n{args.steps} transitions per repeat, {args.repeats} repeats interleaved, medians; "
          f"{ENVS} simulations per process")
    print("| collector | env steps/s (wall) | / local | overhead per transition (wall) | "
          "CPU us per transition | overhead (CPU) |")
    print("|---|---|---|---|---|---|")
    step_us, step_cpu = 1e6 / loc, cpu["local (1 core)"]
    for name, v in med.items():
        over = statistics.median([1e6 / a - 1e6 / b for a, b in
                                  zip(rates[name], rates["local (1 core)"])])
        oc = cpu[name] - step_cpu
        print(f"| {name} | {v:.0f} | {v / loc:.2f}x | {over:+.0f} us = "
              f"{100 * over / step_us:+.1f} % | {cpu[name]:.0f} | {oc:+.0f} us = "
              f"{100 * oc / step_cpu:+.1f} % |")
    print(f"Ray async 2 workers / local: {med['Ray async, 2 workers'] / loc:.2f}x (target 1.7x)")
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    for tr in trainers.values():
        tr.close()
    ray.shutdown()
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
