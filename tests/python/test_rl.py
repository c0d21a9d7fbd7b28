"""Tests of ernest_cpp.rl (seed 004 §4.1, §4.2 noise injection, §4.4 exploration, §4.6 consolidation,
Tables 4–5) on small self-made environments; the rover environments are not needed."""

from __future__ import annotations

import copy
import json
import math
import os

import numpy as np
import pytest
import yaml
import torch

torch.set_num_threads(1)

from ernest_cpp import cli  # noqa: E402
from ernest_cpp.rl import config as C  # noqa: E402
from ernest_cpp.rl import layout as L  # noqa: E402
from ernest_cpp.rl.consolidate import (consolidate_runs, pool_buffers, relabel_lateral,  # noqa: E402
                                       train_on_buffer)
from ernest_cpp.rl.exploration import GaussianExploration, MarkovExploration  # noqa: E402
from ernest_cpp.rl.export import ExportError, export_actor, load_policy  # noqa: E402
from ernest_cpp.rl.networks import Actor, TwinCritic  # noqa: E402
from ernest_cpp.rl.replay import ReplayBuffer  # noqa: E402
from ernest_cpp.rl.storage import CorruptFileError  # noqa: E402
from ernest_cpp.rl.td3 import TD3, TD3Config  # noqa: E402
from ernest_cpp.rl.toy_envs import PointMassEnv, optimal_return  # noqa: E402
from ernest_cpp.rl.checkpoints import load_checkpoint  # noqa: E402
from ernest_cpp.rl.envs_util import scenario_env_id  # noqa: E402
from ernest_cpp.rl.trainer import Trainer  # noqa: E402

POINT_MASS = "ernest-toy/PointMass-v0"


def small_cfg(**over) -> dict:
    """Quick preset shrunk for tests; ``over`` uses dotted keys."""
    sets = [f"env.id={POINT_MASS}", "td3.hidden=64", "td3.batch_size=64", "td3.actor_lr=0.001",
            "td3.critic_lr=0.001", "random_steps=500", "learning_starts=500", "total_steps=3000",
            "eval.every_steps=1000", "eval.episodes=20", "checkpoint.every_steps=1000",
            "log.progress_bar=false", "log.tensorboard=false", "buffer_size=5000"]
    sets += [f"{k}={v}" for k, v in over.items()]
    return C.build_config("quick", None, sets)


def zero_and_optimal(seed: int, episodes: int) -> tuple[float, float]:
    """Closed-form returns on the evaluation seeds: doing nothing, and moving 0.2 towards g."""
    env, zero, best = PointMassEnv(), [], []
    for k in range(episodes):
        env.reset(seed=seed + k)
        zero.append(-10 * abs(env.x - env.g))
        best.append(optimal_return(env.x, env.g))
    return float(np.mean(zero)), float(np.mean(best))


# ----------------------------------------------------------------------------------- networks
def test_networks_follow_section_4_1():
    actor, critic = Actor(45, 3), TwinCritic(45, 3)
    # Parameter counts from the architecture: 45-512-512-3 and [45+3]-512-[512+3]-512-1.
    assert sum(p.numel() for p in actor.parameters()) == 45 * 512 + 512 + 512 * 512 + 512 + 512 * 3 + 3
    per_critic = 48 * 512 + 512 + 515 * 512 + 512 + 512 + 1
    assert sum(p.numel() for p in critic.parameters()) == 2 * per_critic
    x = torch.randn(1000, 45) * 100.0
    a = actor(x)
    assert a.shape == (1000, 3) and a.abs().max() <= 1.0  # tanh output layer
    # The action reaches the critic's second layer directly: perturbing only the weights of the
    # re-injected action columns changes Q.
    s, act = torch.randn(8, 45), torch.randn(8, 3)
    q_before = critic.q1(s, act).detach().clone()
    with torch.no_grad():
        critic.q1.l2.weight[:, 512:] += 1.0
    assert not torch.allclose(q_before, critic.q1(s, act))
    assert critic.q1.l2.in_features == 512 + 3


def test_td3_update_matches_definition():
    """One critic step against a hand-computed target; delayed actor; soft target update."""
    cfg = TD3Config(hidden=16, batch_size=8, actor_lr=1e-2, critic_lr=1e-2, target_noise=0.0)
    agent = TD3(4, 2, cfg, seed=3)
    g = torch.Generator().manual_seed(0)
    batch = {"obs": torch.randn(8, 4, generator=g), "act": torch.rand(8, 2, generator=g) * 2 - 1,
             "rew": torch.randn(8, generator=g), "next_obs": torch.randn(8, 4, generator=g),
             "done": torch.tensor([0, 1, 0, 0, 1, 0, 0, 0], dtype=torch.float32)}
    with torch.no_grad():
        na = agent.actor_target(batch["next_obs"])
        t1, t2 = agent.critic_target(batch["next_obs"], na)
        y = batch["rew"] + 0.99 * (1 - batch["done"]) * torch.minimum(t1, t2)
        q1, q2 = agent.critic(batch["obs"], batch["act"])
        expected_loss = float(((q1 - y) ** 2).mean() + ((q2 - y) ** 2).mean())
    actor0 = copy.deepcopy(agent.actor.state_dict())
    tgt0 = copy.deepcopy(agent.actor_target.state_dict())
    info = agent.update(batch)
    assert info["critic_loss"] == pytest.approx(expected_loss, rel=1e-5)
    assert "actor_loss" not in info  # d = 2: no actor step on the first update
    for k, v in agent.actor.state_dict().items():
        assert torch.equal(v, actor0[k])
    info = agent.update(batch)
    assert "actor_loss" in info
    for k, v in agent.actor_target.state_dict().items():  # θ' ← τθ + (1-τ)θ'
        expected = 5e-3 * agent.actor.state_dict()[k] + (1 - 5e-3) * tgt0[k]
        torch.testing.assert_close(v, expected, rtol=0, atol=1e-6)
    assert not torch.equal(agent.actor.state_dict()["l1.weight"], actor0["l1.weight"])


