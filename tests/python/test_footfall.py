"""ernest_cpp.footfall from Python: the stability map as numpy arrays (green/red/none), a planned
step re-checked densely with numpy-side sampling, ValueError for NaN input and bad options, the
explicit no-plan answers, and `ernest footfall` run small."""

import json
import math

import numpy as np
import pytest

from ernest_cpp import dynamics as D
from ernest_cpp import footfall as F
from ernest_cpp import walker as W
from ernest_cpp.cli import main


@pytest.fixture(scope="module")
def scene():
    model = W.WalkerModel(W.sdm_b_parameters())
    body, q = model.standard_body_pose(), model.standard_configuration
    feet = model.contact_points(body, q)
    return model, body, q, feet, F.rock_field(F.RockFieldOptions(), feet[:2])


def test_stability_map_arrays_and_plot(scene, tmp_path):
    model, body, q, feet, terrain = scene
    o = F.StabilityMapOptions()
    o.cell = 0.05
    m = F.stability_map(model, terrain, body, q, 0, o)
    st = m["status"]
    assert st.dtype == np.uint8 and st.shape == (m["x"].size, m["y"].size)
    assert set(np.unique(st)) <= {0, 1, 2} and (st == 2).sum() > 50
    assert np.all(np.isnan(m["margin"][st == 0])) and np.all(m["margin"][st == 2] > 0)
    # cells outside the reach are never reachable
    xx, yy = np.meshgrid(m["x"], m["y"], indexing="ij")
    far = np.hypot(xx - m["hip"][0], yy - m["hip"][1]) > m["reach"]
    assert np.all(st[far] == 0)
    F.plot_stability_map(m, tmp_path / "map.png", terrain, feet)
    assert (tmp_path / "map.png").stat().st_size > 10_000


def test_step_is_free_when_sampled_densely(scene):
    model, body, q, feet, terrain = scene
    so = F.StepOptions()
    so.map.cell = 0.05
    step = F.plan_step(model, terrain, body, q, 0, feet[0, 0] + 0.35, feet[1, 0], so)
    assert step.solved, step.reason
    assert step.smoothing.length <= step.plan.length + 1e-12
    exact = F.CollisionOptions()
    exact.environment_clearance = exact.own_leg_clearance = 0.0
    exact.clearance_table = np.zeros((7, 8))
    checker = F.LegCollisionChecker(model, terrain, step.planning_body, q, 0, exact)
    path = step.path
    # every 1e-3 rad along the edges between the waypoints above start and goal, with the wheel
    for k in range(1, path.shape[1] - 2):
        a, b = path[:, k], path[:, k + 1]
        n = max(1, math.ceil(np.abs(b - a).max() / 1e-3))
        assert all(checker.valid(a + t * (b - a)) for t in np.linspace(0, 1, n + 1))
    sag = F.predict_swing_sag(model, body, q, 0)
    assert np.allclose(step.planning_body, sag.sagged_body)
    assert sag.hip_drop[0] > 0


def test_errors_and_no_plan(scene):
    model, body, q, feet, terrain = scene
    with pytest.raises(ValueError, match="goal_x"):
        F.plan_step(model, terrain, body, q, 0, float("nan"), 0.0)
    o = F.PlannerOptions()
    o.time_limit = -1.0
    with pytest.raises(ValueError, match="time_limit"):
        o.validate()
    with pytest.raises(ValueError):
        D.HeightMap(np.zeros((0, 0)), 0.05, 0.0, 0.0)  # an empty map
    far = F.plan_step(model, terrain, body, q, 0, 20.0, 0.0)
    assert far.status == F.PlanStatus.NoPlan and "unreachable" in far.reason
    checker = F.LegCollisionChecker(model, terrain, body, q, 0)
    planner = F.LegPlanner(checker)
    r = planner.plan(q[:, 0], q[:, 0])
    assert not r.solved and r.reason == "start in collision"
    bad = q[:, 0].copy()
    bad[1] = np.nan
    with pytest.raises(ValueError):
        planner.plan(bad, q[:, 0])


