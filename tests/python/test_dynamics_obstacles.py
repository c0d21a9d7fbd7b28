"""Rock contacts through the sparse solver (issue 17): guessed sticking contacts and sliding ones
with Coulomb's law, counted in SolverStats, switchable with SimOptions.guess_obstacle_contacts."""

import numpy as np

from ernest_cpp import dynamics as D


def _drive(guess: bool, obstacles, seconds: float = 3.0):
    o = D.make_options("soil", friction=0.8)
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