def test_td3_defaults_are_tables_4_and_5():
    c = TD3Config()
    assert (c.gamma, c.tau, c.policy_delay, c.target_noise, c.target_noise_clip) == \
        (0.99, 5e-3, 2, 0.05, 0.2)
    assert (c.batch_size, c.actor_lr, c.hidden) == (128, 1e-5, 512)
    paper = C.load_preset("paper")
    assert paper["td3"]["batch_size"] == 128 and paper["td3"]["actor_lr"] == 1e-5
    assert paper["buffer_size"] == 1_000_000
    cons = paper["consolidate"]
    assert (cons["per_run"], cons["buffer_size"], cons["batch_size"], cons["lr"],
            cons["iterations"]) == (1_000_000, 4_000_000, 512, 1e-3, 10_000)
    with pytest.raises(ValueError, match="td3.tau"):
        TD3Config(tau=0.0).validate()


# ----------------------------------------------------------------------------------- exploration
def _markov_trace(num_envs: int, steps: int, seed: int):
    ex = MarkovExploration(num_envs, 2)
    rng = np.random.default_rng(seed)
    sentinel = np.full((num_envs, 2), 7.0)  # outside [-1, 1]: marks "policy action used"
    acts = np.empty((steps, num_envs, 2))
    for t in range(steps):
        acts[t] = ex(sentinel, rng)
    return acts


def test_markov_exploration_transition_probabilities():
    acts = _markov_trace(100, 1000, seed=12345)
    random = acts[..., 0] != 7.0  # (steps, envs)
    prev, cur = random[:-1], random[1:]
    n_p, n_r = int((~prev).sum()), int(prev.sum())
    p_pr = (~prev & cur).sum() / n_p  # POLICY -> RANDOM
    p_rr = (prev & cur).sum() / n_r  # RANDOM -> RANDOM (held)
    assert abs(p_pr - 0.5) < 4 * math.sqrt(0.25 / n_p)
    assert abs(p_rr - 0.5) < 4 * math.sqrt(0.25 / n_r)
    assert abs(random.mean() - 0.5) < 0.01  # stationary share of random steps
    # First decision of an episode (start in POLICY) is random with probability 1/2.
    assert abs(random[0].mean() - 0.5) < 4 * math.sqrt(0.25 / 100)
    # Consecutive random steps always hold the same action (a new draw only comes after POLICY).
    held = prev & cur
    assert np.array_equal(acts[:-1][held], acts[1:][held])
    # Draws are uniform over the full range [-1, 1]: mean 0, variance 1/3.
    starts = cur & ~prev
    draws = acts[1:][starts].reshape(-1)
    assert draws.min() >= -1 and draws.max() <= 1
    assert abs(draws.mean()) < 4 * math.sqrt((1 / 3) / draws.size)
    assert abs(draws.var() - 1 / 3) < 0.01


def test_markov_exploration_holding_durations_are_geometric():
    acts = _markov_trace(1, 200_000, seed=7)
    random = acts[:, 0, 0] != 7.0
    runs, k = [], 0
    for r in random:
        if r:
            k += 1
        elif k:
            runs.append(k)
            k = 0
    runs = np.asarray(runs)
    # P(k) = 2^-k for k >= 1 (hold with probability 1/2): chi-square over k = 1..7 and >= 8.
    observed = np.array([(runs == j).sum() for j in range(1, 8)] + [(runs >= 8).sum()])
    probs = np.array([2.0 ** -j for j in range(1, 8)] + [2.0 ** -7])
    expected = probs * runs.size
    chi2 = float(((observed - expected) ** 2 / expected).sum())
    assert chi2 < 24.32  # 99.9 % quantile of chi-square with 7 degrees of freedom
    assert abs(runs.mean() - 2.0) < 4 * math.sqrt(2.0 / runs.size)  # mean 1/p, variance (1-p)/p²


def test_exploration_reset_and_gaussian():
    ex = MarkovExploration(3, 1, p_random=1.0, p_hold=0.99)
    rng = np.random.default_rng(0)
    a = ex(np.full((3, 1), 7.0), rng)
    assert np.all(a != 7.0)
    ex.reset(np.array([True, False, False]))
    assert ex.mode.tolist() == [0, 1, 1]
    g = GaussianExploration(1000, 2, sigma=0.1)
    out = g(np.zeros((1000, 2)), rng)
    assert abs(out.std() - 0.1) < 0.01 and abs(out.mean()) < 0.01
    assert np.all(g(np.ones((1000, 2)), rng) <= 1.0)


