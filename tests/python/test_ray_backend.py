"""Training, consolidation and evaluation on a Ray cluster: a local two-CPU cluster,
the sync mode equal bit for bit to the local trainer, a killed worker recovered, and the toy
point mass learned through the async mode.

Ray is the optional extra ernest-cpp[ray]; the README's test command installs it, so these tests
run there and in CI. Without it they skip, naming the extra."""

from __future__ import annotations

import os
import shutil
import signal
import time

import numpy as np
import pytest
import torch

ray = pytest.importorskip(
    "ray", reason="needs the optional extra ernest-cpp[ray]: pip install 'ernest-cpp[ray]'")

torch.set_num_threads(1)

from ernest_cpp.rl import config as C  # noqa: E402
from ernest_cpp.rl.consolidate import consolidate_runs  # noqa: E402
from ernest_cpp.rl.ray_trainer import RayTrainer  # noqa: E402
from ernest_cpp.rl.toy_envs import PointMassEnv, optimal_return  # noqa: E402
from ernest_cpp.rl.checkpoints import load_checkpoint  # noqa: E402
from ernest_cpp.rl.trainer import Trainer  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    ray.init(address="local", num_cpus=2, include_dashboard=False, object_store_memory=80 << 20,
             log_to_driver=False, configure_logging=False)
    yield ray
    ray.shutdown()


def cfg_for(workers: int, per_worker: int, **over) -> dict:
    sets = ["env.id=ernest-toy/PointMass-v0", "td3.hidden=32", "td3.batch_size=64",
            "td3.actor_lr=0.001", "td3.critic_lr=0.001", "random_steps=100",
            "learning_starts=100", "total_steps=600", "eval.every_steps=300", "eval.episodes=2",
            "checkpoint.every_steps=300", "log.progress_bar=false", "log.tensorboard=false",
            "buffer_size=5000", f"env.num_envs={workers * per_worker}",
            f"ray.num_workers={workers}", f"ray.envs_per_worker={per_worker}",
            "ray.learner_device=cpu"]  # the local trainer's device, also on a GPU machine
    return C.build_config("quick", None, sets + [f"{k}={v}" for k, v in over.items()])


def assert_same_run(a: Trainer, b: Trainer) -> None:
    assert a.step == b.step and a.agent.updates == b.agent.updates
    sd_a, sd_b = a.agent.state_dict(), b.agent.state_dict()
    for net in ("actor", "critic", "actor_target", "critic_target"):
        for k, v in sd_a[net].items():
            assert torch.equal(v, sd_b[net][k]), (net, k)
    for f in ("obs", "act", "rew", "next_obs", "done"):
        assert np.array_equal(getattr(a.buffer, f), getattr(b.buffer, f)), f


def test_sync_mode_equals_local_and_checkpoints_cross_backends(cluster, tmp_path):
    cfg = cfg_for(2, 2)
    local = Trainer(cfg, str(tmp_path / "local"))
    local.train()
    local.close()
    rt = RayTrainer(cfg, str(tmp_path / "ray"))
    assert rt.n == 4 and len(set(rt.vec.pids())) == 2  # two worker processes, two envs each
    rt.train(total_steps=300)  # ends with the checkpoint at 300
    shutil.copytree(tmp_path / "ray", tmp_path / "ray_then_local")
    rt.train()
    assert_same_run(local, rt)
    assert rt.lost_transitions == 0 and rt.vec.env_steps.tolist() == [300, 300]
    rt.close()
    # A checkpoint taken with Ray resumes locally and continues exactly like the local run.
    resumed = Trainer(cfg, str(tmp_path / "ray_then_local"), resume=True)
    assert resumed.step == 300
    resumed.train()
    assert_same_run(local, resumed)
    resumed.close()
    # Consolidation's evaluation table fanned out over the cluster equals the in-process one.
    cc = cfg_for(2, 2, **{"consolidate.iterations": 20, "consolidate.hidden": 32,
                          "consolidate.eval_episodes": 3, "consolidate.batch_size": 64})
    runs = [str(tmp_path / "local"), str(tmp_path / "ray")]
    here = consolidate_runs(runs, cc, str(tmp_path / "c1"), log=lambda *a: None)["table"]
    there = consolidate_runs(runs, cc, str(tmp_path / "c2"), log=lambda *a: None,
                             ray={"address": None})["table"]
    assert here == there and len(here) == 3


