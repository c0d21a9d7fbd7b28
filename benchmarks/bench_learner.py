"""One TD3 update (seed 004 §4.1, Tables 4–5): critic every update, actor and Polyak targets every
second one, with the paper's networks (45 -> 2×512 -> 3, the critic re-receiving the action at its
second layer), minibatch 128 (specialists) and 512 (consolidation), on 1 and 2 torch threads; hidden
256 for the width of specialists. Side by side in the same run, interleaved block by block:

* ``baseline``: the update as ``rl.td3`` did it before its learner optimisations (a frozen copy in
  this file: two ``Critic`` modules, Adam's per-tensor loop, a per-tensor Polyak loop);
* ``ours``: ``ernest_cpp.rl.td3.TD3.update`` (fused Adam, ``_foreach_lerp_`` soft updates);
* ``sb3``: Stable-Baselines3's TD3 (``net_arch`` [h, h], same batch size, policy delay 2, target
  noise 0.05 clipped at 0.2), timed on ``model.train(gradient_steps=N)`` with a filled buffer. Its
  critic takes the action at the first layer only (3 fewer inputs at layer 2, ~0.3 % fewer FLOPs);
* ``minimal``: a one-file PyTorch TD3 in the style of Fujimoto et al.'s reference code (both Q heads
  in one module, plain Adam, Polyak loop), with our architecture.

Every update samples its minibatch from a filled buffer (ours, baseline and minimal from one numpy
buffer; SB3 from its own). Times are medians over ``--blocks`` blocks of updates after a warm-up;
ratios are medians of the per-block ratios (each block times all implementations back to back, so a
load change on a shared machine hits them alike). ``cpu/base`` is the same ratio on the process's
CPU time (``time.process_time``): on one thread it does not count the time other processes hold
the core, so it is the steadier figure on a loaded machine.

``--ablation`` adds each candidate alone on top of the baseline: a fused twin critic (both critics'
weights stacked in one module, one product per critic and layer; not kept), the same evaluated with
one batched product per layer for both critics (``baddbmm``; not kept), fused Adam, foreach Polyak
(both kept); and fused critic + fused Adam + foreach Polyak together. ``--processes`` compares the
throughput of 2 intra-op threads in one process with 2 processes of one thread each (how
specialists train side by side).

    python benchmarks/bench_learner.py [--quick] [--ablation] [--processes]

Prints a table and writes nothing.
"""

from __future__ import annotations

import argparse
import copy
import multiprocessing as mp
import os
import statistics
import time

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # as the `ernest` commands

import numpy as np  # noqa: E402
import torch  # noqa: E402
import torch.nn.functional as F  # noqa: E402
from torch import nn  # noqa: E402

from ernest_cpp.rl.networks import Actor, TwinCritic  # noqa: E402
from ernest_cpp.rl.td3 import TD3, TD3Config  # noqa: E402

OBS, ACT = 45, 3
LR = 3e-4
BUFFER = 20_000


# ------------------------------------------------------------------------------ implementations
class StackedTwinCritic(nn.Module):
    """Both critics in one module, measured and not kept: layer k of critic i is
    ``x @ w{k}[i] + b{k}[i]`` with ``w1`` [2, n, h], ``w2`` [2, h + act, h], ``w3`` [2, h, 1]
    (6 tensors for Adam and Polyak instead of 12), one product per critic and layer on views of the
    stacked weights; initialised from a ``TwinCritic`` (same draws)."""

    NAMES = ("w1", "b1", "w2", "b2", "w3", "b3")

    def __init__(self, obs_dim, act_dim, hidden):
        super().__init__()
        tw = TwinCritic(obs_dim, act_dim, hidden)
        for k in (1, 2, 3):
            ls = [getattr(c, f"l{k}") for c in (tw.q1, tw.q2)]
            self.register_parameter(f"w{k}", nn.Parameter(
                torch.stack([m.weight.detach().t() for m in ls]).contiguous()))
            self.register_parameter(f"b{k}", nn.Parameter(
                torch.stack([m.bias.detach().unsqueeze(0) for m in ls])))

    @staticmethod
    def _q(x, act, w1, b1, w2, b2, w3, b3):
        h = torch.relu(torch.addmm(b1, x, w1))
        h = torch.relu(torch.addmm(b2, torch.cat([h, act], dim=-1), w2))
        return torch.addmm(b3, h, w3).squeeze(-1)

    def forward(self, obs, act):
        x = torch.cat([obs, act], dim=-1)
        q1, q2 = (self._q(x, act, *w) for w in zip(*(getattr(self, n).unbind(0)
                                                     for n in self.NAMES)))
        return q1, q2

    def q1(self, obs, act):
        return self._q(torch.cat([obs, act], dim=-1), act,
                       *(getattr(self, n)[0] for n in self.NAMES))


