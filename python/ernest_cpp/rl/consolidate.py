"""Policy consolidation (seed 004 §4.6, Table 4).

The most recent ``per_run`` (1e6) transitions of each specialist's replay buffer are pooled
(buffer 4e6 for four specialists) and a freshly initialised actor–critic pair is trained on this pool
alone, with the same TD3 algorithm but minibatch 512, learning rate 1e-3 and 1e4 iterations. FTS noise
is still injected on sampling (it is part of the learning algorithm, §4.2). No simulation is run while
training; afterwards the consolidated actor and every specialist are evaluated on every specialist's
environment and the results written as a table.
"""

from __future__ import annotations

import csv
import json
import os
import time

import numpy as np
import torch

from . import layout as L
from .._csv import header as csv_header
from ..sensing import RewardWeights as _RewardWeights
from .replay import ReplayBuffer
from .storage import AtomicDir
from .td3 import TD3, TD3Config, resolve_device
from .checkpoints import agent_from_checkpoint, find_checkpoint, load_checkpoint
from .envs_util import evaluate, make_env, noise_for


DEFAULT_W_DELTA = _RewardWeights().w_delta  # eq 38's lateral weight where no env set another


def relabel_lateral(buf: ReplayBuffer, index: int, scale: float, w_from: float,
                    w_to: float) -> None:
    """Re-weights eq 38's lateral term of every stored reward from ``w_from`` to ``w_to``, exactly:
    δ is the stored next observation's ``lateral_deviation`` (entry ``index``, normalised by
    ``scale``, never clipped), and the other terms do not depend on the weight."""
    n = buf.size
    d = buf.next_obs[:n, index].astype(np.float64) * float(scale)
    buf.rew[:n] -= ((float(w_to) - float(w_from)) * d * d).astype(np.float32)


def pool_buffers(sources: list, per_run: int, capacity: int | None = None,
                 relabel=None) -> ReplayBuffer:
    """Most recent ``per_run`` transitions of each buffer (ReplayBuffer or saved folder), pooled.
    ``relabel(i, part)``, if given, may change source i's part in place before pooling."""
    parts = []
    for i, s in enumerate(sources):
        buf = s if isinstance(s, ReplayBuffer) else ReplayBuffer.load(s)
        parts.append(buf.last_n(per_run))
        if relabel is not None:
            relabel(i, parts[-1])
    total = sum(len(p) for p in parts)
    if capacity is not None and total > capacity:
        raise ValueError(f"consolidate: pooled {total} transitions exceed buffer_size {capacity}")
    return ReplayBuffer.merge(parts)  # sized to what was pooled (the pool never grows)


def train_on_buffer(buffer: ReplayBuffer, td3_cfg: TD3Config, iterations: int, seed: int = 0,
                    progress=None, device: str = "cpu", snapshot=None,
                    init: dict | None = None, anchor: float = 0.0,
                    anchor_mask: np.ndarray | None = None) -> tuple[TD3, dict]:
    """TD3 trained for ``iterations`` updates on ``buffer`` alone (no environment), its
    networks on ``device`` (a torch device, e.g. ``resolve_device("auto")``): fresh (§4.6), or
    continued from ``init`` (a ``TD3.state_dict()``; networks, targets and Adam moments, at
    ``td3_cfg``'s learning rates; with ``anchor`` > 0 its actor is held near ``init``'s by
    ``TD3.set_anchor``, on the rows where ``anchor_mask`` is 1 if it is given).
    ``snapshot(done, agent)``, if given, is called after every
    update (it decides whether to keep the agent)."""
    agent = TD3(buffer.obs_dim, buffer.act_dim, td3_cfg, seed=seed, device=device)
    if init is not None:
        agent.load_state_dict(init)
        for opt, lr in ((agent.actor_opt, td3_cfg.actor_lr), (agent.critic_opt, td3_cfg.critic_lr)):
            for g in opt.param_groups:
                g["lr"] = lr
        agent.set_anchor(agent.actor, anchor)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xC0]))
    losses, t0 = [], time.perf_counter()
    for it in range(int(iterations)):
        rows = None if anchor_mask is None else {"anchor_mask": anchor_mask}
        m = agent.update(buffer.sample(td3_cfg.batch_size, rng, rows=rows))
        losses.append(m["critic_loss"])
        if progress is not None:
            progress(it + 1, m)
        if snapshot is not None:
            snapshot(it + 1, agent)
    dt = time.perf_counter() - t0
    return agent, {"iterations": int(iterations), "seconds": dt,
                   "final_critic_loss": float(np.mean(losses[-100:])) if losses else float("nan")}


