"""FootFall gait planning and execution in simulation from Python (seed 003 §5.3.1, §4.1): the demo
figure and its numbers, the skeleton gait's reverse wave, and ValueError/WalkerSimDiverged for bad
input."""

import math

import numpy as np
import pytest

from ernest_cpp import footfall_gait, walker as W, walker_sim as WS


@pytest.fixture(scope="module")
def sdm_b():
    return W.WalkerModel(W.sdm_b_parameters())


def test_demo_writes_the_figure_and_reports_the_lesson(tmp_path):
    r = footfall_gait.demo(tmp_path, cycles=4)
    assert (tmp_path / "footfall_gait.png").stat().st_size > 10_000
    assert r["sequence"] == [0, 1, 5, 2, 4, 3]
    # both plans keep the requested clearance on paper; only the compensated one keeps it executed
    assert r["rigid_planned_clearance"] >= 0.03 - 1e-9 and r["compensated_planned_clearance"] >= 0.03 - 1e-9
    assert r["rigid_executed_clearance"] < 0.0 < r["compensated_executed_clearance"]
    assert r["compensated_lift"] > r["rigid_lift"]
    assert r["min_support_margin"] > 0.0
    assert r["periodicity_error"] < 1e-3
    assert r["sag_error_lifted"] < 0.005


def test_gait_plan_from_python(sdm_b):
    o = W.GaitPlannerOptions()
    o.cycles = 1
    plan = W.plan_gait(sdm_b, sdm_b.standard_body_pose()[:3, 3], sdm_b.standard_configuration, o)
    assert plan.sequence == W.reverse_wave_sequence(sdm_b, 0.0)
    assert np.asarray(plan.step_lengths).shape == (1, 6)
    steps = [e for e in plan.events if e.kind == W.GaitEventKind.Step]
    assert [e.leg for e in steps] == plan.sequence
    for e in steps:  # the stepping foot moved along +x by the reported length, the others stayed
        d = np.asarray(e.feet_after) - np.asarray(e.feet_before)
        np.testing.assert_allclose(d[:, e.leg], [e.length, 0, 0], atol=1e-9)
        np.testing.assert_allclose(np.delete(d, e.leg, axis=1), 0.0, atol=1e-12)


def test_bad_input_is_a_value_error(sdm_b):
    o = W.GaitPlannerOptions()
    o.max_step = math.nan
    with pytest.raises(ValueError, match="max_step"):
        W.plan_gait(sdm_b, [0, 0, 1.75], sdm_b.standard_configuration, o)
    with pytest.raises(ValueError, match="sequence"):
        o = W.GaitPlannerOptions()
        o.sequence = [0, 1, 2]
        o.validate(6)
    s = WS.WalkerSimOptions()
    s.dt = -1.0
    with pytest.raises(ValueError, match="dt"):
        WS.WalkerSim(sdm_b, sdm_b.standard_body_pose(), sdm_b.standard_configuration, [], s)
    sim = WS.WalkerSim(sdm_b, sdm_b.standard_body_pose(), sdm_b.standard_configuration)
    q = np.array(sdm_b.standard_configuration)
    q[0, 0] = math.nan
    with pytest.raises(ValueError):
        sim.step(q)
    rock = WS.Rock()
    rock.half_extents = [0.1, -0.1, 0.1]
    with pytest.raises(ValueError, match="half_extents"):
        rock.validate()


def test_the_lesson_holds_on_t12_too():
    # T12 (seven joints a leg, 2.15 m, heavier): its chassis sags 5.2 cm on six wheels (m g / 6 k)
    # and more with a leg up; the rigid plan hits the rock, the compensated one clears it.
    t12 = W.WalkerModel(W.t12_parameters())
    r = WS.run_sag_scenario(t12, WS.SagScenarioOptions())
    weight = t12.params.total_mass() * t12.params.gravity
    np.testing.assert_allclose(np.asarray(r.rigid_corners) - np.asarray(r.measured_six_corners),
                               weight / (6 * WS.WalkerSimOptions().contact_stiffness), atol=5e-4)
    assert r.rigid_run.min_rock_clearance < 0.0 < r.compensated_run.min_rock_clearance
    assert r.lifted_error < 0.003
