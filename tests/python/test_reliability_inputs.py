"""Objects handed out by an environment outlive its reset, and inputs that used to give NaN,
inf or a silently wrong answer are refused with an error naming the parameter."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest


def test_scenario_and_mapper_kept_across_reset_stay_valid():
    # In a subprocess: a reference into the replaced objects would read freed memory.
    code = """
import numpy as np
from ernest_cpp import dynamics as D
from ernest_cpp.envs import core as E
from ernest_cpp.envs import make_options
env = E.RoverEnv(D.RoverParameters(), make_options("rockfield", terrain_source="stereo"))
env.reset(1)
sc, mapper = env.scenario, env.mapper
heights, name, path = sc.heights.copy(), sc.name, sc.path.heading
for seed in (2, 3):
    env.reset(seed)
    env.step(np.zeros(3))
assert env.scenario is not sc and env.mapper is not mapper
assert np.array_equal(sc.heights, heights) and sc.name == name and sc.path.heading == path
assert np.isfinite(sc.height(1.0, 0.0))
frames = mapper.frames
mapper.capture(np.array([0.0, 0.0, 0.5]), np.eye(3))
assert mapper.frames == frames + 1
assert np.isfinite(mapper.map.heights).any()
print("ok")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip().endswith("ok")


# ---- parameter structs are validated by the functions that take them ---------------------------

def test_helpers_validate_their_parameter_structs():
    from ernest_cpp import dynamics as D, sensing as SE

    limits = SE.ActionLimits()
    limits.roll_rate_max = 0.0
    with pytest.raises(ValueError, match=r"ActionLimits\.roll_rate_max = 0"):
        SE.command_to_action(np.zeros(3), limits)
    with pytest.raises(ValueError, match=r"ActionLimits\.roll_rate_max"):
        SE.action_to_command(np.zeros(3), limits)
    scales = SE.ObservationScales()
    scales.action = 0.0
    with pytest.raises(ValueError, match=r"ObservationScales\.action = 0"):
        SE.build_observation(SE.ObservationInputs(), scales)
    motor = D.MotorParameters()
    motor.torque_constant = 0.0
    with pytest.raises(ValueError, match=r"torque_constant = 0 is outside the allowed range"):
        D.motor_electrical(motor, 1.0, 1.0)
    weights = SE.RewardWeights()
    weights.dt = 5e-324
    with pytest.raises(ValueError, match=r"RewardWeights\.dt = .* outside the allowed range"):
        weights.validate()
    with pytest.raises(ValueError, match=r"RewardWeights\.dt"):
        SE.compute_reward(SE.PathLine(), 0.0, 0.0, 0.1, 0.0, 0.0, weights)


@pytest.mark.parametrize("call, name", [
    ("S.slip_ratio(math.nan, 0.1, 1e4)", "vx"),
    ("ST.nesm_edge(np.array([math.nan, 0, 0]), np.array([1., 0, 0]), np.array([.5, .5, 1]), "
     "np.array([0, 0, 1.]), True)", "a must be finite"),
    ("SE.PathLine().lateral_deviation(-math.inf, 0.0)", "x and y must be finite"),
    ("SE.PathLine().progress(0.0, 0.0, math.nan, 0.0)", "must be finite"),
    ("SE.PathLine().heading_deviation(math.inf)", "yaw must be finite"),
    ("O.squirming().position(math.nan)", "t must be finite"),
    ("F.path_length(np.array([[0.0, math.nan], [0.0, 1.0]]))", "path must be finite"),
    ("F.path_length(np.array([[0.0, 1e308, -1e308]]))", "overflows"),
    ("P.mask_iou(np.array([[0.3, 0.2]]), np.array([[0.5, 0.1]]))", "bool or integer"),
    ("P.mask_iou(np.array([[2, 0]]), np.array([[1, 0]]))", "only 0 and 1"),
])
def test_non_finite_or_meaningless_input_is_refused(call, name):
    from ernest_cpp import footfall as F, opt as O, perception as P, sensing as SE, soil as S
    from ernest_cpp import statics as ST

    with pytest.raises((ValueError, TypeError), match=name):
        eval(call, {"math": math, "np": np, "S": S, "ST": ST, "SE": SE, "O": O, "F": F, "P": P})


def test_mask_iou_of_boolean_and_integer_masks():
    from ernest_cpp import perception as P

    a = np.array([[1, 1, 0, 0]], dtype=np.uint8)
    assert P.mask_iou(a, a.astype(bool)) == 1.0
    assert P.mask_iou(a, np.array([[1, 0, 0, 1]])) == pytest.approx(1 / 3)


# ---- environments ------------------------------------------------------------------------------