# ----------------------------------------------------------------------------------- layout, noise
def test_paper_layout_and_noise_scales():
    lay = L.paper_layout()
    assert lay.obs_dim == 45 and lay.act_dim == 3  # Table 5
    assert lay.names[6] == "fts_FL_Fx" and lay.names[29] == "fts_RR_Tz"
    assert lay.names[42] == "action_vx"
    idx, std = lay.noise_std_normalised()
    assert sorted(idx.tolist()) == list(range(6, 30))  # only the 4×6 FTS values
    for i, s in zip(idx, std):
        force = (i - 6) % 6 < 3
        assert s == pytest.approx((10.0 if force else 2.0) / lay.scale[i])
    np.testing.assert_allclose(lay.action_high, [0.2, math.radians(20), math.radians(10)])
    # Custom groups by index range, stride and sigma.
    groups = L.parse_noise_groups(["6:30:6=10", [9, 12, 2.0]])
    assert groups[0].indices().tolist() == [6, 12, 18, 24] and groups[1].sigma == 2.0


def _filled_buffer(n=1000, cap=1000, obs_dim=45, seed=0):
    rng = np.random.default_rng(seed)
    buf = ReplayBuffer(cap, obs_dim, 3)
    buf.add(rng.normal(size=(n, obs_dim)), rng.uniform(-1, 1, (n, 3)), np.arange(n),
            rng.normal(size=(n, obs_dim)), rng.integers(0, 2, n))
    return buf


def test_noise_injection_only_fts_redrawn_and_storage_untouched():
    lay = L.paper_layout()
    idx, std = lay.noise_std_normalised()
    buf = _filled_buffer()
    buf.set_noise(idx, std)
    stored = {f: getattr(buf, f).copy() for f in ("obs", "act", "rew", "next_obs", "done")}
    rng = np.random.default_rng(1)
    others = np.setdiff1d(np.arange(45), idx)
    diffs_o, diffs_n = [], []
    for _ in range(20):
        b = buf.sample(512, rng)
        rows = b["rew"].astype(int)  # reward = stored row index
        for key, diffs in (("obs", diffs_o), ("next_obs", diffs_n)):
            d = b[key] - stored[key][rows]
            assert np.array_equal(d[:, others], np.zeros_like(d[:, others]))  # untouched exactly
            diffs.append(d[:, idx])
        assert np.array_equal(b["act"], stored["act"][rows])
    do, dn = np.concatenate(diffs_o), np.concatenate(diffs_n)
    # Per-component std is σ/scale (10 N/200 N, 2 N·m/40 N·m) on both states, independent draws.
    np.testing.assert_allclose(do.std(axis=0), std, rtol=0.05)
    np.testing.assert_allclose(dn.std(axis=0), std, rtol=0.05)
    assert abs(np.corrcoef(do[:, 0], dn[:, 0])[0, 1]) < 0.03
    for f, v in stored.items():  # the stored data never change
        assert np.array_equal(getattr(buf, f), v)
    # Redrawn each time: the same single transition sampled twice gets different noise.
    one = ReplayBuffer(1, 45, 3)
    one.add(stored["obs"][0], stored["act"][0], 0.0, stored["next_obs"][0], 0.0)
    one.set_noise(idx, std)
    b1, b2 = one.sample(4, rng), one.sample(4, rng)
    assert not np.array_equal(b1["obs"][:, idx], b2["obs"][:, idx])
    assert not np.array_equal(b1["obs"][0, idx], b1["obs"][1, idx])
    assert np.array_equal(one.sample(2, rng, noise=False)["obs"][0], stored["obs"][0])


# ----------------------------------------------------------------------------------- buffer
def test_ring_buffer_wraps_and_keeps_order():
    buf = _filled_buffer(n=150, cap=100, obs_dim=4)
    assert len(buf) == 100 and buf.total_added == 150
    np.testing.assert_array_equal(buf.chronological()["rew"], np.arange(50, 150))
    buf.add(np.zeros((5, 4)), np.zeros((5, 3)), np.arange(150, 155), np.zeros((5, 4)), np.zeros(5))
    np.testing.assert_array_equal(buf.chronological()["rew"], np.arange(55, 155))
    assert buf.ptr == 155 % 100


def test_sample_draws_extra_rows_with_the_same_indices():
    buf = _filled_buffer(n=50, cap=50)  # rewards are the row numbers
    tag = np.arange(50, dtype=np.float32) * 10
    a = buf.sample(32, np.random.default_rng(3), rows={"tag": tag})
    b = buf.sample(32, np.random.default_rng(3))
    np.testing.assert_array_equal(a["tag"], a["rew"] * 10)  # the same rows
    np.testing.assert_array_equal(a["obs"], b["obs"])  # and the same draw as without rows


def test_buffer_refuses_non_finite_transitions():
    buf = _filled_buffer(n=10, cap=20)
    size = buf.size
    good = [np.zeros(45), np.zeros(3), 0.0, np.zeros(45), 0.0]
    for k, name in ((0, "obs"), (1, "act"), (2, "rew"), (3, "next_obs")):
        bad = list(good)
        bad[k] = np.full_like(np.atleast_1d(good[k]), np.nan, dtype=float)
        with pytest.raises(ValueError, match=f"{name} of transition 0 of 1 is not finite"):
            buf.add(*bad)
    with pytest.raises(ValueError, match="rew of transition 1 of 2"):
        buf.add(np.zeros((2, 45)), np.zeros((2, 3)), [0.0, np.inf], np.zeros((2, 45)), [0, 0])
    assert buf.size == size  # nothing of a refused batch is stored
    buf.add(*good)
    assert buf.size == size + 1


