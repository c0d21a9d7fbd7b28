"""The environments as an outside client uses them: gym.make without importing
us first, pickling and deep copies, reset options, and a step before reset."""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import ernest_cpp.envs as E
from ernest_cpp import dynamics, perception, sensing

ACTIONS = [np.array([1.0, 0.3, -0.2]), np.array([0.5, -0.5, 0.4]), np.array([1.0, 0.0, 0.0])]


def test_gym_make_with_the_module_prefix_in_a_fresh_interpreter():
    # Gymnasium 1.x does not load the "gymnasium.envs" plugin entry point: the module prefix
    # imports ernest_cpp.envs, which registers the ids (README, Environments).
    code = ("import gymnasium as gym\n"
            "env = gym.make('ernest_cpp.envs:ernest/Slope-v0', episode_length=1.0)\n"
            "obs, info = env.reset(seed=0)\nprint(obs.shape, info['scenario'])\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "(45,) slope"


def _fields(obj, cls_names=("Options", "Parameters", "Scales", "Weights", "Limits")):
    """Every field of a bound struct, nested structs expanded (an independent walk)."""
    out = {}
    for name in dir(type(obj)):
        attr = getattr(type(obj), name)
        if isinstance(attr, property) and attr.fset is not None:
            v = getattr(obj, name)
            out[name] = _fields(v) if type(v).__name__.endswith(cls_names) else \
                (np.asarray(v).tolist() if isinstance(v, (np.ndarray, tuple, list)) else v)
    return out


def test_env_options_and_parameters_pickle_with_every_field():
    stereo = perception.StereoMapperOptions()
    stereo.fusion_rate = 1.0
    o = E.make_options("slope", soil="wet_sand", randomisation={"range_scale": 0.5,
                       "slope_angle_range_deg": (3.0, 7.0)}, fts_noise_force=2.5,
                       terrain_source="stereo", stereo=stereo)
    o.scales.torque = 41.0
    o.limits.vx_max = 0.15
    copies = [pickle.loads(pickle.dumps(o)), copy.deepcopy(o)]
    want = _fields(o)
    assert want["scenario"]["range_scale"] == 0.5 and want["stereo"]["fusion_rate"] == 1.0
    assert want["scales"]["torque"] == 41.0 and want["limits"]["vx_max"] == 0.15
    for c in copies:
        assert type(c) is type(o) and _fields(c) == want
        c.validate()
    p = dynamics.RoverParameters()
    p.chassis_mass = 61.0
    p.wheel_motor.gear_ratio = 123.0
    assert _fields(p)["wheel_motor"]["gear_ratio"] == 123.0 and _fields(p)["chassis_mass"] == 61.0
    assert _fields(pickle.loads(pickle.dumps(p))) == _fields(p)
    assert _fields(pickle.loads(pickle.dumps(sensing.RewardWeights()))) == \
        _fields(sensing.RewardWeights())


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_env_copies_run_the_same_episodes(how):
    env = gym.make("ernest/Ripples-v0", soil="m90", episode_length=3.0,
                   randomisation={"range_scale": 0.5})
    dup = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    assert dup.unwrapped.options.episode_duration == 3.0
    with pytest.raises(RuntimeError, match="reset"):
        dup.unwrapped.step(ACTIONS[0])  # a copy is the configured env, before its first reset
    runs = []
    for e in (env, dup):
        obs, info = e.reset(seed=11)
        traj = [obs]
        for a in ACTIONS:
            obs, reward, *_ = e.step(a)
            traj += [obs, np.float32(reward)]
        runs.append((info["episode_seed"], np.concatenate([np.ravel(t) for t in traj])))
    assert runs[0][0] == runs[1][0]
    np.testing.assert_array_equal(runs[0][1], runs[1][1])


def test_reset_options_unknown_keys_are_refused():
    env = gym.make("ernest/Flat-v0", episode_length=1.0)
    with pytest.raises(ValueError, match="unknown key.*start_x"):
        env.reset(seed=0, options={"start_x": 1.0})
    env.reset(seed=0, options={})  # empty is fine
    vec = E.make_vec("ernest/Flat-v0", 2, episode_length=1.0)
    with pytest.raises(ValueError, match="unknown key.*bogus"):
        vec.reset(seed=0, options={"bogus": 1})
    vec.close()


def test_step_before_reset_raises_in_the_single_and_the_vector_env():
    env = gym.make("ernest/Flat-v0", episode_length=1.0)
    with pytest.raises(RuntimeError, match="reset"):
        env.unwrapped.step(ACTIONS[0])
    vec = E.make_vec("ernest/Flat-v0", 2, episode_length=1.0)
    with pytest.raises(RuntimeError, match="reset"):
        vec.step(np.zeros((2, 3)))
    obs, _ = vec.reset(seed=0)
    obs, reward, term, trunc, info = vec.step(np.zeros((2, 3)))
    assert obs.shape == (2, 45) and np.all(np.isfinite(reward))
    vec.close()