def keep_settings(c: dict) -> tuple[int, int]:
    """(keep_every, keep_from) of a ``consolidate`` section, validated: besides the final policy,
    the agent after every ``keep_every`` iterations from ``keep_from`` on (0: none) is kept."""
    every, start, total = c.get("keep_every", 0), c.get("keep_from", 0), c["iterations"]
    for name, v in (("keep_every", every), ("keep_from", start)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise ValueError(f"consolidate.{name} = {v!r} must be a whole number >= 0")
    if start > total:
        raise ValueError(f"consolidate.keep_from = {start} must be at most consolidate.iterations "
                         f"= {total}")
    return every, start


def _check_writable(folder: str) -> None:
    """Creates ``folder`` and writes a probe file in it; an OSError becomes a ValueError naming it."""
    probe = os.path.join(folder, ".write-probe")
    try:
        os.makedirs(folder, exist_ok=True)
        with open(probe, "w") as fh:
            fh.write("ok")
        os.remove(probe)
    except OSError as exc:
        raise ValueError(f"consolidate: cannot write to {folder}: {exc.strerror or exc}") from None


def _write_agent(path: str, agent: TD3, state: dict) -> None:
    with AtomicDir(path, "checkpoint", {"consolidated": True}) as tmp:
        torch.save(agent.state_dict(), os.path.join(tmp, "agent.pt"))
        with open(os.path.join(tmp, "state.json"), "w") as fh:
            json.dump(state, fh)


def consolidate_runs(runs: list[str], cfg: dict, out_dir: str, evaluate_policies: bool = True,
                     log=print, ray: dict | None = None) -> dict:
    """``ray`` ({address, object_store_mb}): evaluate on a Ray cluster (one task per policy and
    environment) instead of in this process."""
    c = cfg["consolidate"]
    _check_writable(os.path.join(out_dir, "checkpoints"))  # before minutes of training, not after
    torch.set_num_threads(int(cfg["torch_threads"]))
    device = resolve_device(cfg.get("learner_device", "cpu"))
    specialists = []
    for r in runs:
        ck = load_checkpoint(r, with_buffer=True)
        if "buffer" not in ck:
            raise ValueError(f"{r}: checkpoint {ck['path']} holds no replay buffer")
        specialists.append(ck)
        log(f"  {r}: {ck['state']['env_id']}, {len(ck['buffer'])} transitions, step "
            f"{ck['state']['step']}")
    dims = {(s["state"]["obs_dim"], s["state"]["act_dim"]) for s in specialists}
    if len(dims) != 1:
        raise ValueError(f"consolidate: runs have different observation/action sizes {dims}")
    lay = L.ObservationLayout.from_dict(specialists[0]["state"]["layout"])
    w_to = c.get("w_delta")
    relabel = None
    if w_to is not None:
        if isinstance(w_to, bool) or not isinstance(w_to, (int, float)) or not 0 <= w_to < 1e3:
            raise ValueError(f"consolidate.w_delta = {w_to!r} must be null (rewards as stored) or "
                             f"a weight in [0, 1000) [1/m^2]")
        lat = lay.names.index("lateral_deviation")

        def relabel(i, part):  # each specialist's own eq 38 weight -> w_delta
            kw = (specialists[i]["state"]["config"].get("env") or {}).get("kwargs") or {}
            w_from = (kw.get("reward") or {}).get("w_delta", DEFAULT_W_DELTA)
            relabel_lateral(part, lat, lay.scale[lat], w_from, w_to)
    pool = pool_buffers([s["buffer"] for s in specialists], int(c["per_run"]),
                        int(c["buffer_size"]), relabel)
    part_sizes = [min(int(c["per_run"]), len(s["buffer"])) for s in specialists]  # pool order
    for s in specialists:  # the pool holds what is needed; free the full buffers
        s.pop("buffer", None)
    pool.set_noise(*noise_for(cfg["noise"], lay))
    log(f"  pooled {len(pool)} transitions (capacity {pool.capacity}); noise on "
        f"{pool.noise_idx.size} components"
        + (f"; rewards relabelled to w_delta = {w_to:g}" if w_to is not None else ""))
    base = dict(specialists[0]["state"]["td3"])
    base.update(batch_size=int(c["batch_size"]), actor_lr=float(c["lr"]),
                critic_lr=float(c["lr"]), hidden=int(c["hidden"]))
    td3_cfg = TD3Config(**base).validate()
    init, anchor = None, c.get("anchor") or 0.0
    if isinstance(anchor, bool) or not isinstance(anchor, (int, float)) or not 0 <= anchor < 1e6:
        raise ValueError(f"consolidate.anchor = {anchor!r} must be a weight in [0, 1e6) "
                         f"(0: no anchor)")
    if anchor and not c.get("init"):
        raise ValueError("consolidate.anchor holds the actor near consolidate.init's: give an init")
    held = c.get("anchor_runs")
    mask = None
    if held is not None:  # anchor only the rows of these specialists (by run folder name)
        names = [os.path.basename(os.path.normpath(r)) for r in runs]
        if (not anchor or not isinstance(held, list) or not held
                or any(not isinstance(h, str) or h not in names for h in held)):
            raise ValueError(f"consolidate.anchor_runs = {held!r} must be null or a non-empty "
                             f"list of the consolidated runs' folder names {names}, with "
                             f"consolidate.anchor > 0")
        mask = np.repeat(np.array([float(n in held) for n in names], np.float32), part_sizes)
        assert mask.size == len(pool)
    if c.get("init"):  # continue a consolidated agent instead of a fresh one
        ck = load_checkpoint(str(c["init"]), with_buffer=False)
        st = ck["state"]
        if (st["obs_dim"], st["act_dim"], st["td3"]["hidden"]) != (pool.obs_dim, pool.act_dim,
                                                                    td3_cfg.hidden):
            raise ValueError(f"consolidate.init = {c['init']}: networks (obs, act, hidden) = "
                             f"{(st['obs_dim'], st['act_dim'], st['td3']['hidden'])}, the pool "
                             f"and consolidate.hidden need {(pool.obs_dim, pool.act_dim, td3_cfg.hidden)}")
        init = ck["agent"]
        log(f"  continuing {ck['path']} at lr {td3_cfg.actor_lr:g}"
            + (f", its actor held by an anchor of weight {anchor:g}" if anchor else "")
            + (f" on the rows of {', '.join(held)}" if mask is not None else ""))
    bar = None
    if cfg["log"]["progress_bar"]:
        from tqdm import tqdm

        bar = tqdm(total=int(c["iterations"]), unit="it", dynamic_ncols=True)
    total, t0 = int(c["iterations"]), time.perf_counter()

    def progress(done, m):  # done: iterations so far
        if bar:
            bar.update(1)
        elif done % max(1, total // 10) == 0:  # without a bar: a line every tenth
            el = time.perf_counter() - t0
            log(f"  iteration {done}/{total}, {el:.0f} s, {done / el:.1f} iterations/s, "
                f"critic loss {m['critic_loss']:.3g}")

    ck_root = os.path.join(out_dir, "checkpoints")
    every, start = keep_settings(c)

    def state_of(agent, info):
        return {"env_id": "consolidated", "obs_dim": pool.obs_dim, "act_dim": pool.act_dim,
                "td3": agent.config_dict(), "layout": lay.to_dict(), "step": 0,
                "updates": agent.updates, "sources": [s["path"] for s in specialists],
                "config": cfg, "consolidation": info}

    def snapshot(done, agent):  # intermediate policies for ``ernest train-default``'s selection
        if every and start <= done < total and done % every == 0:
            info = {"iterations": done, "seconds": time.perf_counter() - t0}
            _write_agent(os.path.join(ck_root, f"iteration-{done:08d}"), agent,
                         state_of(agent, info))

    agent, info = train_on_buffer(pool, td3_cfg, total, int(cfg["seed"]), progress, device,
                                  snapshot if every else None, init, float(anchor), mask)
    if bar:
        bar.close()
    log(f"  {info['iterations']} iterations in {info['seconds']:.1f} s on {device}")
    _write_agent(os.path.join(ck_root, "consolidated"), agent, state_of(agent, info))
    with open(os.path.join(ck_root, "LATEST.tmp"), "w") as fh:
        fh.write("consolidated\n")
    os.replace(os.path.join(ck_root, "LATEST.tmp"), os.path.join(ck_root, "LATEST"))
    result = {"checkpoint": os.path.join(ck_root, "consolidated"), "info": info, "table": []}
    if evaluate_policies:
        result["table"] = evaluation_table(agent, specialists, cfg, out_dir, log, ray)
    return result


def evaluate_actor(weights: dict, obs_dim: int, act_dim: int, hidden: int, env_id: str,
                   kwargs: dict, episodes: int, seed: int, info_keys) -> dict:
    """``evaluate`` of an actor given by its weights, on a fresh env (a Ray task's body)."""
    from .networks import Actor

    torch.set_num_threads(1)
    actor = Actor(obs_dim, act_dim, hidden).requires_grad_(False)
    actor.load_state_dict({k: torch.as_tensor(np.array(v)) for k, v in weights.items()})

    def policy(obs):
        with torch.no_grad():
            return actor(torch.as_tensor(obs)).numpy().astype(np.float64)

    env = make_env(env_id, kwargs)
    try:
        return evaluate(policy, env, episodes, seed, info_keys)
    finally:
        env.close()


def evaluation_table(agent: TD3, specialists: list[dict], cfg: dict, out_dir: str, log=print,
                     ray: dict | None = None):
    """Consolidated actor vs every specialist on every specialist's environment (with ``ray``,
    each pair is a task on the cluster: ray_backend.fan_out)."""
    ev = cfg["eval"]
    envs = []
    for s in specialists:
        env_id = s["state"]["env_id"]
        kwargs = s["state"]["config"]["env"].get("kwargs") or {}
        if env_id not in [e[0] for e in envs]:
            envs.append((env_id, kwargs))
    policies = [("consolidated", agent)] + [
        (os.path.basename(os.path.dirname(os.path.dirname(s["path"]))) or s["path"],
         agent_from_checkpoint(s)) for s in specialists]
    rows, episodes, keys = [], int(cfg["consolidate"]["eval_episodes"]), ev.get("info_keys") or ()
    if ray is not None:
        from .ray_backend import fan_out, weights_to_numpy

        jobs = [(env_id, kwargs, name, pol) for env_id, kwargs in envs for name, pol in policies]
        results = fan_out(evaluate_actor, [
            (weights_to_numpy(pol.actor), pol.obs_dim, pol.act_dim, pol.config.hidden, env_id,
             kwargs, episodes, int(ev["seed"]), list(keys)) for env_id, kwargs, _, pol in jobs],
            ray.get("address"), ray.get("object_store_mb", 200))
        for (env_id, _, name, _), res in zip(jobs, results):
            rows.append({"policy": name, "env": env_id, **res})
            log(f"  {name:>20s} on {env_id}: return {res['return']:.3f}")
    for env_id, kwargs in envs if ray is None else ():
        env = make_env(env_id, kwargs)
        for name, pol in policies:
            res = evaluate(pol.act, env, episodes, int(ev["seed"]), keys)
            rows.append({"policy": name, "env": env_id, **res})
            log(f"  {name:>20s} on {env_id}: return {res['return']:.3f}")
        env.close()
    from .trainer import EVAL_UNITS

    keys = sorted({k for r in rows for k in r}, key=lambda k: (k not in ("policy", "env"), k))
    with open(os.path.join(out_dir, "evaluation.csv"), "w", newline="") as fh:
        w = csv.writer(fh)  # each column's unit in its header, as eval.csv's ([?]: an info key's)
        w.writerow(csv_header(keys, {"policy": "-", "env": "-", **EVAL_UNITS}, "?"))
        w.writerows([r.get(k, "") for k in keys] for r in rows)
    return rows


__all__ = ["pool_buffers", "train_on_buffer", "consolidate_runs", "evaluation_table",
           "find_checkpoint"]