def test_buffer_save_load_round_trip(tmp_path):
    buf = _filled_buffer(n=2500, cap=2000, obs_dim=45)
    buf.set_noise([6, 7], [0.1, 0.2])
    buf.save(str(tmp_path / "b"), chunk_rows=300)  # several chunks
    assert len(os.listdir(tmp_path / "b" / "obs")) == 7
    back = ReplayBuffer.load(str(tmp_path / "b"))
    for f in ("obs", "act", "rew", "next_obs", "done"):
        assert np.array_equal(getattr(back, f), getattr(buf, f))
    assert (back.ptr, back.size, back.total_added) == (buf.ptr, buf.size, buf.total_added)
    # Same storage order: the same generator draws the same minibatches (with the same noise).
    b1 = buf.sample(64, np.random.default_rng(5))
    b2 = back.sample(64, np.random.default_rng(5))
    for k in b1:
        assert np.array_equal(b1[k], b2[k])
    small = ReplayBuffer.load(str(tmp_path / "b"), capacity=500)  # most recent 500 kept
    np.testing.assert_array_equal(small.chronological()["rew"], np.arange(2000, 2500))
    buf.save(str(tmp_path / "b"))  # overwriting an existing buffer is atomic too
    assert len(ReplayBuffer.load(str(tmp_path / "b"))) == 2000


def test_last_n_and_merge():
    a = _filled_buffer(n=300, cap=200, obs_dim=4)  # holds 100..299
    b = _filled_buffer(n=50, cap=100, obs_dim=4, seed=1)
    b.rew[:50] += 1000  # marks b's rows
    last = a.last_n(30)
    np.testing.assert_array_equal(last.chronological()["rew"], np.arange(270, 300))
    assert len(a.last_n(10_000)) == 200
    pooled = pool_buffers([a, b], per_run=40)
    np.testing.assert_array_equal(pooled.chronological()["rew"],
                                  np.concatenate([np.arange(260, 300), 1010 + np.arange(40)]))
    assert pooled.capacity == 80  # allocated for what was pooled, not for buffer_size
    with pytest.raises(ValueError, match="exceed buffer_size"):
        pool_buffers([a, b], per_run=40, capacity=79)
    merged = ReplayBuffer.merge([a, b])
    assert len(merged) == 250
    np.testing.assert_array_equal(merged.chronological()["obs"][200:], b.chronological()["obs"])
    with pytest.raises(ValueError, match="do not fit"):
        ReplayBuffer.merge([a, b], capacity=100)
    with pytest.raises(ValueError, match="different"):
        ReplayBuffer.merge([a, _filled_buffer(n=5, cap=5, obs_dim=5)])


def test_corrupt_buffer_gives_clear_error(tmp_path):
    buf = _filled_buffer(n=100, cap=100, obs_dim=4)
    path = tmp_path / "b"
    buf.save(str(path))
    chunk = path / "obs" / "000000.npy"
    raw = bytearray(chunk.read_bytes())
    raw[-3] ^= 0xFF
    chunk.write_bytes(bytes(raw))
    with pytest.raises(CorruptFileError, match="checksum"):
        ReplayBuffer.load(str(path))
    chunk.write_bytes(bytes(raw[:50]))
    with pytest.raises(CorruptFileError, match="truncated"):
        ReplayBuffer.load(str(path))
    (path / "manifest.json").write_text("{not json")
    with pytest.raises(CorruptFileError, match="not valid JSON"):
        ReplayBuffer.load(str(path))
    (path / "manifest.json").unlink()
    with pytest.raises(CorruptFileError, match="no manifest.json"):
        ReplayBuffer.load(str(path))
    with pytest.raises(CorruptFileError, match="not found"):
        ReplayBuffer.load(str(tmp_path / "nothing"))


# ----------------------------------------------------------------------------------- training
def test_td3_learns_point_mass(tmp_path):
    """Fails if the updates are broken: the untrained actor is far from the closed-form optimum."""
    cfg = small_cfg(**{"eval.baseline": "{action: [0.0]}"})
    tr = Trainer(cfg, str(tmp_path / "run"))
    before = tr.run_eval()["return"]
    res = tr.train()
    tr.close()
    zero, best = zero_and_optimal(cfg["eval"]["seed"], cfg["eval"]["episodes"])
    after = res["last_eval"]["return"]
    assert before < best + 0.5 * (zero - best)  # untrained: at least half-way to doing nothing
    assert after > best + 0.15 * (zero - best), (before, after, zero, best)
    assert res["updates"] == 3000 - 500 + 2  # one update per transition after learning_starts
    # The fixed-action baseline (standing still) on the same seeds has the closed-form return.
    assert res["baseline"]["return"] == pytest.approx(zero, rel=1e-6)
    rows = open(tmp_path / "run" / "eval.csv").read().splitlines()
    assert len(rows) == 1 + 1 + 3  # header, the manual evaluation, three periodic ones
    names = rows[0].split(",")  # each header names its unit
    assert "return [-]" in names and "step [transitions]" in names and "elapsed_s [s]" in names
    assert all(n.endswith("]") and " [" in n for n in names), names


