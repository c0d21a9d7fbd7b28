"""Stable-Baselines3 on the C++ batched environments through ``envs.sb3.ErnestSB3VecEnv``:
the adapter gives exactly the transitions of SB3's own DummyVecEnv over the
single Gymnasium env (SB3's autoreset and terminal-observation handling as the reference), and
SB3's TD3 trains through it unmodified."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from stable_baselines3 import TD3
from stable_baselines3.common.vec_env import DummyVecEnv

import ernest_cpp.envs  # noqa: F401  (registers the ids)
from ernest_cpp.envs.sb3 import ErnestSB3VecEnv

KW = {"episode_length": 1.5, "soil": "m90"}  # 3 policy steps per episode: several autoresets


def test_adapter_matches_dummy_vec_env_of_single_envs():
    n = 3
    ours = ErnestSB3VecEnv("ernest/Ripples-v0", n, **KW)
    ref = DummyVecEnv([lambda: gym.make("ernest/Ripples-v0", **KW) for _ in range(n)])
    ours.seed(5)
    ref.seed(5)
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(8):
        a = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        o1, r1, d1, i1 = ours.step(a)
        o2, r2, d2, i2 = ref.step(a)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_allclose(r1, r2, rtol=0, atol=1e-6)
        np.testing.assert_array_equal(d1, d2)
        for k in np.flatnonzero(d1):
            ends += 1
            np.testing.assert_array_equal(i1[k]["terminal_observation"],
                                          i2[k]["terminal_observation"])
            assert i1[k]["TimeLimit.truncated"] == i2[k]["TimeLimit.truncated"]
    assert ends >= 2 * n
    assert ours.get_attr("episode_seed") == [e.unwrapped.core.episode_seed for e in ref.envs]
    ours.close()
    ref.close()


def test_sb3_td3_trains_through_the_adapter():
    # one torch thread: on a shared 2-core machine multi-threaded small updates were ~40x slower
    # (measured 117 s vs 2.9 s)
    old = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        _train_td3()
    finally:
        torch.set_num_threads(old)


def _train_td3():
    env = ErnestSB3VecEnv("ernest/Flat-v0", 4, episode_length=5.0)
    torch.manual_seed(0)
    model = TD3("MlpPolicy", env, learning_starts=400, batch_size=64, buffer_size=5000,
                policy_kwargs={"net_arch": [32, 32]}, seed=0, device="cpu", verbose=0)
    before = [p.detach().clone() for p in model.actor.parameters()]
    model.learn(total_timesteps=2000)
    assert model.num_timesteps == 2000
    assert model.replay_buffer.size() == 2000 // 4  # per-env rows
    stored = model.replay_buffer.observations[:model.replay_buffer.size()]
    assert np.all(np.isfinite(stored)) and stored.shape[1:] == (4, 45)
    assert any(not torch.equal(a, b) for a, b in zip(before, model.actor.parameters()))
    action, _ = model.predict(env.reset(), deterministic=True)
    assert action.shape == (4, 3) and np.all(np.abs(action) <= 1)
    env.close()


def _runtime_exe() -> str:
    import glob
    import os

    exe = os.environ.get("ERNEST_RUNTIME_EXE", "")
    if exe and os.access(exe, os.X_OK):
        return exe
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    found = sorted(glob.glob(os.path.join(root, "build*", "cpp", "cpp", "runtime", "ernest_runtime")),
                   key=os.path.getmtime)
    assert found, "ernest_runtime not built: set ERNEST_RUNTIME_EXE"
    return found[-1]


def test_sb3_td3_model_exports_and_runs_in_evaluate_and_the_runtime(tmp_path):
    # `ernest export MODEL.zip`: SB3's actor (any widths) with the envs' scaling; `ernest
    # evaluate`'s policy path and the C++ runtime then give SB3's own actions.
    import subprocess

    from ernest_cpp import cli
    from ernest_cpp.evaluate import LEARNED, controllers

    old = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        env = ErnestSB3VecEnv("ernest/Ripples-v0", 2, **KW)
        torch.manual_seed(0)
        model = TD3("MlpPolicy", env, learning_starts=50, batch_size=32, buffer_size=1000,
                    policy_kwargs={"net_arch": [32, 24]}, seed=0, device="cpu", verbose=0)
        model.learn(total_timesteps=120)
        env.close()
        model.save(tmp_path / "td3.zip")
        policy = tmp_path / "policy.pt"
        assert cli.main(["export", str(tmp_path / "td3.zip"), "--out", str(policy)]) == 0

        learned, passive = controllers(str(policy))[LEARNED]  # ernest evaluate's checks and path
        assert not passive
        genv = gym.make("ernest/Ripples-v0", episode_length=5.0)
        obs, _ = genv.reset(seed=2)
        ours = []
        while True:
            a = np.asarray(learned(obs))
            sb3, _ = model.predict(obs, deterministic=True)
            np.testing.assert_allclose(a, sb3, rtol=0, atol=1e-5)
            ours.append(a)
            obs, _, term, trunc, _ = genv.step(a)
            if term or trunc:
                break
        ours = np.array(ours)
        assert len(ours) == 10 and np.ptp(ours, axis=0).max() > 1e-3  # it acts, and not constantly

        out = tmp_path / "actions.csv"
        r = subprocess.run([_runtime_exe(), "--policy", str(policy), "--scenario", "ripples",
                            "--seed", "2", "--duration", "5", "--actions", str(out)],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stdout + r.stderr
        cpp = np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:]
        np.testing.assert_allclose(cpp, ours, rtol=0, atol=1e-5)
    finally:
        torch.set_num_threads(old)
    with pytest.raises(Exception, match="TD3"):  # not a model: refused, naming what it expects
        from ernest_cpp.rl.export import actor_from_sb3
        (tmp_path / "junk.zip").write_bytes(b"not a zip")
        actor_from_sb3(tmp_path / "junk.zip")