class BatchedTwinCritic(StackedTwinCritic):
    """The stacked critic evaluated with one batched product per layer for both critics
    (``torch.baddbmm``): measured and not kept."""

    def forward(self, obs, act):
        x = torch.cat([obs, act], dim=-1)
        h = torch.relu(torch.baddbmm(self.b1, x.expand(2, *x.shape), self.w1))
        h = torch.relu(torch.baddbmm(self.b2, torch.cat([h, act.expand(2, *act.shape)], dim=-1),
                                     self.w2))
        q = torch.baddbmm(self.b3, h, self.w3).squeeze(-1)
        return q[0], q[1]


class BaselineTD3:
    """``rl.td3.TD3.update`` without the fused optimisations (torch's defaults); each flag switches on one of
    the optimisations, so that their effect is measured one at a time."""

    def __init__(self, cfg: TD3Config, seed: int = 0, fused_critic=False, fused_adam=False,
                 foreach_polyak=False, batched_critic=False):
        self.c = cfg
        self.gen = torch.Generator().manual_seed(seed)
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.actor = Actor(OBS, ACT, cfg.hidden)
            critic = (BatchedTwinCritic if batched_critic else StackedTwinCritic if fused_critic
                      else TwinCritic)
            self.critic = critic(OBS, ACT, cfg.hidden)
        self.fused_critic = fused_critic or batched_critic
        self.foreach_polyak = foreach_polyak
        self.actor_target = copy.deepcopy(self.actor).requires_grad_(False)
        self.critic_target = copy.deepcopy(self.critic).requires_grad_(False)
        kw = {"fused": True} if fused_adam else {}
        self.actor_opt = torch.optim.Adam(self.actor.parameters(), lr=cfg.actor_lr, **kw)
        self.critic_opt = torch.optim.Adam(self.critic.parameters(), lr=cfg.critic_lr, **kw)
        self.updates = 0

    def update(self, batch: dict) -> dict:
        c = self.c
        obs, act, rew, next_obs, done = (torch.from_numpy(batch[k]) for k in
                                         ("obs", "act", "rew", "next_obs", "done"))
        with torch.no_grad():
            eps = (torch.randn(act.shape, generator=self.gen) * c.target_noise)
            eps = eps.clamp(-c.target_noise_clip, c.target_noise_clip)
            next_act = (self.actor_target(next_obs) + eps).clamp(-1.0, 1.0)
            tq1, tq2 = self.critic_target(next_obs, next_act)
            target = rew + c.gamma * (1.0 - done) * torch.min(tq1, tq2)
        q1, q2 = self.critic(obs, act)
        critic_loss = F.mse_loss(q1, target) + F.mse_loss(q2, target)
        self.critic_opt.zero_grad(set_to_none=True)
        critic_loss.backward()
        self.critic_opt.step()
        self.updates += 1
        info = {"critic_loss": critic_loss.item(), "q1": q1.mean().item(),
                "q_target": target.mean().item()}
        if self.updates % c.policy_delay == 0:
            q1_params = list(self.critic.parameters() if self.fused_critic
                             else self.critic.q1.parameters())
            for p in q1_params:
                p.requires_grad_(False)
            actor_loss = -self.critic.q1(obs, self.actor(obs)).mean()
            self.actor_opt.zero_grad(set_to_none=True)
            actor_loss.backward()
            for p in q1_params:
                p.requires_grad_(True)
            self.actor_opt.step()
            self._soft_update()
            info["actor_loss"] = actor_loss.item()
        return info

    @torch.no_grad()
    def _soft_update(self):
        tau = self.c.tau
        pairs = [(p, tp) for net, tgt in ((self.actor, self.actor_target),
                                          (self.critic, self.critic_target))
                 for p, tp in zip(net.parameters(), tgt.parameters())]
        if self.foreach_polyak:
            torch._foreach_lerp_([tp for _, tp in pairs], [p for p, _ in pairs], tau)
        else:
            for p, tp in pairs:
                tp.mul_(1.0 - tau).add_(p, alpha=tau)