def test_resume_gives_the_same_updates(tmp_path):
    over = {"env.num_envs": 2, "td3.hidden": 32, "total_steps": 800, "random_steps": 100,
            "learning_starts": 100, "checkpoint.every_steps": 400, "eval.every_steps": 400,
            "eval.episodes": 2}
    cfg = small_cfg(**over)
    full = Trainer(cfg, str(tmp_path / "full"))
    full.train()
    part = Trainer(cfg, str(tmp_path / "part"))
    part.train(total_steps=400)  # "interrupted" right after its checkpoint at 400
    part.close()
    with pytest.raises(ValueError, match="--resume"):
        Trainer(cfg, str(tmp_path / "part"))
    with open(tmp_path / "part" / "eval.csv", "a") as fh:  # as if killed after a later evaluation
        fh.write("9.5,10,-1,-1,0,600\n10,-1")  # and a row cut short by the kill
    resumed = Trainer(cfg, str(tmp_path / "part"), resume=True)
    assert resumed.step == 400
    resumed.train()
    for run in ("full", "part"):  # one evaluation row per evaluation step, none duplicated
        rows = open(tmp_path / run / "eval.csv").read().splitlines()
        assert [float(r.split(",")[-1]) for r in rows[1:]] == [400, 800]
    assert full.agent.updates == resumed.agent.updates == 800 - 100 + 2
    sd_a, sd_b = full.agent.state_dict(), resumed.agent.state_dict()
    for net in ("actor", "critic", "actor_target", "critic_target"):
        for k, v in sd_a[net].items():
            assert torch.equal(v, sd_b[net][k]), (net, k)
    assert torch.equal(sd_a["gen"], sd_b["gen"])
    for f in ("obs", "act", "rew", "next_obs", "done"):
        assert np.array_equal(getattr(full.buffer, f), getattr(resumed.buffer, f))
    # The next minibatches are the same too.
    b1 = full.buffer.sample(8, full.sample_rng)
    b2 = resumed.buffer.sample(8, resumed.sample_rng)
    assert np.array_equal(b1["obs"], b2["obs"])
    full.close()
    resumed.close()


def test_simulations_in_processes_feed_the_learner_like_in_process(tmp_path):
    """env.vector=async (one process per simulation) collects exactly what sync collects."""
    weights = {}
    for mode in ("sync", "async"):
        cfg = small_cfg(**{"env.vector": mode, "td3.hidden": 16, "total_steps": 400,
                           "random_steps": 100, "learning_starts": 100,
                           "eval.every_steps": 0, "checkpoint.every_steps": 400})
        tr = Trainer(cfg, str(tmp_path / mode))
        tr.train()
        weights[mode] = (tr.agent.actor.l1.weight.clone(), tr.buffer.obs.copy())
        tr.close()
    assert torch.equal(weights["sync"][0], weights["async"][0])
    assert np.array_equal(weights["sync"][1], weights["async"][1])


@pytest.mark.parametrize("autoreset", ["same", "next"])
def test_stored_transitions_obey_the_dynamics(tmp_path, autoreset):
    """With either autoreset convention, every stored (s, a, s') is a real step of the point mass
    (x' = clip(x + 0.2 a, -2, 2), same target): no reset observation is ever stored as s'."""
    cfg = small_cfg(**{"env.autoreset": autoreset, "env.num_envs": 3, "td3.hidden": 16,
                       "total_steps": 300, "random_steps": 300, "learning_starts": 300,
                       "eval.every_steps": 0, "checkpoint.every_steps": 0})
    tr = Trainer(cfg, str(tmp_path / autoreset))
    tr.train()
    tr.close()
    b = tr.buffer.chronological()
    assert len(tr.buffer) == tr.step == 300
    np.testing.assert_array_equal(b["obs"][:, 1], b["next_obs"][:, 1])
    x_next = np.clip(b["obs"][:, 0] + 0.2 * b["act"][:, 0], -2, 2)
    np.testing.assert_allclose(b["next_obs"][:, 0], x_next, atol=1e-6)
    assert tr.episodes == 30  # 300 transitions of 10-step episodes


def test_corrupt_checkpoint_gives_clear_error(tmp_path):
    cfg = small_cfg(**{"td3.hidden": 16, "total_steps": 200, "random_steps": 100,
                       "learning_starts": 100, "checkpoint.every_steps": 200,
                       "eval.every_steps": 0})
    tr = Trainer(cfg, str(tmp_path / "run"))
    tr.train()
    tr.close()
    ck = load_checkpoint(str(tmp_path / "run"))["path"]
    agent_file = os.path.join(ck, "agent.pt")
    data = open(agent_file, "rb").read()
    with open(agent_file, "wb") as fh:
        fh.write(data[: len(data) // 2])
    with pytest.raises(CorruptFileError, match="agent.pt"):
        load_checkpoint(str(tmp_path / "run"))
    with pytest.raises(CorruptFileError):
        Trainer(cfg, str(tmp_path / "run"), resume=True)
    # The same via the console command: one clear line, exit code 2.
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", str(tmp_path / "run"),
                     "--resume"]) == 2


