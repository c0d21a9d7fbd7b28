"""The scripted step climb (envs.climbing, seed 004 §5.3) and demonstrator experience in the replay
buffer (rl.demos)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

torch.set_num_threads(1)

import ernest_cpp.envs  # noqa: E402,F401
from ernest_cpp.envs.baselines import PassiveController  # noqa: E402
from ernest_cpp.envs.climbing import (BicklerCrossController, PhaseGait,  # noqa: E402
                                     StepClimbController)
from ernest_cpp.evaluate import run_episode  # noqa: E402
from ernest_cpp.reproduce import wheels_over  # noqa: E402
from ernest_cpp.rl import config as C  # noqa: E402
from ernest_cpp.rl import demos  # noqa: E402
from ernest_cpp.rl.trainer import Trainer  # noqa: E402


@pytest.mark.parametrize("seed", [0, 5])
def test_step_climb_gets_all_four_wheels_up_the_wheel_high_step(seed):
    """The 0.34 m step stops the passive bogie (no wheel on top); the scripted climb puts all four
    wheels on top, at different obstacle frictions (the seed draws it from [0.5, 0.9])."""
    _, _, passive_env, _ = run_episode("ernest/WheelStep-v0", {"episode_length": 40.0},
                                       PassiveController(), True, seed)
    assert wheels_over("step", passive_env) == 0
    _, _, env, info = run_episode("ernest/WheelStep-v0", {}, StepClimbController(), False, seed)
    assert wheels_over("step", env) == 4
    assert info["path_progress"] > 2.5  # past the step and on along the path
    wp = np.asarray(env.core.state.wheel_position)
    top = env.scenario.step_height
    assert np.all(wp[:, 2] > top + 0.1)  # wheel centres a radius above the step's top (0.17)


@pytest.mark.parametrize("seed", [0, 3])
def test_bickler_crossing_gets_the_rear_wheels_over_where_the_passive_bogie_is_trapped(seed):
    _, _, passive_env, _ = run_episode("ernest/BicklerTrap-v0", {"episode_length": 30.0},
                                       PassiveController(), True, seed)
    assert wheels_over("bickler", passive_env) == 2  # front over, rear trapped (§5.2, Fig. 17)
    _, _, env, _ = run_episode("ernest/BicklerTrap-v0", {"episode_length": 30.0},
                               BicklerCrossController(), False, seed)
    assert wheels_over("bickler", env) == 4


def test_demonstrations_from_another_environment(tmp_path):
    cfg = _cfg(**{"demos.controller": "bickler_cross", "demos.episodes": 1,
                  "demos.env": "ernest/BicklerTrap-v0", "demos.kwargs": "{episode_length: 3.0}"})
    data, _ = demos.collect("ernest/Step-v0", cfg, -np.ones(3), np.ones(3), log=lambda s: None)
    assert len(data["rew"]) == 6  # 3 s of the trap at 2 Hz, not the training env's 5 s
    env = ernest_cpp.envs.ErnestEnv("bickler", soil="dry_sand", episode_length=3.0)
    obs, _ = env.reset(seed=2000000)
    np.testing.assert_array_equal(obs, data["obs"][0])


def test_phase_gait_commands_stay_within_the_action_limits_and_follow_its_phases():
    g = PhaseGait([(0.0, 0.0, 0.0, 0.2), (1.0, 30.0, -20.0, 0.1)], trigger=10.0)
    env = ernest_cpp.envs.ErnestEnv("wheel_step")
    obs, _ = env.reset(seed=0)
    a = g(obs, env)  # trigger already met (10 m): the approach ends after this period
    assert g.phase == 1 and np.all(np.abs(a) <= 1.0)
    a = g(env.step(a)[0], env)
    assert a[1] == pytest.approx(1.0) and a[2] == pytest.approx(-1.0)  # rates saturate towards
    assert a[0] == pytest.approx(0.0)  # 0.1 m/s of [0, 0.2] -> 0 in [-1, 1]
    g.reset()
    assert g.phase == 0 and g.t == 0.0


@pytest.mark.parametrize("bad", [
    {"phases": []}, {"phases": [(1.0, 50.0, 0.0, 0.1)]}, {"phases": [(1.0, 0.0, 31.0, 0.1)]},
    {"phases": [(1.0, 0.0, 0.0, 0.3)]}, {"phases": [(-1.0, 0.0, 0.0, 0.1)]},
    {"phases": [(1.0, 0.0)]}, {"trigger": -0.1}, {"k_joint": 0.0}, {"max_steer_deg": 60.0}])
def test_phase_gait_rejects_bad_settings(bad):
    kw = {"phases": [(0.0, 0.0, 0.0, 0.2)], "trigger": 0.1}
    kw.update(bad)
    with pytest.raises(ValueError):
        PhaseGait(**kw)


def test_phase_gait_needs_the_environment():
    with pytest.raises(ValueError, match="environment"):
        StepClimbController()(np.zeros(45), None)


def _cfg(**over) -> dict:
    sets = {"env.scenario": "step", "env.num_envs": 1, "td3.hidden": 16, "random_steps": 20,
            "learning_starts": 20, "total_steps": 40, "eval.every_steps": 0,
            "checkpoint.every_steps": 20, "log.progress_bar": "false",
            "log.tensorboard": "false", "buffer_size": 2000,
            "env.kwargs": "{episode_length: 5.0}"}
    sets.update(over)
    return C.build_config("quick", None, [f"{k}={v}" for k, v in sets.items()])


def test_demonstrator_transitions_are_the_controllers_own(tmp_path):
    """collect() replays what the controller did: a fresh env stepped with the recorded actions
    gives the recorded observations, rewards and terminations."""
    cfg = _cfg(**{"demos.controller": "step_climb", "demos.episodes": 2})
    low, high = -np.ones(3), np.ones(3)
    data, returns = demos.collect("ernest/Step-v0", cfg, low, high, log=lambda s: None)
    n = len(data["rew"])
    assert n == 20 and len(returns) == 2  # two 5 s episodes at 2 Hz
    assert np.all(np.abs(data["act"]) <= 1.0)
    assert np.any(np.abs(data["act"][:, 1]) > 0.5)  # the gait swings the gimbal, unlike a drive
    env = ernest_cpp.envs.ErnestEnv("step", episode_length=5.0)
    obs, _ = env.reset(seed=2000000)
    for k in range(10):
        np.testing.assert_array_equal(obs, data["obs"][k])
        obs, r, term, _, _ = env.step(data["act"][k])
        np.testing.assert_array_equal(obs, data["next_obs"][k])
        assert r == pytest.approx(data["rew"][k], rel=1e-6)
    assert sum(data["rew"][:10]) == pytest.approx(returns[0], rel=1e-5)


def test_trainer_fills_demos_once_and_resumes_without_refilling(tmp_path):
    cfg = _cfg(**{"demos.controller": "step_climb", "demos.episodes": 1})
    t = Trainer(cfg, str(tmp_path / "run"))
    t.train(total_steps=20)
    t.close()
    assert t.demo_transitions == 10
    assert t.buffer.total_added == 10 + 20
    r = Trainer(cfg, str(tmp_path / "run"), resume=True)
    assert r.demo_transitions == 10
    r.train()
    r.close()
    assert r.buffer.total_added == 10 + 40  # no second set of demonstrations


@pytest.mark.parametrize("over, match", [
    ({"demos.controller": "walker", "demos.episodes": 1}, "demos.controller"),
    ({"demos.controller": "step_climb", "demos.episodes": -1}, "demos.episodes"),
    ({"demos.controller": "step_climb", "demos.episodes": 1.5}, "demos.episodes")])
def test_bad_demo_settings_are_refused_before_training(tmp_path, over, match):
    with pytest.raises(ValueError, match=match):
        Trainer(_cfg(**over), str(tmp_path / "run"))