class MinimalTD3:
    """A minimal one-file TD3 (Fujimoto et al.'s reference layout) with our networks."""

    class Actor(nn.Module):
        def __init__(self, h):
            super().__init__()
            self.l1, self.l2, self.l3 = nn.Linear(OBS, h), nn.Linear(h, h), nn.Linear(h, ACT)

        def forward(self, s):
            return torch.tanh(self.l3(F.relu(self.l2(F.relu(self.l1(s))))))

    class Critic(nn.Module):
        def __init__(self, h):
            super().__init__()
            self.l1, self.l2, self.l3 = nn.Linear(OBS + ACT, h), nn.Linear(h + ACT, h), nn.Linear(h, 1)
            self.l4, self.l5, self.l6 = nn.Linear(OBS + ACT, h), nn.Linear(h + ACT, h), nn.Linear(h, 1)

        def forward(self, s, a):
            sa = torch.cat([s, a], 1)
            q1 = self.l3(F.relu(self.l2(torch.cat([F.relu(self.l1(sa)), a], 1))))
            q2 = self.l6(F.relu(self.l5(torch.cat([F.relu(self.l4(sa)), a], 1))))
            return q1, q2

        def Q1(self, s, a):
            sa = torch.cat([s, a], 1)
            return self.l3(F.relu(self.l2(torch.cat([F.relu(self.l1(sa)), a], 1))))

    def __init__(self, cfg: TD3Config):
        self.c = cfg
        self.actor = self.Actor(cfg.hidden)
        self.actor_target = copy.deepcopy(self.actor)
        self.actor_optimizer = torch.optim.Adam(self.actor.parameters(), lr=cfg.actor_lr)
        self.critic = self.Critic(cfg.hidden)
        self.critic_target = copy.deepcopy(self.critic)
        self.critic_optimizer = torch.optim.Adam(self.critic.parameters(), lr=cfg.critic_lr)
        self.total_it = 0

    def update(self, batch):
        c = self.c
        self.total_it += 1
        state, action, next_state = (torch.from_numpy(batch[k]) for k in ("obs", "act", "next_obs"))
        reward = torch.from_numpy(batch["rew"]).unsqueeze(1)
        not_done = 1.0 - torch.from_numpy(batch["done"]).unsqueeze(1)
        with torch.no_grad():
            noise = (torch.randn_like(action) * c.target_noise).clamp(-c.target_noise_clip,
                                                                       c.target_noise_clip)
            next_action = (self.actor_target(next_state) + noise).clamp(-1, 1)
            target_q1, target_q2 = self.critic_target(next_state, next_action)
            target_q = reward + not_done * c.gamma * torch.min(target_q1, target_q2)
        current_q1, current_q2 = self.critic(state, action)
        critic_loss = F.mse_loss(current_q1, target_q) + F.mse_loss(current_q2, target_q)
        self.critic_optimizer.zero_grad()
        critic_loss.backward()
        self.critic_optimizer.step()
        if self.total_it % c.policy_delay == 0:
            actor_loss = -self.critic.Q1(state, self.actor(state)).mean()
            self.actor_optimizer.zero_grad()
            actor_loss.backward()
            self.actor_optimizer.step()
            for param, target_param in zip(self.critic.parameters(), self.critic_target.parameters()):
                target_param.data.copy_(c.tau * param.data + (1 - c.tau) * target_param.data)
            for param, target_param in zip(self.actor.parameters(), self.actor_target.parameters()):
                target_param.data.copy_(c.tau * param.data + (1 - c.tau) * target_param.data)


