"""Consolidation speed (seed 004 §4.6, Table 4): TD3 iterations with minibatch 512, lr 1e-3, the
paper's 2×512 networks, on a synthetic pooled buffer of 45-value observations and 3-value actions
with FTS noise injection on sampling, on N CPU threads (default 2). Target: 1e4 iterations ≤ 15 min.

By default it measures ``--iterations`` (300) iterations ``--repeats`` (3) times after a warm-up and
EXTRAPOLATES the median to 1e4 iterations; ``--iterations 10000 --repeats 1`` measures the full run.
The reference measured in the same run is the dense-matmul floor: the time the iteration's matrix
products (counted analytically) would take at the GEMM rate measured here on 512×512×512 products.

    python benchmarks/bench_consolidation.py [--pool 4000000] [--threads 2] [--iterations 300]

OMP_WAIT_POLICY defaults to PASSIVE as in the ``ernest`` commands; run with OMP_WAIT_POLICY=ACTIVE
to see what spinning OpenMP threads cost on a shared machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

# As `ernest consolidate` does (rl/commands.py): idle OpenMP threads sleep rather than spin.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from ernest_cpp.rl import layout as L  # noqa: E402
from ernest_cpp.rl.replay import ReplayBuffer  # noqa: E402
from ernest_cpp.rl.td3 import TD3, TD3Config  # noqa: E402

FULL_ITERATIONS = 10_000  # Table 4
TARGET_S = 15 * 60  # SPEC performance bar


def synthetic_pool(n: int, obs_dim: int, act_dim: int, seed: int = 0) -> ReplayBuffer:
    buf = ReplayBuffer(n, obs_dim, act_dim)
    rng = np.random.default_rng(seed)
    chunk = 1 << 18
    for start in range(0, n, chunk):
        k = min(chunk, n - start)
        buf.add(rng.standard_normal((k, obs_dim), dtype=np.float32),
                rng.uniform(-1, 1, (k, act_dim)).astype(np.float32),
                rng.standard_normal(k, dtype=np.float32),
                rng.standard_normal((k, obs_dim), dtype=np.float32),
                (rng.random(k) < 0.01).astype(np.float32))
    idx, std = L.paper_layout().noise_std_normalised()
    buf.set_noise(idx, std)
    return buf


def iteration_flops(b: int, ns: int, na: int, h: int, delay: int) -> float:
    """Matrix-product FLOPs of one TD3 iteration (forward = 2·B·Σ in·out; backward ≈ 2× forward)."""
    actor = 2 * b * (ns * h + h * h + h * na)
    critic = 2 * b * ((ns + na) * h + (h + na) * h + h)
    target = actor + 2 * critic  # target policy + both target critics
    critic_step = 2 * critic * 3  # both critics forward + backward
    actor_step = actor * 3 + critic * 2  # actor fwd+bwd, Q1 fwd + input-gradient pass
    return target + critic_step + actor_step / delay


def gemm_rate(threads: int, repeats: int = 20) -> float:
    a, b = torch.randn(512, 512), torch.randn(512, 512)
    for _ in range(5):
        a @ b
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(10):
            a @ b
        times.append((time.perf_counter() - t) / 10)
    return 2 * 512 ** 3 / statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pool", type=int, default=4_000_000, help="pooled transitions (Table 4: 4e6)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--iterations", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--warmup", type=int, default=20)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    t = time.perf_counter()
    pool = synthetic_pool(args.pool, 45, 3)
    print(f"synthetic pool: {len(pool)} transitions of 45/3 values "
          f"({(pool.obs.nbytes * 2 + pool.act.nbytes) / 2**30:.2f} GiB) in "
          f"{time.perf_counter() - t:.1f} s; torch threads {torch.get_num_threads()}, "
          f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY')}")
    cfg = TD3Config(batch_size=512, actor_lr=1e-3, critic_lr=1e-3, hidden=512)
    agent = TD3(45, 3, cfg, seed=0)
    rng = np.random.default_rng(1)
    for _ in range(args.warmup):
        agent.update(pool.sample(cfg.batch_size, rng))
    per_iter, sample_share = [], []
    for _ in range(args.repeats):
        ts = 0.0
        t0 = time.perf_counter()
        for _ in range(args.iterations):
            t1 = time.perf_counter()
            batch = pool.sample(cfg.batch_size, rng)
            ts += time.perf_counter() - t1
            agent.update(batch)
        dt = time.perf_counter() - t0
        per_iter.append(dt / args.iterations)
        sample_share.append(ts / dt)
    med = statistics.median(per_iter)
    full = med * FULL_ITERATIONS
    rate = gemm_rate(args.threads)
    floor = iteration_flops(512, 45, 3, 512, cfg.policy_delay) / rate
    kind = "measured" if args.iterations >= FULL_ITERATIONS else (
        f"EXTRAPOLATED from {args.repeats}×{args.iterations} iterations")
    print(f"per iteration: median {med * 1e3:.1f} ms over {args.repeats} repeats "
          f"(min {min(per_iter) * 1e3:.1f}, max {max(per_iter) * 1e3:.1f}); sampling + noise "
          f"{100 * statistics.median(sample_share):.0f} % of it")
    print(f"reference (same run): GEMM {rate / 1e9:.1f} GFLOP/s -> matmul floor "
          f"{floor * 1e3:.1f} ms/iteration; ratio to floor {med / floor:.2f}")
    print(f"load average during the run (other processes share the cores): "
          f"{os.getloadavg()[0]:.2f}")
    print(f"1e4 iterations, minibatch 512: {full / 60:.1f} min ({kind}); target ≤ 15 min: "
          f"{'OK' if full <= TARGET_S else 'MISSED'} (ratio to target {full / TARGET_S:.2f})")


if __name__ == "__main__":
    main()
