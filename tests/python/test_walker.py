"""ernest_cpp.walker from Python: the SDM-B/T12 models, IK round trips and unreachable targets,
Jacobians and torques against finite differences computed here with numpy, and ValueError naming
the field for bad input."""

import math

import numpy as np
import pytest

from ernest_cpp import walker as W


@pytest.fixture(scope="module")
def sdm_b():
    return W.WalkerModel(W.sdm_b_parameters())


def random_q(model, rng, shrink=0.9):
    lo, hi = model.lower_limits, model.upper_limits
    c, h = 0.5 * (lo + hi), 0.5 * shrink * (hi - lo)
    return rng.uniform(c - h, c + h)


def test_presets_match_the_paper_where_it_speaks(sdm_b):
    p = W.sdm_b_parameters()
    assert p.legs == 6 and p.joints_per_leg() == 6 and math.isclose(p.total_mass(), 850.0)
    assert W.t12_parameters().joints_per_leg() == 7
    body = sdm_b.standard_body_pose()
    assert body[2, 3] == pytest.approx(1.75)  # §5.1.4: SDM-B chassis height in the studied pose
    c = sdm_b.contact_points(body, sdm_b.standard_configuration)
    assert c.shape == (3, 6)
    np.testing.assert_allclose(c[2], 0.0, atol=1e-7)
    np.testing.assert_allclose(np.hypot(c[0], c[1]), p.standard_foot_radius, atol=1e-7)
    t12 = W.WalkerModel(W.t12_parameters())
    assert t12.standard_body_pose()[2, 3] == pytest.approx(2.15)


def test_ik_round_trip_and_limits(sdm_b):
    ik = W.LegIk(sdm_b)
    rng = np.random.default_rng(1)
    for trial in range(10):
        leg = trial % 6
        q = random_q(sdm_b, rng)
        target = sdm_b.foot_pose(leg, q)
        r = ik.solve(leg, target, sdm_b.standard_configuration[:, leg])
        assert r.solved and r.status == W.IkStatus.Solved and r.solutions
        for s in r.solutions:
            assert sdm_b.within_limits(s)
            np.testing.assert_allclose(sdm_b.foot_pose(leg, s), target, atol=1e-6)
        ok, q1 = ik.solve_from(leg, target, r.solutions[0])
        assert ok
        np.testing.assert_allclose(q1, r.solutions[0], atol=1e-9)


def test_unreachable_target(sdm_b):
    ik = W.LegIk(sdm_b)
    far = W.upright_foot_pose(sdm_b, np.array([6.0, 0.0, -1.75]), 0.0)
    r = ik.solve(0, far, sdm_b.standard_configuration[:, 0])
    assert not r.solved and r.status == W.IkStatus.Unreachable and r.solutions == []
    assert r.position_error > 2.0
    assert sdm_b.within_limits(r.closest)


def test_jacobian_and_torques_by_finite_differences(sdm_b):
    rng = np.random.default_rng(2)
    q = random_q(sdm_b, rng)
    leg, h = 4, 1e-6
    J = sdm_b.contact_jacobian(leg, q)
    reaction = np.array([120.0, -300.0, 1800.0])
    tau = sdm_b.joint_torques(leg, q, reaction)
    g = np.array([0.0, 0.0, -sdm_b.params.gravity])
    joints = sdm_b.params.joints

    def potential(qq):
        # V = sum m_j g z_j over the leg's links, from the link frames (foot_pose needs only FK).
        v = 0.0
        rot = sdm_b.hip_mount(leg)[:3, :3].copy()
        p = sdm_b.hip_mount(leg)[:3, 3].copy()
        for j, qj in zip(joints, qq):
            p = p + rot @ j.offset
            a = j.axis
            k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
            rot = rot @ (np.eye(3) + math.sin(qj) * k + (1 - math.cos(qj)) * k @ k)
            v -= j.mass * g @ (p + rot @ j.com)
        return v

    for i in range(len(q)):
        dq = np.zeros_like(q)
        dq[i] = h
        dc = (sdm_b.contact_point(leg, q + dq) - sdm_b.contact_point(leg, q - dq)) / (2 * h)
        np.testing.assert_allclose(J[:, i], dc, atol=1e-7)
        dv = (potential(q + dq) - potential(q - dq)) / (2 * h)
        assert tau[i] == pytest.approx(dv - reaction @ dc, rel=1e-6, abs=1e-5)
    sat = sdm_b.saturation(tau)
    np.testing.assert_allclose(sat, np.abs(tau) / sdm_b.torque_limits)
    assert sdm_b.margin_to_saturation(tau) == pytest.approx(1.0 - sat.max())