def test_env_arguments_are_checked_and_named():
    import gymnasium as gym

    import ernest_cpp.envs  # noqa: F401  (registers the ids)
    from ernest_cpp.envs import ErnestEnv, ErnestVectorEnv

    with pytest.raises(TypeError, match=r"soil = 3 must be a str"):
        gym.make("ernest/Flat-v0", soil=3)
    assert gym.make("ernest/Flat-v0", soil=None).unwrapped.options.soil == "m90"  # the scenario's
    env = gym.make("ernest/Flat-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action must be numbers in \[-1, 1\], got 'abc'"):
        env.step("abc")
    for seed in (2**64, -1):
        with pytest.raises(ValueError, match=r"seed = .* outside the allowed range \[0, 1844"):
            env.reset(seed=seed)
    env.reset(seed=2**64 - 1)
    vec = ErnestVectorEnv(2, 1, "flat")
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must be \(2, 3\), got \(3,\)"):
        vec.step(np.zeros(3))
    with pytest.raises(ValueError, match="actions must be numbers"):
        vec.step("abc")
    state = env.unwrapped.__getstate__()
    state["scenario_name"] = "lava"
    with pytest.raises(ValueError, match=r"scenario = 'lava'; allowed:"):
        ErnestEnv.__new__(ErnestEnv).__setstate__(state)


def test_changed_params_and_options_apply_at_the_next_reset():
    from ernest_cpp.envs import ErnestEnv

    env = ErnestEnv("flat")
    env.reset(seed=0)
    env.options.episode_duration = 1.0  # two policy steps
    env.step(np.zeros(3))  # the episode in progress keeps its 60 s
    env.reset(seed=0)
    assert env.step(np.zeros(3))[3] is False
    assert env.step(np.zeros(3))[3] is True
    env.options.weights.w_s = -1.0
    with pytest.raises(ValueError, match=r"RewardWeights\.w_s = -1"):
        env.reset(seed=0)
    env.options.weights.w_s = 2.0
    env.params.wheel_radius = -1.0
    with pytest.raises(ValueError, match="wheel_radius"):
        env.reset(seed=0)


# ---- command lines -----------------------------------------------------------------------------

def test_cli_refuses_ignored_or_meaningless_arguments(tmp_path, capsys):
    from ernest_cpp import cli

    with pytest.raises(SystemExit) as exc:
        cli.main(["footfall", "--cell", "0", "--out", str(tmp_path / "ff")])
    assert exc.value.code == 2
    assert "--cell: 0 is outside the allowed range [0.005, 0.5]" in capsys.readouterr().err
    assert cli.main(["statics", "--steps", "liftoff", "--policy", "/nonexistent.pt",
                     "--out", str(tmp_path / "st")]) == 2
    assert "--policy /nonexistent.pt: no such file" in capsys.readouterr().err
    assert cli.main(["statics", "--steps", "sag", "--policy", __file__,
                     "--out", str(tmp_path / "st")]) == 2
    assert "only by the liftoff step" in capsys.readouterr().err
    assert cli.main(["slope-demo", "--soils", "", "--out", str(tmp_path / "sd")]) == 2
    assert "--soils = '' names no soil" in capsys.readouterr().err
    assert not (tmp_path / "sd").exists() and not (tmp_path / "st").exists()


def test_a_policy_returning_nan_is_named_by_its_file(tmp_path):
    import json

    import torch

    from ernest_cpp import sensing
    from ernest_cpp.envs import ErnestEnv
    from ernest_cpp.evaluate import LEARNED, controllers
    from ernest_cpp.rl.export import ExportedPolicy, _quiet_jit, export_actor, save_stamped
    from ernest_cpp.rl.networks import Actor
    from ernest_cpp.rl.policy_file import METADATA_FILE, PLACEHOLDER, POLICY_KEY

    class NanOut(ExportedPolicy):  # finite for the zero observation (checked at load), NaN else
        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            return 0.0 * obs[..., :3] + torch.sqrt(-obs.abs().sum(-1, keepdim=True))

    env = ErnestEnv("flat")
    actor = Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 16)
    good = str(tmp_path / "good.pt")
    export_actor(actor, env.observation_layout, good)
    extra = {METADATA_FILE: ""}
    with _quiet_jit():
        torch.jit.load(good, _extra_files=extra)
        module = torch.jit.script(NanOut(actor, env.observation_layout, 2.0))
    text = extra[METADATA_FILE].decode()
    bad = str(tmp_path / "nan_policy.pt")
    save_stamped(module, text.replace(json.loads(text)[POLICY_KEY], PLACEHOLDER), bad)
    policy, _ = controllers(bad)[LEARNED]
    obs, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match=r"nan_policy\.pt: the policy returned a non-finite command"):
        policy(obs, env)