def make_sb3(cfg: TD3Config, data: dict):
    """SB3's TD3 with the same sizes and a buffer filled with ``data``; None if not installed."""
    try:
        import gymnasium as gym
        from stable_baselines3 import TD3 as SB3TD3
        from stable_baselines3.common.logger import configure
    except ImportError:
        return None

    class Dummy(gym.Env):
        observation_space = gym.spaces.Box(-np.inf, np.inf, (OBS,), np.float32)
        action_space = gym.spaces.Box(-1.0, 1.0, (ACT,), np.float32)

    model = SB3TD3("MlpPolicy", Dummy(), learning_rate=LR, buffer_size=BUFFER, learning_starts=0,
                   batch_size=cfg.batch_size, tau=cfg.tau, gamma=cfg.gamma,
                   policy_delay=cfg.policy_delay, target_policy_noise=cfg.target_noise,
                   target_noise_clip=cfg.target_noise_clip,
                   policy_kwargs={"net_arch": [cfg.hidden, cfg.hidden]}, device="cpu", seed=0,
                   verbose=0)
    model.set_logger(configure(None, []))
    rb, n = model.replay_buffer, len(data["obs"])
    rb.observations[:n, 0] = data["obs"]
    rb.next_observations[:n, 0] = data["next_obs"]
    rb.actions[:n, 0] = data["act"]
    rb.rewards[:n, 0] = data["rew"]
    rb.dones[:n, 0] = data["done"]
    rb.pos, rb.full = 0, True
    return model


