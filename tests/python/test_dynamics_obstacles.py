"""Rock contacts through the sparse solver: guessed sticking contacts and sliding ones
with Coulomb's law, counted in SolverStats, switchable with SimOptions.guess_obstacle_contacts."""

import numpy as np

from ernest_cpp import dynamics as D
from ernest_cpp.soil import soil_preset


def _drive(guess: bool, obstacles, seconds: float = 3.0):
    # Table 2's soil as printed (eps_slip 100): the scenario these figures were measured on
    o = D.make_options("soil", soil=soil_preset("m90"), friction=0.8)
    o.guess_obstacle_contacts = guess
    sim = D.make_sim(obstacles=obstacles, options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15)
    c = D.Commands()
    c.gimbal_enabled = False
    c.wheel_speed = [0.15 / sim.parameters.wheel_radius] * 4
    sim.set_commands(c)
    touched = 0
    for _ in range(int(round(seconds / o.dt))):
        sim.step()
        touched = max(touched, sim.solver_stats.obstacles_touched)
    return sim, touched


def test_rock_contacts_are_guessed_and_counted_and_agree_with_the_bounded_path():
    # A flat rock 5 mm under the soil: the front wheels sink onto it and roll on it (sticking).
    slab = [D.BoxObstacle(np.array([1.0, 0.0, -0.055]), np.array([2.0, 3.0, 0.1]), 0.0, 0.0, 0.0)]
    guessed, touched = _drive(True, slab)
    bounded, _ = _drive(False, slab)
    s = guessed.solver_stats
    assert touched == 1  # one rock under the wheels
    assert s.obstacle_guessed > 10 * s.obstacle_bounded
    assert bounded.solver_stats.obstacle_guessed == 0
    assert bounded.solver_stats.obstacle_bounded > 0
    assert "obstacle_guessed=" in repr(s)
    # the wheels on the slab (~4 kg effective mass bound or more): every contact's §3.4 spring
    # explicit (cpp/dynamics/obstacle_contacts.hpp), one contact per wheel and (sub)step
    assert s.obstacle_explicit >= s.obstacle_guessed + s.obstacle_bounded > 0
    assert s.obstacle_implicit == 0
    assert "obstacle_explicit=" in repr(s)
    # the same trajectory to well within a millimetre (ODE's friction bound differs only where a
    # tyre's friction nears mu F_n)
    assert abs(guessed.state.position[0] - bounded.state.position[0]) < 1e-4
    assert D.SimOptions().guess_obstacle_contacts is True


def test_a_wheel_spinning_against_a_face_takes_the_explicit_slip_and_keeps_climbing():
    # The passive bogie pushing a 0.4 m wall on M90 without substeps (test_dynamics_substeps.cpp):
    # at the foot of the face eq 12's slip drives the wheel, so those steps take the slip from
    # the step's start (SolverStats.slip_driving, rover_step.cpp); the rest stays implicit.
    o = D.make_options("soil", friction=0.7)
    o.obstacle_substeps = 1
    o.soil.eps_slip = 1e4
    o.soil.eps_motion = 0.01
    wall = [D.BoxObstacle(np.array([1.5, 0.0, 0.2]), np.array([0.3, 3.0, 0.4]), 0.0, 0.0, 0.0)]
    sim = D.make_sim(obstacles=wall, options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.2)
    c = D.Commands()
    c.gimbal_enabled = False
    c.wheel_speed = [0.2 / sim.parameters.wheel_radius] * 4
    sim.set_commands(c)
    for _ in range(int(round(12.0 / o.dt))):
        sim.step()
    s = sim.solver_stats
    assert 0 < s.slip_driving < 0.2 * s.steps
    assert "slip_driving=" in repr(s)
    # it kept climbing the face and falling back (dt / 8 throughout: 788 J; held at the foot of
    # the face by the implicit slip it was 381 J)
    assert sim.state.energy > 700.0


def test_one_substep_at_half_the_step_climbs_the_wheel_high_step_like_the_default():
    # The passive bogie at the wheel-high step (evaluate.COURSES), one obstacle substep at dt / 2:
    # near h lambda = 1 the surge up the face aborted and the wheel stayed spinning at v_x ~ 0 from
    # 37 s on (CoT 6.52 against 9.72 with the default substeps); obstacle steps where a wheel's
    # slip grows at dt lambda >= 1/2 are now split (obstacle_contacts.cpp, step()).
    import ernest_cpp.envs  # noqa: F401  (registers the ids)
    from ernest_cpp import evaluate

    pol, passive = evaluate.controllers(None)[evaluate.PASSIVE]
    dt = D.SimOptions().dt
    ref = evaluate.run_episode("ernest/WheelStep-v0", {}, pol, passive, 0)[0]
    half = evaluate.run_episode("ernest/WheelStep-v0", dict(physics_dt=dt / 2, obstacle_substeps=1),
                                pol, passive, 0)[0]
    assert abs(half["travel_reduction"] - ref["travel_reduction"]) < 0.02
    assert abs(half["cost_of_transport"] / ref["cost_of_transport"] - 1.0) < 0.05
