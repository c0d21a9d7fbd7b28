"""Optional settings are None when unset, never a 0 or -1 that stands for "default" or "off": a
set value must be a real one, and nonsense is refused naming the field and its range."""

from __future__ import annotations

import numpy as np
import pytest

from ernest_cpp import footfall as F, perception as P, statics as S, walker_sim as WS
from ernest_cpp.envs import make_options
from ernest_cpp.envs.core import default_soil


@pytest.mark.parametrize("make, field, default, bad, message", [
    (F.PlannerOptions, "range", 1.0, 0.0, r"PlannerOptions.range = 0 must be finite and > 0"),
    (WS.FootfallCycleOptions, "steps", None, 0, r"FootfallCycleOptions.steps = 0 is outside the "
                                                 r"allowed range \[1, 1000\]"),
    (WS.ExecutionOptions, "frame_interval", None, 0.0,
     r"ExecutionOptions.frame_interval = 0 must be finite and > 0"),
    (P.StereoMatcherOptions, "max_lr_difference", 1, -1,
     r"StereoMatcherOptions.max_lr_difference = -1 is outside the allowed range \[0, 1024\]"),
])
def test_unset_is_none_and_a_sentinel_is_refused(make, field, default, bad, message):
    o = make()
    assert getattr(o, field) == default
    setattr(o, field, None)
    assert getattr(o, field) is None
    if not isinstance(o, WS.FootfallCycleOptions):  # whose validate() takes the joint count
        o.validate()
    with pytest.raises(ValueError, match=message):
        setattr(o, field, bad)
    assert getattr(o, field) is None  # a refused value leaves the field as it was


def test_the_planner_takes_ompls_default_range_when_unset():
    o = F.PlannerOptions()
    o.range = None
    o.validate()
    o.range = 2.5
    assert o.range == 2.5


def test_load_pose_names_itself_or_its_index():
    pose = S.slope_pose(0.0, 0.0, 0.0)
    pose.loads = np.array([np.nan, 1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"^LoadPose.loads"):
        pose.validate()
    with pytest.raises(ValueError, match=r"^poses\[3\].loads"):
        pose.validate(index=3)


def test_an_env_stands_on_its_scenarios_soil_unless_one_is_chosen():
    assert default_soil("bickler") == "dry_sand" and default_soil("slope") == "m90"
    assert make_options("bickler").soil == "dry_sand"
    assert make_options("bickler", soil="wet_sand").soil == "wet_sand"
    with pytest.raises(ValueError, match="unknown scenario 'rock_field'"):
        default_soil("rock_field")


def test_a_configuration_path_traces_no_wheel_when_leg_is_none():
    from ernest_cpp import walker as W

    model = W.WalkerModel(W.sdm_b_parameters())
    q = model.standard_configuration
    sim = WS.WalkerSim(model, model.standard_body_pose(), q, [])
    opts = WS.ExecutionOptions()
    opts.pause = 0.0
    trace = WS.execute_configuration_path(sim, None, [q, q], opts)
    assert trace.min_rock_clearance == float("inf") and len(trace.frame_time) == 0
    with pytest.raises(ValueError, match=r"leg = -1 is outside the allowed range \[0, 5\]"):
        WS.execute_configuration_path(sim, -1, [q, q], opts)