def test_killed_worker_is_restarted_and_the_loss_counted(cluster, tmp_path):
    cfg = cfg_for(2, 1, total_steps=400, **{"checkpoint.every_steps": 400})
    tr = RayTrainer(cfg, str(tmp_path / "run"), log=lambda *a: None)
    pid0, pid1 = tr.vec.pids()
    step, calls = tr.vec.step, [0]

    def step_and_kill(actions):
        calls[0] += 1
        if calls[0] == 50:  # mid-run, mid-episode: SIGKILL worker 0's process
            os.kill(pid0, signal.SIGKILL)
            for _ in range(200):
                try:
                    os.kill(pid0, 0)
                except ProcessLookupError:
                    break
                time.sleep(0.05)
        return step(actions)

    tr.vec.step = step_and_kill
    res = tr.train()
    # 49 steps of 2 transitions, the lost step's 1, then 2 a step: 401 when 400 is passed
    assert res["step"] == 401 and res["lost_transitions"] == 1  # one env, one step
    new0, same1 = tr.vec.pids()
    assert new0 != pid0 and same1 == pid1 and tr.vec.restarts == [1, 0]
    assert load_checkpoint(str(tmp_path / "run"))["state"]["lost_transitions"] == 1
    assert len(tr.buffer) == 401
    tr.close()


def test_point_mass_learns_through_async_mode(cluster, tmp_path):
    cfg = cfg_for(2, 2, **{"ray.mode": "async", "ray.collect_steps": 5,
                           "ray.weight_sync_updates": 10, "td3.hidden": 64,
                           "random_steps": 500, "learning_starts": 500, "total_steps": 3000,
                           "eval.every_steps": 1500, "eval.episodes": 20,
                           "checkpoint.every_steps": 1500, "log.tensorboard": True})
    tr = RayTrainer(cfg, str(tmp_path / "run"), log=lambda *a: None)
    before = tr.run_eval()["return"]
    pid1 = tr.vec.pids()[1]
    advance, killed = tr._advance, []

    def advance_and_kill(run, added):  # worker 1 dies once, mid-run, with calls queued
        if tr.step >= 1000 and not killed:
            os.kill(pid1, signal.SIGKILL)
            killed.append(pid1)
        return advance(run, added)

    tr._advance = advance_and_kill
    res = tr.train()
    zero, best = 0.0, 0.0
    env = PointMassEnv()
    for k in range(20):
        env.reset(seed=cfg["eval"]["seed"] + k)
        zero += -10 * abs(env.x - env.g) / 20
        best += optimal_return(env.x, env.g) / 20
    after = res["last_eval"]["return"]
    assert before < best + 0.5 * (zero - best)
    assert after > best + 0.15 * (zero - best), (before, after, zero, best)
    # Batches of 2 envs x 5 steps, two queued per worker: the run stops within those of the
    # total; the dead worker's queued calls are lost (10 env steps each), then it is replaced.
    assert 3000 <= res["step"] <= 3000 + 4 * 10
    assert res["lost_transitions"] in (10, 20) and tr.vec.restarts == [0, 1]
    assert 0 <= tr.lag.max() < 10 * 8  # weights at most a few broadcasts old
    tags = os.listdir(tmp_path / "run" / "tb")
    assert tags  # TensorBoard events with perf/worker*/... written
    tr.close()
    # The async checkpoint resumes locally (same state layout, same number of simulations).
    cont = Trainer(cfg, str(tmp_path / "run"), resume=True)
    assert cont.step == res["step"]
    cont.close()


def test_evaluate_fans_its_episodes_out_with_the_same_report(cluster, tmp_path, monkeypatch):
    from ernest_cpp import cli, evaluate

    # two short courses (2 s episodes) keep it fast; the tasks get the courses with the job
    monkeypatch.setattr(evaluate, "COURSES", [
        ("Bickler trap (dry sand)", "ernest/BicklerTrap-v0", {"episode_length": 2.0}),
        ("20 deg slope, dry M90", "ernest/SlopeEval-v0", {"soil": "m90", "episode_length": 2.0})])
    tables = []
    for backend in ("local", "ray"):
        out = tmp_path / backend
        assert cli.main(["evaluate", "--out", str(out), "--no-video", "--backend", backend]) == 0
        tables.append([ln for ln in (out / "report.md").read_text().splitlines()
                       if ln.startswith("| ")])
        assert (out / "paths.png").stat().st_size > 1000
    assert tables[0] == tables[1] and len(tables[0]) == 1 + 4  # the header, 2 x 2 episodes