def test_footfall_command_small(tmp_path):
    out = tmp_path / "ff"
    assert main(["footfall", "--out", str(out), "--cell", "0.06", "--no-variants"]) == 0
    r = json.loads((out / "footfall.json").read_text())
    c = r["cycle"]["compensated"]
    assert c["completed"], c["reason"]
    assert [s["leg"] for s in c["steps"]] == [0, 1, 5, 2, 4, 3]  # the reverse wave, +x
    assert c["min_rock_clearance"] > 0 and abs(c["executed_advance"] - c["planned_advance"]) < 0.01
    for k, s in enumerate(c["steps"]):
        assert s["smoothed_length"] <= s["raw_length"] + 1e-9 and s["swing_hip_sag"] > 0
        assert (out / f"step{k + 1}_leg{s['leg']}_path.png").exists()
    gif = out / "footfall_cycle.gif"
    assert 10_000 < gif.stat().st_size < 3_000_000 and gif.read_bytes()[:6] == b"GIF89a"
    assert (out / "footfall_cycle_maps.png").stat().st_size > 20_000
    assert "| step | leg |" in (out / "footfall_report.md").read_text()
    # §7.1: the torque-aware planner picks no foothold over its limit; today's does with a payload
    t = r["torque"]
    assert t["nominal"]["torque_aware"]["over_limit"] == 0 and t["payload"]["torque_aware"]["over_limit"] == 0
    assert t["payload"]["today"]["over_limit"] > 0
    assert (out / "footfall_torque.png").stat().st_size > 20_000
    assert "## Torque-aware footholds" in (out / "footfall_report.md").read_text()


def test_cycle_world_is_one_rock_field():
    """The planner's map is the simulator's boxes: at every box centre it reads the box top, and
    a point a grid step outside every (dilated) footprint reads the ground."""
    from ernest_cpp import footfall_cycle

    model = W.WalkerModel(W.sdm_b_parameters())
    rocks, terrain, _ = footfall_cycle.rock_world(model)
    assert len(rocks) == 60
    for rk in rocks:
        c, h = np.asarray(rk.centre), np.asarray(rk.half_extents)
        assert terrain.height(c[0], c[1]) >= c[2] + h[2] - 1e-12
    assert terrain.height(0.0, 0.0) == 0.0  # under the body: no rock within 1.4 m


def test_cycle_bad_options_are_value_errors():
    from ernest_cpp import walker_sim as WS

    model = W.WalkerModel(W.sdm_b_parameters())
    flat = D.HeightMap.flat(8.0, 8.0, 0.05, 0.0, -4.0, -4.0)
    o = WS.FootfallCycleOptions()
    o.stride = float("nan")
    with pytest.raises(ValueError, match="stride"):
        WS.run_footfall_cycle(model, flat, [], o)
    with pytest.raises(ValueError, match="spacing"):
        mo = WS.RockMapOptions()
        mo.spacing = 0.0
        WS.rock_height_map([], mo)


def test_cycle_that_cannot_start_writes_maps_and_no_gif(tmp_path):
    """A planner map with no reachable ground (a plateau 3 m above the feet) stops the cycle at its
    first step with the reason; the command's figures are still written, without an animation of
    nothing. The foothold relief tolerance reaches C++ (and is range-checked there)."""
    from ernest_cpp import footfall_cycle

    plateau = D.HeightMap.flat(8.0, 8.0, 0.05, 3.0, -3.5, -4.0)
    r = footfall_cycle.demo(tmp_path, cell=0.08, rocks=5, variants=False, log=lambda *_: None,
                            terrain=plateau, flat_tolerance=0.05)
    c = r["compensated"]
    assert not c["completed"] and "foothold" in c["reason"]
    assert r["gif_frames"] == 0 and not (tmp_path / "footfall_cycle.gif").exists()
    assert (tmp_path / "footfall_cycle_maps.png").exists()
    with pytest.raises(ValueError, match="flat_tolerance"):
        footfall_cycle.demo(tmp_path, cell=0.08, rocks=5, variants=False, log=lambda *_: None,
                            flat_tolerance=-0.01)


def test_wheel_rock_clearance_refuses_what_fcl_would_abort_on():
    from ernest_cpp import walker_sim as WS

    r = WS.Rock()
    r.centre = np.array([3.0, 0.0, 0.05])
    r.half_extents = np.array([0.1, 0.1, 0.1])
    centre, axle = np.array([2.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    assert WS.wheel_rock_clearance(centre, axle, 0.5, 0.3, r) > 0.0
    nan = float("nan")
    for args, name in (((centre, axle, 0.5, nan, r), "width"), ((centre, axle, nan, 0.3, r), "radius"),
                       ((np.array([nan, 0, 0]), axle, 0.5, 0.3, r), "centre"),
                       ((centre, np.array([0, nan, 0]), 0.5, 0.3, r), "axle"),
                       ((centre, np.zeros(3), 0.5, 0.3, r), "axle")):
        with pytest.raises(ValueError, match=name):
            WS.wheel_rock_clearance(*args)