# ------------------------------------------------------------------------------------- timing
def filled_data(n: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    return {"obs": rng.standard_normal((n, OBS), dtype=np.float32),
            "act": rng.uniform(-1, 1, (n, ACT)).astype(np.float32),
            "rew": rng.standard_normal(n, dtype=np.float32),
            "next_obs": rng.standard_normal((n, OBS), dtype=np.float32),
            "done": (rng.random(n) < 0.01).astype(np.float32)}


def sampler(data: dict, batch: int, seed: int = 1):
    rng, n = np.random.default_rng(seed), len(data["obs"])

    def sample():
        idx = rng.integers(0, n, batch)
        return {k: v[idx] for k, v in data.items()}
    return sample


def implementations(hidden: int, batch: int, ablation: bool) -> dict:
    """name -> fn(n): n updates."""
    cfg = TD3Config(batch_size=batch, hidden=hidden, actor_lr=LR, critic_lr=LR).validate()
    data = filled_data(BUFFER)
    out = {}

    def loop(agent):
        sample = sampler(data, batch)

        def run(n):
            for _ in range(n):
                agent.update(sample())
        return run
    out["baseline"] = loop(BaselineTD3(cfg))
    out["ours"] = loop(TD3(OBS, ACT, cfg, seed=0))
    sb3 = make_sb3(cfg, data)
    if sb3 is not None:
        out["sb3"] = lambda n: sb3.train(gradient_steps=n, batch_size=batch)
    out["minimal"] = loop(MinimalTD3(cfg))
    if ablation:
        for name, kw in (("+fused critic", {"fused_critic": True}),
                         ("+batched critic", {"batched_critic": True}),
                         ("+fused Adam", {"fused_adam": True}),
                         ("+foreach Polyak", {"foreach_polyak": True}),
                         ("+all three", {"fused_critic": True, "fused_adam": True,
                                         "foreach_polyak": True})):
            out[name] = loop(BaselineTD3(cfg, **kw))
    return out


def time_case(threads: int, hidden: int, batch: int, blocks: int, per_block: int, warmup: int,
              ablation: bool) -> dict:
    torch.set_num_threads(threads)
    impls = implementations(hidden, batch, ablation)
    for fn in impls.values():
        fn(warmup)
    times, cpu = {k: [] for k in impls}, {k: [] for k in impls}
    for _ in range(blocks):
        for k, fn in impls.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn(per_block)
            times[k].append((time.perf_counter() - t0) / per_block * 1e3)
            cpu[k].append((time.process_time() - c0) / per_block * 1e3)
    return times, cpu


def fmt_case(threads, hidden, batch, times, cpu) -> list[str]:
    med = {k: statistics.median(v) for k, v in times.items()}

    def ratio(a, b, t=times):
        return statistics.median(x / y for x, y in zip(t[a], t[b]))
    rows = []
    for k, v in times.items():
        r = [f"{ratio(k, ref):6.2f}" if ref in times else "     -" for ref in
             ("baseline", "sb3", "minimal")]
        rows.append(f"{threads:>3} {hidden:>6} {batch:>5}  {k:<16} {med[k]:8.2f} {min(v):8.2f} "
                    f"{max(v):8.2f}  {'  '.join(r)}   {ratio(k, 'baseline', cpu):8.2f}   "
                    f"{1e3 / med[k]:7.1f}")
    return rows


# ------------------------------------------------------------------- processes vs intra-op threads
def _proc_worker(hidden, batch, n, barrier, q):
    torch.set_num_threads(1)
    cfg = TD3Config(batch_size=batch, hidden=hidden, actor_lr=LR, critic_lr=LR)
    agent, sample = TD3(OBS, ACT, cfg, seed=0), sampler(filled_data(BUFFER), batch)
    for _ in range(10):
        agent.update(sample())
    barrier.wait()
    t0 = time.perf_counter()
    for _ in range(n):
        agent.update(sample())
    q.put(time.perf_counter() - t0)


def processes_vs_threads(hidden, batch, n) -> list[str]:
    """Updates/s of 1 process x 1 thread, 1 process x 2 threads, 2 processes x 1 thread (sum)."""
    rows = []
    for threads in (1, 2):
        torch.set_num_threads(threads)
        cfg = TD3Config(batch_size=batch, hidden=hidden, actor_lr=LR, critic_lr=LR)
        agent, sample = TD3(OBS, ACT, cfg, seed=0), sampler(filled_data(BUFFER), batch)
        for _ in range(10):
            agent.update(sample())
        t0 = time.perf_counter()
        for _ in range(n):
            agent.update(sample())
        rows.append((f"1 process x {threads} thread{'s' if threads > 1 else ''}",
                     n / (time.perf_counter() - t0)))
    ctx = mp.get_context("spawn")
    barrier, q = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_proc_worker, args=(hidden, batch, n, barrier, q)) for _ in range(2)]
    for p in procs:
        p.start()
    dts = [q.get() for _ in procs]
    for p in procs:
        p.join()
    rows.append(("2 processes x 1 thread", sum(n / dt for dt in dts)))
    one = rows[0][1]
    return [f"  {name:<26} {rate:7.1f} updates/s  ({rate / one:.2f}x one thread)"
            for name, rate in rows]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a tiny run (seconds): 3 blocks of 3")
    ap.add_argument("--ablation", action="store_true",
                    help="also each optimisation alone on top of the baseline")
    ap.add_argument("--processes", action="store_true",
                    help="also 2 processes x 1 thread against 1 process x 2 threads")
    ap.add_argument("--blocks", type=int, default=7)
    ap.add_argument("--threads", default="1,2")
    args = ap.parse_args()
    if args.blocks < 1:
        raise SystemExit(f"--blocks = {args.blocks}: give a whole number >= 1")
    threads = [int(t) for t in args.threads.split(",")]
    cases = [(512, 128), (512, 512), (256, 128), (256, 512)]
    blocks, warmup = (3, 2) if args.quick else (args.blocks, 10)
    print(f"TD3 update, {OBS} -> h x h -> {ACT}, policy delay 2; ms per update: median, min, max "
          f"over {blocks} blocks; ratio = median of per-block ratios (ours / reference: < 1 is "
          f"faster). OMP_WAIT_POLICY={os.environ['OMP_WAIT_POLICY']}, cores {os.cpu_count()}")
    print(f"{'thr':>3} {'hidden':>6} {'batch':>5}  {'implementation':<16} {'ms':>8} {'min':>8} "
          f"{'max':>8}  {'/base':>6}  {'/sb3':>6}  {'/min':>6}   {'cpu/base':>8}   {'upd/s':>7}")
    have_sb3 = True
    for t in threads:
        for hidden, batch in cases:
            per_block = 3 if args.quick else max(4, int(20 * 128 / batch * (512 / hidden) ** 2))
            times, cpu = time_case(t, hidden, batch, blocks, per_block, warmup,
                                   args.ablation and (hidden, batch) in ((512, 128), (512, 512)))
            have_sb3 = "sb3" in times
            for row in fmt_case(t, hidden, batch, times, cpu):
                print(row, flush=True)
    if not have_sb3:
        print("stable-baselines3: not installed (pip install stable-baselines3)")
    if args.processes:
        n = 20 if args.quick else 200
        print(f"throughput of ours, hidden 512, minibatch 128, {n} updates each:")
        for row in processes_vs_threads(512, 128, n):
            print(row, flush=True)
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