def test_consolidation_end_to_end(tmp_path, capsys):
    runs = []
    for seed in (0, 1):
        cfg = small_cfg(**{"seed": seed, "total_steps": 1500, "eval.every_steps": 0,
                           "checkpoint.every_steps": 1500})
        tr = Trainer(cfg, str(tmp_path / f"spec{seed}"))
        tr.train()
        tr.close()
        runs.append(str(tmp_path / f"spec{seed}"))
    cfg = small_cfg(**{"consolidate.per_run": 1000, "consolidate.buffer_size": 2000,
                       "consolidate.batch_size": 128, "consolidate.iterations": 1500,
                       "consolidate.hidden": 64, "consolidate.eval_episodes": 20,
                       "log.progress_bar": False})
    res = consolidate_runs(runs, cfg, str(tmp_path / "cons"), log=lambda *a: None)
    table = res["table"]
    assert {r["policy"] for r in table} == {"consolidated", "spec0", "spec1"}
    cons_ret = next(r["return"] for r in table if r["policy"] == "consolidated")
    zero, best = zero_and_optimal(cfg["eval"]["seed"], 20)
    assert cons_ret > best + 0.3 * (zero - best)  # learned from the pooled data alone
    assert os.path.exists(tmp_path / "cons" / "evaluation.csv")
    ck = load_checkpoint(str(tmp_path / "cons"), with_buffer=False)
    assert ck["state"]["td3"]["batch_size"] == 128 and ck["state"]["td3"]["actor_lr"] == 1e-3


def test_train_on_buffer_iterations():
    buf = _filled_buffer(n=500, cap=500, obs_dim=6)
    agent, info = train_on_buffer(buf, TD3Config(hidden=16, batch_size=32), 10)
    assert info["iterations"] == 10 and agent.updates == 10


# ----------------------------------------------------------------------------------- export
def test_export_round_trip_identical_outputs(tmp_path):
    lay = L.paper_layout()
    torch.manual_seed(0)
    actor = Actor(45, 3, 64)
    meta = export_actor(actor, lay, str(tmp_path / "policy.pt"), extra_meta={"note": "t"})
    mod, meta_back = load_policy(str(tmp_path / "policy.pt"))
    assert meta_back["layout_version"] == L.LAYOUT_VERSION and meta_back["obs_dim"] == 45
    assert meta_back["act_dim"] == 3 and meta_back["policy_rate_hz"] == 2.0
    assert meta_back["note"] == "t" and meta["verified_max_abs_error"] <= 1e-6
    assert mod.obs_dim == 45 and mod.layout_version == L.LAYOUT_VERSION
    # Identical to the Python path computed independently here.
    rng = np.random.default_rng(3)
    raw = (lay.offset + rng.uniform(-1, 1, (100, 45)) * lay.scale).astype(np.float32)
    with torch.no_grad():
        u = actor(torch.from_numpy(((raw - lay.offset) / lay.scale).astype(np.float32)))
        want = lay.action_low + (u.numpy() + 1) / 2 * (lay.action_high - lay.action_low)
        got = mod(torch.from_numpy(raw)).numpy()
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)
    assert got[:, 0].min() >= 0.0 and got[:, 0].max() <= 0.2  # Vx range in m/s
    # A saved-then-reloaded file gives bit-identical outputs to the first load.
    mod2, _ = load_policy(str(tmp_path / "policy.pt"))
    assert torch.equal(mod2(torch.from_numpy(raw)), mod(torch.from_numpy(raw)))
    (tmp_path / "bad.pt").write_bytes(b"garbage")
    with pytest.raises(ExportError, match="not a loadable"):
        load_policy(str(tmp_path / "bad.pt"))
    with pytest.raises(ExportError, match="do not match"):
        export_actor(Actor(10, 3, 8), lay, str(tmp_path / "x.pt"))
    assert not os.path.exists(tmp_path / "x.pt")


