"""FootFall on the perception stack's terrain: the binding of terrain_from_map, its
errors, and the end-to-end path stereo → fused map → planner DEM → plan, re-checked densely
against the ground truth."""

import numpy as np
import pytest

from ernest_cpp import footfall as F
from ernest_cpp import footfall_terrain as FT
from ernest_cpp import walker as W


def _zero_clearance(n):
    o = F.CollisionOptions()
    o.environment_clearance = o.own_leg_clearance = 0.0
    o.clearance_table = np.zeros((n + 1, n + 2))
    return o


def test_arrays_round_trip_a_step_raised_by_k_sigma():
    # 1 m x 1 m at 1 cm: ground 0 for x < 0.5, a 0.2 m step beyond, sigma 2 cm, no holes
    x = np.arange(101) * 0.01
    h = np.where(x[:, None] < 0.5, 0.0, 0.2) * np.ones((1, 101))
    t = F.terrain_from_arrays(h, np.full(h.shape, 0.02 ** 2), 0.01, 0.0, 0.0)
    z = np.asarray(t.terrain.heights)
    assert z.shape == (21, 21)
    assert np.allclose(z[:9], 0.04) and np.allclose(z[11:], 0.24)  # h + 2 sigma
    assert np.allclose(z[9:11], 0.24)  # within one spacing of the step: its top (upper envelope)
    assert t.unknown == 0 and t.filled == 0 and t.observed == 21 * 21
    assert np.all(np.asarray(t.state) == int(F.TerrainCell.Observed))


def test_errors_are_clear():
    nan = np.full((30, 30), np.nan)
    with pytest.raises(ValueError, match="no observed cell"):
        F.terrain_from_arrays(nan, np.full((30, 30), np.inf), 0.01, 0.0, 0.0)
    with pytest.raises(ValueError, match="same shape"):
        F.terrain_from_arrays(np.zeros((30, 30)), np.zeros((30, 31)), 0.01, 0.0, 0.0)
    o = F.MapTerrainOptions()
    o.max_sigma = -1.0
    with pytest.raises(ValueError, match="max_sigma"):
        o.validate()
    with pytest.raises(ValueError, match="terrain source"):
        FT.planner_terrain("lidar", None, np.eye(4))
    with pytest.raises(ValueError, match="views"):
        FT.stereo_map(None, np.eye(4), views=0)


def test_plan_on_the_stereo_map_is_collision_free_on_the_ground_truth():
    model = W.WalkerModel(W.sdm_b_parameters())
    body, q = np.asarray(model.standard_body_pose()), np.asarray(model.standard_configuration)
    feet = np.asarray(model.contact_points(body, q))
    truth = F.rock_field(F.RockFieldOptions(), feet[:2])
    so = F.StepOptions()
    so.map.cell = 0.05
    gx, gy = feet[0, 0] + 0.35, feet[1, 0]
    r = FT.plan_step_from_stereo(model, truth, body, q, 0, gx, gy, so)
    t, step = r["terrain"], r["step"]
    # the stereo DEM: mostly seen, unseen parts are columns, never free ground
    assert t.observed + t.filled > 0.5 * (t.observed + t.filled + t.unknown)
    z, state = np.asarray(t.terrain.heights), np.asarray(t.state)
    assert np.all(z[state == int(F.TerrainCell.Unknown)] > t.top + 9.0)
    assert not r["goal_unknown"]
    assert step.solved, step.reason
    exact = F.LegCollisionChecker(model, truth, step.planning_body, q, 0, _zero_clearance(model.joints_per_leg))
    assert F.first_colliding_edge(exact, step.path, 1e-3, 1) == -1
    # against the ground truth the seen terrain is an upper envelope near the step's path
    w = F.wheel_track(model, step.planning_body, 0, np.asarray(step.path))
    seen = [(t.terrain.height(a, b), truth.height(a, b)) for a, b in w[:2].T if not t.unknown_at(a, b)]
    below = [s - g for s, g in seen if s < g - 0.03]
    assert len(seen) > 10 and not below, below


def test_cli_terrain_option():
    from ernest_cpp import cli

    parser, _ = cli.build_parser()
    assert parser.parse_args(["footfall"]).terrain == "truth"
    assert parser.parse_args(["footfall", "--terrain", "stereo"]).terrain == "stereo"
    with pytest.raises(SystemExit):
        parser.parse_args(["footfall", "--terrain", "lidar"])
