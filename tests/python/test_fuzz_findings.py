"""What the property-based fuzzing (test_fuzz.py) found, each as a plain regression test: an
input that crashed, hung, returned NaN or inf without saying so, or raised an error that did not
name the parameter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ernest_cpp import dynamics as D
from ernest_cpp import footfall as F
from ernest_cpp import opt as O
from ernest_cpp import perception as P
from ernest_cpp import soil as S
from ernest_cpp import walker as W
from ernest_cpp import walker_sim as WS


@pytest.fixture(scope="module")
def walker():
    m = W.WalkerModel(W.sdm_b_parameters())
    return m, m.standard_body_pose(), m.standard_configuration


@pytest.fixture(scope="module")
def ground():
    return D.HeightMap.flat(8.0, 8.0, 0.05, 0.0, -4.0, -4.0)


def test_transition_cost_refuses_a_duration_outside_the_solver_bounds():
    # x[0] = T = 0 gave an infinite cost (1 / T^4); a negative T an error about gait_pose's t_end
    p = O.AsterixParameters()
    pb = O.TransitionProblem(p, O.squirming(p), O.wheel_walking(p), 1.0)
    o = O.TransitionOptions()
    for fn, args in ((O.transition_cost, (pb, O.Strategy.Bezier, O.CostWeights(), o)),
                     (O.transition_constraints, (pb, O.Strategy.Bezier, o))):
        for t in (0.0, -10.0, 1e300):
            with pytest.raises(ValueError, match=r"x\[0\] \(the duration.*outside the allowed "
                                                 r"range \[0\.2, 30\]"):
                fn(*args, [t, 0.0])
    cost, grad = O.transition_cost(pb, O.Strategy.Bezier, O.CostWeights(), o, [1.0, 0.0])
    assert math.isfinite(cost) and np.all(np.isfinite(grad))


def test_an_unreachable_cell_has_nan_waypoint_angles_not_uninitialised_memory(walker, ground):
    m, body, q = walker
    mapper = F.StabilityMapper(m, ground, body, q, 0)
    e = mapper.evaluate(-1.0, 0.0, q[:, 0])  # behind the hip: out of reach
    assert e.status == F.CellStatus.Unreachable
    assert np.all(np.isnan(e.q_above))


def test_sample_waypoints_refuses_a_count_it_cannot_allocate(walker, ground):
    m, body, q = walker
    o = F.StabilityMapOptions()
    o.cell = 0.1
    mapper = F.StabilityMapper(m, ground, body, q, 0, o)
    checker = F.LegCollisionChecker(m, ground, body, q, 0)
    with pytest.raises(ValueError, match=r"sample_waypoints\.count = 2.* outside the allowed"):
        F.sample_waypoints(mapper, mapper.map(), checker, 2**31 - 1, 0)  # was std::bad_alloc


def test_dense_path_checks_refuse_a_resolution_below_their_floor(walker, ground):
    m, body, q = walker
    checker = F.LegCollisionChecker(m, ground, body, q, 0)
    path = np.stack([q[:, 0], q[:, 0] + 0.1], axis=1)
    for tiny in (1e-300, 5e-324, 1e-6):  # 1e-300: an int overflow of the step count
        with pytest.raises(ValueError, match=r"first_colliding_edge\.resolution = .* allowed "
                                             r"range \[1e-05, inf\]"):
            F.first_colliding_edge(checker, path, tiny)
        with pytest.raises(ValueError, match=r"motion_valid\.epsilon = .* allowed range"):
            checker.motion_valid(path[:, 0], path[:, 1], tiny)
    far = path.copy()
    far[0, 0] = 1e300  # finite, but no joint turns that far: refused, not looped over
    with pytest.raises(ValueError, match="first_colliding_edge: path edge 0 needs"):
        F.first_colliding_edge(checker, far, 1e-3)
    assert F.first_colliding_edge(checker, path, 1e-3) in (-1, 0)


def test_measurement_variance_refuses_a_point_not_in_front_of_the_camera():
    m = P.ElevationMap()
    cam = P.StereoCameraParameters()
    for z in (0.0, -1.0):  # z = 0 returned NaN
        with pytest.raises(ValueError, match=r"p_cam\.z = .* must be > 0"):
            m.measurement_variance(np.array([0.0, 0.0, z]), np.eye(3), cam)
    assert math.isfinite(m.measurement_variance(np.array([0.0, 0.0, 2.0]), np.eye(3), cam))


def test_evaluate_batch_names_the_states_row():
    m = S.BekkerWongModel(S.SoilParameters())
    states = np.array([[0.01, 0.1, 0.0, 0.2, 0.0], [0.01, 0.1, 0.0, 0.2, math.nan]])
    with pytest.raises(ValueError, match=r"evaluate_batch: states row 1: .*vcy = nan"):
        m.evaluate_batch(states)


def test_walker_sim_names_q_target(walker):
    m, body, q = walker
    sim = WS.WalkerSim(m, body, q, [])
    with pytest.raises(ValueError, match=r"WalkerSim\.step: q_target has shape \(0, 0\)"):
        sim.step(np.zeros((0, 0)))
    bad = q.copy()
    bad[0, 0] = math.inf
    with pytest.raises(ValueError, match=r"WalkerSim\.hold: q_target contains a value that is not"):
        sim.hold(bad, 0.1)


def test_motor_electrical_refuses_inputs_that_overflow_the_power():
    with pytest.raises(ValueError, match="motor_electrical: output_torque = .* overflow"):
        D.motor_electrical(D.MotorParameters(), 1e300, 1e300)  # was power = inf
    e = D.motor_electrical(D.MotorParameters(), 2.0, 1.0)
    assert math.isfinite(e.current) and math.isfinite(e.power)


def test_pose_rate_refuses_a_rate_that_overflows():
    k = O.AsterixKinematics()
    with pytest.raises(ValueError, match=r"pose_rate: psi, theta, theta_rate = .* not finite"):
        k.pose_rate(0.0, -3.05, 1.7976931348623157e308)  # was (-inf, inf, ...)
    assert all(math.isfinite(v) for v in k.pose_rate(0.0, 0.3, 0.1))


def test_stereo_mapper_capture_names_the_pose_arguments():
    mapper = P.StereoMapper(D.HeightMap.flat(8.0, 8.0, 0.05, 0.0, -4.0, -4.0), [])
    bad = np.eye(3)
    bad[0, 0] = math.nan
    with pytest.raises(ValueError, match="StereoMapper.capture: chassis_position and "
                                         "chassis_rotation must be finite"):
        mapper.capture(np.zeros(3), bad)  # was "Raycaster.render: the camera pose ..."


def test_lift_legs_names_the_legs_argument(walker):
    m, body, q = walker
    with pytest.raises(ValueError, match=r"lift_legs: legs holds -1, outside \[0, 5\]"):
        W.lift_legs(m, body, q, [-1], 0.1)


def test_lifted_path_names_a_non_finite_path(walker):
    m, body, q = walker
    torques = F.StanceTorques(m, body, q, 0)
    path = np.stack([q[:, 0], q[:, 0]], axis=1)
    path[1, 1] = math.nan
    with pytest.raises(ValueError, match="StanceTorques.lifted_path: path must be finite"):
        torques.lifted_path(path, 1.0)  # was "b.hip_pitch = nan"


def test_rig_state_refuses_a_slip_of_one():
    for slip in (1.0, 1.5, -1.5):  # slip 1 gave v_cx = -inf
        with pytest.raises(ValueError, match=r"rig_state\.slip = .* allowed range \[-1, 1\)"):
            S.rig_state(0.01, slip, 0.2, 0.17)
    assert math.isfinite(S.rig_state(0.01, 0.99, 0.2, 0.17).vcx)


def test_execute_joint_path_names_the_stance(walker):
    m, body, q = walker
    sim = WS.WalkerSim(m, body, q, [])
    bad = q.copy()
    bad[2, 3] = math.nan
    with pytest.raises(ValueError, match="execute_joint_path: stance contains a value that is not"):
        WS.execute_joint_path(sim, 0, bad, [q[:, 0], q[:, 0]])


def test_synchronise_wheels_and_wheel_jacobian_validate_the_parameters():
    p = D.RoverParameters()
    p.wheel_radius = 0.0  # gave NaN wheel speeds
    with pytest.raises(ValueError, match="wheel_radius"):
        D.synchronise_wheels(p, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="wheel_radius"):
        D.wheel_jacobian(p, 0.0, 0.0, 0)


def test_minimize_slsqp_names_crossed_bounds():
    with pytest.raises(ValueError, match=r"minimize_slsqp: lower\[1\] = 9\.81.* must be <= "
                                         r"upper\[1\] = -3\.5"):  # was NLopt's "bounds 1 fail"
        O.minimize_slsqp(lambda x: (float(np.sum(x ** 2)), 2 * np.asarray(x)), [0.0, 0.0],
                         [0.0, 9.81], [1.0, -3.5])


def test_measurement_variance_refuses_an_overflowing_point():
    m = P.ElevationMap()
    with pytest.raises(ValueError, match="measurement_variance: p_cam = .* not finite"):
        # a camera whose z row looks along x: jz = 3.6 / 1e-300 overflows (was NaN)
        m.measurement_variance(np.array([3.6, 0.0, 1e-300]), np.array([[0.0, 1.0, 0.0],
                               [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), P.StereoCameraParameters())