# ----------------------------------------------------------------------------------- commands
def test_console_commands_on_a_45_value_env(tmp_path, capsys):
    """train -> export -> consolidate through ``ernest``, on an env with the paper's sizes."""
    run = str(tmp_path / "run")
    common = ["--set", "env.kwargs={obs_dim: 45, act_dim: 3}", "--set", "td3.hidden=32",
              "--set", "log.progress_bar=false", "--set", "eval.every_steps=0",
              "--set", "random_steps=100", "--set", "learning_starts=100"]
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", run, "--steps", "300",
                     "--set", "checkpoint.every_steps=300"] + common) == 0
    out = capsys.readouterr().out
    assert "layout ernest-obs-v2" in out and "FTS noise on 24 components" in out
    assert os.path.isdir(os.path.join(run, "tb"))  # TensorBoard logs
    capsys.readouterr()
    # --resume with no more steps than done is refused (exit 2, one line naming both counts)
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "300"]) == 2
    assert "has done 300 transitions already" in capsys.readouterr().err
    # --print-config: the resolved settings (the run's, with the command line's) and no training
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "400",
                     "--set", "td3.batch_size=64", "--print-config"]) == 0
    printed = yaml.safe_load(capsys.readouterr().out)
    assert printed["total_steps"] == 400 and printed["td3"]["batch_size"] == 64
    assert printed["td3"]["hidden"] == 32
    assert load_checkpoint(run, with_buffer=False)["state"]["step"] == 300
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "400"]) == 0
    assert load_checkpoint(run, with_buffer=False)["state"]["step"] == 400
    assert cli.main(["export", run, "--out", str(tmp_path / "p.pt")]) == 0
    _, meta = load_policy(str(tmp_path / "p.pt"))
    assert meta["obs_dim"] == 45 and meta["env_id"] == POINT_MASS
    assert cli.main(["consolidate", run, "--out", str(tmp_path / "cons"), "--set",
                     "consolidate.iterations=20", "--set", "consolidate.hidden=16",
                     "--set", "consolidate.eval_episodes=1", "--set",
                     "log.progress_bar=false"]) == 0
    with open(tmp_path / "cons" / "evaluation.csv") as fh:
        lines = fh.read().splitlines()
    assert len(lines) == 3
    head = lines[0].split(",")  # each column names its unit, as eval.csv's
    assert set(head[:2]) == {"policy [-]", "env [-]"} and "return [-]" in head, head
    assert all(h.endswith("]") and " [" in h for h in head), head
    capsys.readouterr()
    assert cli.main(["train", "--env", "ernest-toy/DoesNotExist-v0"]) == 2
    err = capsys.readouterr().err
    assert "unknown environment id 'ernest-toy/DoesNotExist-v0'" in err and POINT_MASS in err
    # an unknown rover id names itself and the valid ids, not a missing package
    assert cli.main(["train", "--env", "ernest/Moon-v0"]) == 2
    err = capsys.readouterr().err
    assert "unknown environment id 'ernest/Moon-v0'" in err, err
    assert "ernest/Slope-v0" in err and "ernest/RockField-v0" in err and "not available" not in err
    assert cli.main(["train", "--env", POINT_MASS, "--set", "td3.batchsize=3"]) == 2
    assert "unknown setting 'td3.batchsize'" in capsys.readouterr().err
    assert scenario_env_id("slope") == "ernest/Slope-v0"
    assert json.loads(json.dumps(C.parse_assignment("a.b=[1, 2]"))) == {"a": {"b": [1, 2]}}


def test_relabelling_the_lateral_weight_is_exact_and_touches_only_the_reward():
    lay = L.paper_layout()
    i = lay.names.index("lateral_deviation")
    buf = _filled_buffer(n=300, cap=400)
    before = {f: getattr(buf, f).copy() for f in ("obs", "act", "rew", "next_obs", "done")}
    relabel_lateral(buf, i, lay.scale[i], 0.1, 0.5)
    delta = before["next_obs"][:300, i].astype(np.float64) * lay.scale[i]  # eq 37's delta [m]
    np.testing.assert_allclose(buf.rew[:300], before["rew"][:300] - 0.4 * delta ** 2, rtol=1e-6,
                               atol=1e-5)
    assert np.all(buf.rew[300:] == 0.0)  # the empty slots stay empty
    for f in ("obs", "act", "next_obs", "done"):
        np.testing.assert_array_equal(getattr(buf, f), before[f])
    # pool_buffers hands each source's part to the relabelling, not the source itself
    src = _filled_buffer(n=300, cap=300)
    seen = []
    pool = pool_buffers([src], 200, relabel=lambda k, part: seen.append((k, len(part))))
    assert seen == [(0, 200)] and len(pool) == 200


