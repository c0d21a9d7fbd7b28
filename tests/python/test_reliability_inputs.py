"""Objects handed out by an environment outlive its reset, and inputs that used to give NaN,
inf or a silently wrong answer are refused with an error naming the parameter."""

from __future__ import annotations

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
