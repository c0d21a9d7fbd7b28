"""Inputs that could abort the process, one simulator from two threads, errors
naming the wrong thing, and NaN or nonsense that passed silently. Each error must name the
argument (and its allowed range where it has one)."""

from __future__ import annotations

import math
import subprocess
import sys
import threading
import time

import gymnasium as gym
import numpy as np
import pytest

from ernest_cpp import cli, dynamics as D, opt as O, soil as S
from ernest_cpp.envs import ErnestVectorEnv


# ---- values that must not abort the process -----------------------------------------------------

def test_commands_have_physical_ranges_named_in_the_error():
    c = D.Commands()
    c.yaw_rate = 1e306
    with pytest.raises(ValueError, match=r"Commands\.yaw_rate = 1e\+306 is outside the allowed "
                                         r"range \[-100, 100\]"):
        c.validate()
    c = D.Commands()
    c.wheel_speed = [0.0, 1e307, 0.0, 0.0]
    with pytest.raises(ValueError, match=r"Commands\.wheel_speed\[1\]"):
        c.validate()
    sim = D.make_sim("rigid")
    with pytest.raises(ValueError, match="wheel_speed"):
        sim.set_commands(c)


def test_issue_reproducers_end_in_an_exception_not_an_abort():
    # Each in its own process: before the fix they ended with ODE's abort (exit 134).
    code = """
import numpy as np
from ernest_cpp import dynamics as D
s = D.make_sim(); s.reset(0, 0, 0)
c = D.Commands(); c.yaw_rate = 1e306
try:
    s.set_commands(c); s.step_n(100)
except ValueError as e:
    print("refused:", e)
b = D.BatchStepper([D.make_sim()], 1)
cmd = np.zeros((1, D.COMMAND_SIZE)); cmd[0, 0] = 1e307; cmd[0, 6] = 1
try:
    b.step(cmd, 10)
except ValueError as e:
    print("refused:", e)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("refused:") == 2, r.stdout
    assert "wheel_speed[0]" in r.stdout


def test_batch_flag_columns_must_be_0_or_1():
    b = D.BatchStepper([D.make_sim("rigid")], 1)
    for column, name in ((6, "gimbal_enabled"), (7, "clutch_engage")):
        for bad in (math.nan, math.inf, 0.5):
            cmd = np.zeros((1, D.COMMAND_SIZE))
            cmd[0, column] = bad
            with pytest.raises(ValueError, match=name):
                b.step(cmd, 1)
    b.step(np.zeros((1, D.COMMAND_SIZE)), 1)


# ---- one simulator, two threads ------------------------------------------------------------------

def test_two_threads_on_one_sim_are_refused_not_crashed():
    sim = D.make_sim("soil")
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.2)
    sim.set_commands(D.sync_commands(sim, 0.2))
    snap = sim.snapshot()
    errors: list[str] = []
    stop = threading.Event()

    def stepper():  # most of its time inside step_n, with the GIL released
        while not stop.is_set():
            try:
                sim.step_n(200)
            except RuntimeError as e:
                errors.append(str(e))

    t = threading.Thread(target=stepper)
    t.start()
    calls = 0
    deadline = time.monotonic() + 10.0
    try:  # step and restore from this thread while the other steps, until refused a few times
        while len(errors) < 5 and time.monotonic() < deadline:
            try:
                sim.step_n(1) if calls % 2 else sim.restore(snap)
            except RuntimeError as e:
                errors.append(str(e))
            calls += 1
    finally:
        stop.set()
        t.join()
    assert errors, "no concurrent call was detected"
    assert all("in use by another thread" in e for e in errors), errors[:3]
    sim.step_n(2)  # usable afterwards
    assert np.isfinite(sim.state_vector()).all()
    assert "one thread at a time" in D.RoverSim.__doc__.lower()


# ---- errors name the right thing -----------------------------------------------------------------

@pytest.mark.parametrize("field", ["a1", "b1"])
def test_soil_a1_b1_are_named_with_their_range(field):
    p = S.SoilParameters()
    setattr(p, field, -1.0)
    with pytest.raises(ValueError, match=rf"SoilParameters\.{field} = -1 is outside the allowed "
                                         r"range \[-0\.5, 0\.5\]"):
        p.validate()


def test_asterix_problem_nan_t1_names_t1():
    with pytest.raises(ValueError, match=r"TransitionProblem\.t1 = nan"):
        O.asterix_problem(float("nan"))
    with pytest.raises(ValueError, match="direction"):
        O.asterix_problem(0.0, "sideways")


def test_vector_env_seeds():
    env = ErnestVectorEnv(2, num_threads=1, scenario="flat")
    try:
        obs, _ = env.reset(seed=np.int64(3))  # numpy integers are integers
        obs2, _ = env.reset(seed=3)
        np.testing.assert_array_equal(obs, obs2)
        with pytest.raises(ValueError, match=r"seed = -5 is outside the allowed range \[0, "):
            env.reset(seed=-5)
        with pytest.raises(ValueError, match=r"seed\[1\] = 2\.5 must be an integer"):
            env.reset(seed=[1, 2.5])
        with pytest.raises(ValueError, match="seed must be None, an integer"):
            env.reset(seed=3.0)
    finally:
        env.close()


def test_slsqp_objective_with_wrong_return_type_is_named():
    with pytest.raises(ValueError, match=r"objective\(x\) must return \(value, gradient\), got 1\.0"):
        O.minimize_slsqp(lambda x: 1.0, [0.5])
    with pytest.raises(ValueError, match="the objective's value must be a float, got \\[1.0\\]"):
        O.minimize_slsqp(lambda x: [[1.0], [0.0]], [0.5])
    with pytest.raises(ValueError, match="gradient must be a sequence"):
        O.minimize_slsqp(lambda x: [1.0, "g"], [0.5])


def test_slope_demo_vx_names_the_option(capsys):
    with pytest.raises(SystemExit):
        cli.main(["slope-demo", "--vx", "100"])
    err = capsys.readouterr().err
    assert "--vx = 100.0 is outside the allowed range (0.0, 5.0]" in err
    assert "RoverSim" not in err


# ---- NaN or nonsense must not pass silently -----------------------------------------------------

def test_slsqp_nan_objective_raises():
    with pytest.raises(ValueError, match="objective\\(x\\) returned a non-finite value"):
        O.minimize_slsqp(lambda x: (math.nan, np.zeros(1)), [0.5])
    with pytest.raises(ValueError, match="gradient has a non-finite entry"):
        O.minimize_slsqp(lambda x: (1.0, np.array([math.inf])), [0.5])


def test_slsqp_constraint_count_is_bounded():
    f = lambda x: (np.zeros(1), np.zeros((1, 1)))  # noqa: E731
    with pytest.raises(ValueError, match=r"minimize_slsqp\.inequality m = 1e\+09 is outside the "
                                         r"allowed range \[0, 100000\]"):
        O.minimize_slsqp(lambda x: (0.0, np.zeros(1)), [0.5], inequality=[(10**9, f)])


def test_transition_samplers_reject_nan():
    pb = O.asterix_problem(0.0)
    r = O.naive_transition(pb)
    with pytest.raises(ValueError, match=r"TransitionResult\.sample\.tau\[0\] = nan"):
        r.sample([math.nan])
    with pytest.raises(ValueError, match=r"sample_executed\.times\[1\] = inf"):
        r.sample_executed(pb, [0.0, math.inf])
    n = O.transition_dimension(pb, O.Strategy.Bezier)
    with pytest.raises(ValueError, match=r"transition_constraints\.x\[0\] = nan"):
        O.transition_constraints(pb, O.Strategy.Bezier, O.TransitionOptions(), [math.nan] * n)


def test_kinematics_and_dynamics_helpers_reject_nan_and_absurd_values():
    with pytest.raises(ValueError, match=r"turning_radius\.theta = nan"):
        O.AsterixKinematics().turning_radius(math.nan)
    p = D.RoverParameters()
    with pytest.raises(ValueError, match=r"synchronise_wheels\.vx = 1e\+200 is outside the "
                                         r"allowed range \[-100, 100\]"):
        D.synchronise_wheels(p, 0.0, 0.0, 1e200, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"motor_electrical\.output_torque = nan"):
        D.motor_electrical(p.wheel_motor, math.nan, 0.0)
    with pytest.raises(ValueError, match=r"HeightMap\.height\.y = nan"):
        D.HeightMap.flat(4.0, 4.0, 0.25).height(0.0, math.nan)
    with pytest.raises(ValueError, match=r"RoverParameters\.wheel_centre\.i = 7 is outside the "
                                         r"allowed range \[0, 3\]"):
        p.wheel_centre(7)
    assert p.wheel_centre(3).shape == (3,)


def test_env_flags_must_be_bools():
    with pytest.raises(ValueError, match=r"passive = 'no' must be a bool"):
        gym.make("ernest/Flat-v0", passive="no")
    with pytest.raises(ValueError, match=r"rigid_ground = 'yes' must be a bool"):
        gym.make("ernest/Flat-v0", rigid_ground="yes")