def test_consolidation_continues_a_given_agent_on_relabelled_rewards(tmp_path, capsys):
    run, cons = str(tmp_path / "run"), str(tmp_path / "cons")
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", run, "--steps", "300",
                     "--set", "env.kwargs={obs_dim: 45, act_dim: 3}", "--set", "td3.hidden=32",
                     "--set", "log.progress_bar=false", "--set", "eval.every_steps=0",
                     "--set", "random_steps=100", "--set", "learning_starts=100",
                     "--set", "checkpoint.every_steps=300"]) == 0
    small = ["--set", "consolidate.hidden=16", "--set", "log.progress_bar=false", "--no-eval"]
    assert cli.main(["consolidate", run, "--out", cons, "--set", "consolidate.iterations=20"]
                    + small) == 0
    first = load_checkpoint(cons, with_buffer=False)
    capsys.readouterr()
    # one update at a vanishing learning rate: the continued actor is the given one
    more = str(tmp_path / "more")
    assert cli.main(["consolidate", run, "--out", more, "--set", "consolidate.iterations=1",
                     "--set", f"consolidate.init={first['path']}", "--set", "consolidate.lr=1e-12",
                     "--set", "consolidate.w_delta=0.5"] + small) == 0
    out = capsys.readouterr().out
    assert "continuing" in out and "rewards relabelled to w_delta = 0.5" in out
    cont = load_checkpoint(more, with_buffer=False)
    for k, v in first["agent"]["actor"].items():
        torch.testing.assert_close(cont["agent"]["actor"][k], v, atol=1e-9, rtol=0)
    assert cont["state"]["td3"]["actor_lr"] == 1e-12
    # a fresh agent (no init) is not the given one
    fresh = str(tmp_path / "fresh")
    assert cli.main(["consolidate", run, "--out", fresh, "--set", "consolidate.iterations=1",
                     "--set", "seed=5"] + small) == 0
    w = load_checkpoint(fresh, with_buffer=False)["agent"]["actor"]
    assert any(not torch.equal(w[k], v) for k, v in first["agent"]["actor"].items())
    capsys.readouterr()
    # refused: a weight out of range, an agent of another width
    assert cli.main(["consolidate", run, "--out", str(tmp_path / "bad"), "--set",
                     "consolidate.w_delta=-1"] + small) == 2
    assert "consolidate.w_delta" in capsys.readouterr().err
    for bad in ("-1", "nan", "true"):
        assert cli.main(["consolidate", run, "--out", str(tmp_path / "bad3"), "--set",
                         f"consolidate.init={first['path']}", "--set",
                         f"consolidate.anchor={bad}"] + small) == 2
        assert "consolidate.anchor" in capsys.readouterr().err
    assert cli.main(["consolidate", run, "--out", str(tmp_path / "bad4"), "--set",
                     "consolidate.anchor=1"] + small) == 2  # an anchor needs an agent to hold
    assert "give an init" in capsys.readouterr().err
    # with an anchor the continued actor moves less from the given one than without
    moved = {}
    for w in (0, 1000):
        d = str(tmp_path / f"anchor{w}")
        assert cli.main(["consolidate", run, "--out", d, "--set", "consolidate.iterations=10",
                         "--set", f"consolidate.init={first['path']}", "--set",
                         "consolidate.lr=1e-3", "--set", f"consolidate.anchor={w}"] + small) == 0
        a = load_checkpoint(d, with_buffer=False)["agent"]["actor"]
        moved[w] = sum(float((a[k] - v).abs().sum()) for k, v in first["agent"]["actor"].items())
    assert "held by an anchor of weight 1000" in capsys.readouterr().out
    assert moved[1000] < moved[0], moved
    # the anchor on the rows of named runs only: here the one run, so the same as every row
    d = str(tmp_path / "anchor-rows")
    assert cli.main(["consolidate", run, "--out", d, "--set", "consolidate.iterations=10",
                     "--set", f"consolidate.init={first['path']}", "--set", "consolidate.lr=1e-3",
                     "--set", "consolidate.anchor=1000", "--set", "consolidate.anchor_runs=[run]"]
                    + small) == 0
    assert "on the rows of run" in capsys.readouterr().out
    a = load_checkpoint(d, with_buffer=False)["agent"]["actor"]
    for k, v in load_checkpoint(str(tmp_path / "anchor1000"), with_buffer=False)["agent"]["actor"].items():
        torch.testing.assert_close(a[k], v, rtol=0, atol=0)
    for bad in ("[nope]", "[]", "run"):
        assert cli.main(["consolidate", run, "--out", str(tmp_path / "bad5"), "--set",
                         f"consolidate.init={first['path']}", "--set", "consolidate.anchor=1",
                         "--set", f"consolidate.anchor_runs={bad}"] + small) == 2
        assert "consolidate.anchor_runs" in capsys.readouterr().err
    assert cli.main(["consolidate", run, "--out", str(tmp_path / "bad2"), "--set",
                     f"consolidate.init={first['path']}", "--set", "consolidate.hidden=32",
                     "--set", "log.progress_bar=false", "--no-eval"]) == 2
    assert "consolidate.init" in capsys.readouterr().err
    # an output that cannot be written is refused before any training
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    assert cli.main(["consolidate", run, "--out", str(blocker)] + small) == 2
    assert f"cannot write to {blocker}" in capsys.readouterr().err


# ----------------------------------------------------------------------------------- rover env
def test_rover_environment_integration(tmp_path):
    """On ernest/Step-v0 with the C++ vector env (next-step autoreset): the env's own layout and
    normalisation table drive the noise, an interrupted run resumes exactly, and the passive-bogie
    baseline is evaluated on the evaluation seeds. (Learning curves are benchmarks, not tests.)"""
    sets = {"env.scenario": "step", "env.id": "null", "env.num_envs": 2, "td3.hidden": 16,
            "random_steps": 60, "learning_starts": 60, "total_steps": 200,
            "eval.every_steps": 0, "eval.episodes": 1, "checkpoint.every_steps": 100,
            "eval.baseline": "{action: [1, 0, 0], kwargs: {passive: true}}"}
    cfg = small_cfg(**sets)
    full = Trainer(cfg, str(tmp_path / "full"))
    assert full.autoreset == "next" and full.obs_dim == 45 and full.act_dim == 3
    lay = full.eval_env.unwrapped.observation_layout
    assert full.layout is lay
    idx, std = lay.noise_std_normalised()
    assert sorted(idx.tolist()) == list(range(6, 30))
    np.testing.assert_allclose(full.buffer.noise_std[np.argsort(full.buffer.noise_idx)],
                               std[np.argsort(idx)], rtol=1e-6)
    np.testing.assert_allclose(std[np.argsort(idx)][:3], 10.0 / lay.scale[6:9], rtol=1e-6)
    res_full = full.train()
    full.close()
    assert res_full["baseline"]["length"] > 0
    part = Trainer(cfg, str(tmp_path / "part"))
    part.train(total_steps=100)
    part.close()
    resumed = Trainer(cfg, str(tmp_path / "part"), resume=True)
    resumed.train()
    resumed.close()
    for a, b in zip(full.agent.actor.parameters(), resumed.agent.actor.parameters()):
        assert torch.equal(a, b)
    assert np.array_equal(full.buffer.obs, resumed.buffer.obs)
    meta = export_actor(full.agent.actor, lay, str(tmp_path / "rover.pt"))
    assert meta["obs_dim"] == 45 and meta["layout_version"] == lay.version