def test_capsules(sdm_b):
    caps = sdm_b.capsules(sdm_b.standard_body_pose(), sdm_b.standard_configuration)
    assert len(caps) == 42
    wheels = [c for c in caps if c.link == -1]
    assert len(wheels) == 6
    for c in wheels:
        assert min(c.p0[2], c.p1[2]) - c.radius == pytest.approx(0.0, abs=1e-7)


def test_bad_input_raises_value_error_naming_the_field(sdm_b):
    p = W.sdm_b_parameters()
    p.wheel_radius = -1.0
    with pytest.raises(ValueError, match="wheel_radius"):
        p.validate()
    with pytest.raises(ValueError, match="wheel_radius"):
        W.WalkerModel(p)
    q = sdm_b.standard_configuration[:, 0].copy()
    with pytest.raises(ValueError, match="leg"):
        sdm_b.foot_pose(9, q)
    q[1] = float("nan")
    with pytest.raises(ValueError, match="hip_pitch"):
        sdm_b.contact_point(0, q)
    with pytest.raises(ValueError, match="reaction"):
        sdm_b.joint_torques(0, sdm_b.standard_configuration[:, 0], np.array([0.0, np.nan, 1.0]))
    bad = np.eye(4)
    bad[3, 0] = 1.0
    with pytest.raises(ValueError, match="target"):
        W.LegIk(sdm_b).solve(0, bad, sdm_b.standard_configuration[:, 0])
    with pytest.raises(ValueError, match="body"):
        sdm_b.center_of_mass(np.full((4, 4), np.nan), sdm_b.standard_configuration)
    o = W.IkOptions()
    o.seeds = 0
    with pytest.raises(ValueError, match="IkOptions.seeds"):
        W.LegIk(sdm_b, o)


def test_fig16_and_sway_gait_from_python(sdm_b, tmp_path):
    from ernest_cpp import walker_demo

    body = sdm_b.standard_body_pose()
    weight = sdm_b.params.total_mass() * sdm_b.params.gravity
    q1 = W.lift_legs(sdm_b, body, sdm_b.standard_configuration, [0], 0.2)
    one = W.stance_loads(sdm_b, body, q1, [0])
    np.testing.assert_allclose(one.reactions.sum(axis=1), [0, 0, weight], atol=1e-6)
    assert one.reactions[:, 0].tolist() == [0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="lifted leg 7"):
        W.stance_loads(sdm_b, body, q1, [7])
    with pytest.raises(ValueError, match="SwayGaitOptions.stride"):
        o = W.SwayGaitOptions()
        o.stride = -1.0
        W.optimise_sway_gait(sdm_b, o)
    report = walker_demo.run(tmp_path)
    two, gait = report["two"], report["gait"]
    assert two.peak_saturation < one.peak_saturation and two.mean_force > one.mean_force
    assert gait.peak_reduction > 0.2
    assert all(s.peak_saturation <= r.peak_saturation + 1e-12 for r, s in zip(gait.reference, gait.sway))
    for name in ("fig16_lifted_legs.png", "fig15_sway_gait.png", "walker_report.md"):
        assert (tmp_path / name).stat().st_size > 1000


def test_self_collisions(sdm_b):
    assert W.self_collisions(sdm_b, sdm_b.standard_configuration) == []
    q = sdm_b.standard_configuration.copy()
    q[0, 0], q[0, 1] = math.radians(50), math.radians(-50)
    pairs = W.self_collisions(sdm_b, q)
    assert pairs and all(p.leg_a == 0 and p.leg_b == 1 and p.distance == 0.0 for p in pairs)
    with pytest.raises(ValueError, match="clearance"):
        W.self_collisions(sdm_b, q, -0.1)
