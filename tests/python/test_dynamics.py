"""Python-level tests of ernest_cpp.dynamics: bindings, numpy interfaces, batch stepping, errors."""

import math
import threading

import numpy as np
import pytest

from ernest_cpp import dynamics as D


def rigid_sim(**kw):
    return D.make_sim("rigid", friction=0.8, **kw)


def test_static_loads_sum_to_weight_and_fts_shapes():
    sim = rigid_sim()
    c = D.Commands()
    c.gimbal_enabled = False
    sim.set_commands(c)
    sim.step_n(100)
    s = sim.state
    m = sim.parameters.total_mass()
    assert s.wheel_load.shape == (4,)
    assert abs(s.wheel_load.sum() - m * 9.81) < 0.005 * m * 9.81
    assert s.fts.shape == (4, 6)
    # Each sensor carries its wheel's load minus the assembly's own weight below the sensor.
    wa = sim.parameters.wheel_assembly_mass
    np.testing.assert_allclose(s.fts[:, 2], s.wheel_load - wa * 9.81, rtol=0.01)


def test_observation_layout_matches_state():
    sim = rigid_sim()
    sim.step_n(5)
    o = sim.state_vector()
    names = D.STATE_VECTOR_NAMES
    assert o.shape == (D.STATE_VECTOR_SIZE,) == (len(names),)
    s = sim.state
    assert o[names.index("time")] == pytest.approx(s.time)
    assert o[names.index("wheel_load_RR")] == pytest.approx(s.wheel_load[3])
    assert o[names.index("fts_FR_Fz")] == pytest.approx(s.fts[1, 2])


def test_synchroniser_straight_and_consistent():
    p = D.RoverParameters()
    r = D.synchronise_wheels(p, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(r.wheel_speeds, 0.2 / p.wheel_radius, rtol=1e-12)
    assert r.A.shape == (12, 11) and r.x.shape == (11,)
    t = D.synchronise_wheels(p, 0.4, 0.0, 0.1, 0.0, 0.0, 0.1, 0.0)
    assert t.residual < 1e-10
    np.testing.assert_allclose(t.A @ t.x, t.y, atol=1e-12)


def test_batch_matches_single_rover_runs_and_threads():
    def make(seed):
        sim = D.make_sim("soil", obstacles=D.rock_field(6, seed=seed), seed=seed)
        sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15)
        return sim

    cmds = D.command_array([[1.0, 1.0, 1.0, 1.0, 0.1 * k, 0.0, 1.0, 0.0] for k in range(3)])
    solo = []
    for k in range(3):
        sim = make(k)
        c = D.Commands()
        c.wheel_speed = list(cmds[k, :4])
        c.yaw_rate = cmds[k, 4]
        sim.set_commands(c)
        sim.step_n(20)
        solo.append(sim.state_vector())
    for threads in (1, 2):
        batch = D.BatchStepper([make(k) for k in range(3)], threads)
        obs = None
        for _ in range(4):
            obs = batch.step(cmds, 5)
        assert obs.shape == (3, D.STATE_VECTOR_SIZE)
        np.testing.assert_array_equal(obs, np.array(solo))  # bit-identical, any thread count


def test_batch_releases_the_gil():
    batch = D.BatchStepper([D.make_sim("soil") for _ in range(2)], 2)
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(1)

    t = threading.Thread(target=ticker)
    t.start()
    batch.step(None, 400)
    stop.set()
    t.join()
    assert len(ticks) > 10  # the Python thread ran while C++ stepped


def test_snapshot_restore_exact():
    sim = D.make_sim("soil", obstacles=D.rock_field(5, seed=3))
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15)
    c = D.Commands()
    c.wheel_speed = [1.0, 1.1, 1.0, 0.9]
    c.yaw_rate = 0.1
    sim.set_commands(c)
    sim.step_n(30)
    snap = sim.snapshot()
    at_snap = sim.state
    sim.step_n(50)
    a = sim.state_vector()
    # The snapshot's state is the canonical RoverState of the moment it was taken, not the
    # simulator's current one; its commands are the held set-points.
    assert isinstance(snap.state, D.RoverState)
    np.testing.assert_array_equal(snap.state.position, at_snap.position)
    assert snap.state.time == snap.time == at_snap.time != sim.state.time
    assert list(snap.commands.wheel_speed) == [1.0, 1.1, 1.0, 0.9]
    sim.restore(snap)
    assert sim.state.time == pytest.approx(snap.time)
    np.testing.assert_array_equal(sim.state.position, snap.state.position)
    sim.step_n(50)
    np.testing.assert_array_equal(sim.state_vector(), a)


def test_divergence_raises_python_exception():
    sim = rigid_sim()
    sim.step_n(2)
    sim.apply_chassis_force(np.array([0.0, 0.0, 1e9]))
    with pytest.raises(D.SimulationDiverged, match="chassis"):
        sim.step()
    assert issubclass(D.SimulationDiverged, RuntimeError)
    batch = D.BatchStepper([rigid_sim(), rigid_sim()], 2)
    batch.sim(1).apply_chassis_force(np.array([0.0, 0.0, 1e9]))
    with pytest.raises(D.SimulationDiverged, match="rover 1"):
        batch.step(None, 1)


def test_invalid_inputs_raise_value_error():
    p = D.RoverParameters()
    p.track = -1.0
    with pytest.raises(ValueError, match="track"):
        D.RoverSim(p, D.HeightMap.flat(4, 4, 0.5))
    with pytest.raises(ValueError, match="ground"):
        D.make_options("ice")
    sim = rigid_sim()
    c = D.Commands()
    c.roll_rate = math.nan
    with pytest.raises(ValueError, match="roll_rate"):
        sim.set_commands(c)
    batch = D.BatchStepper([sim], 1)
    with pytest.raises(ValueError, match="shape"):
        batch.step(np.zeros((2, D.COMMAND_SIZE)), 1)


def test_motor_power_eq40():
    m = D.MotorParameters()
    e = D.motor_electrical(m, 10.0, 2.0)
    i = 10.0 / (m.gear_ratio * m.efficiency * m.torque_constant)
    assert e.current == pytest.approx(i)
    assert e.power == pytest.approx(i * (m.resistance * i + m.torque_constant * m.gear_ratio * 2.0))


def test_slope_demo_metrics_follow_table6_definitions(tmp_path):
    from ernest_cpp import slope_demo

    r = slope_demo.run("crawling", "dry_sand", duration=4.0, vx=0.1)
    assert r["expected"] == pytest.approx(0.4, rel=1e-9)  # no-slip travel = Vx * t
    assert r["travel_reduction"] == pytest.approx((r["expected"] - r["actual"]) / r["expected"])
    assert r["energy_J"] > 0.0
    if r["actual"] > 0:
        m = D.RoverParameters().total_mass()
        assert r["cost_of_transport"] == pytest.approx(r["energy_J"] / (m * 9.81 * r["actual"]))
    assert np.ptp(np.degrees(r["psi"])) > 10.0  # the crawling gait swings the bogie
    p = slope_demo.run("passive", "m90", duration=2.0)
    assert np.abs(p["psi"]).max() < 0.01  # AGS off: yaw held by the brake (< 0.6 deg)
    with pytest.raises(ValueError, match="controller"):
        slope_demo.run("rl")


def _same_run_with_option_on_and_off(option: str):
    """Two soil sims, the solver option on and off, driven alike for 40 steps."""
    sims = [D.make_sim("soil", **{option: on}) for on in (True, False)]
    for sim in sims:
        sim.reset(0.0, 0.0, 0.0, speed=0.15)
        sim.set_commands(D.sync_commands(sim, 0.15, yaw_rate=0.1))
        sim.step_n(40)
    return sims


def test_active_set_guessing_is_exposed_and_agrees_with_pivoting():
    # Same start, same commands: the guessed and the pivoted solver agree over a short soil run
    # (the C++ tests compare them step by step over longer, harsher runs).
    sims = _same_run_with_option_on_and_off("guess_active_set")
    a, b = (sim.state for sim in sims)
    np.testing.assert_allclose(a.position, b.position, atol=1e-6)
    np.testing.assert_allclose(a.wheel_load, b.wheel_load, rtol=1e-4)
    guessed, pivoted = (sim.solver_stats for sim in sims)
    assert guessed.steps == pivoted.steps == 40
    assert guessed.first_guess >= 36 and pivoted.first_guess == 0
    assert pivoted.pivoted == 0  # counted only when guessing was tried
    assert "first_guess" in repr(guessed)


def test_sparse_constraint_solver_runs_inside_the_module_and_agrees_with_ode():
    # The sparse solver reaches ODE by symbol interposition; inside the Python extension module
    # (loaded with RTLD_LOCAL) it must still be the one ODE calls.
    sims = _same_run_with_option_on_and_off("sparse_lcp")
    a, b = (sim.state for sim in sims)
    np.testing.assert_allclose(a.position, b.position, atol=1e-9)
    np.testing.assert_allclose(a.wheel_load, b.wheel_load, rtol=1e-7)
    sparse, dense = (sim.solver_stats for sim in sims)
    # (a step may be solved more than once for its implicit slip, and a trial slip far from the
    # end state can make ODE pivot: the share of all solves, as in the C++ solver tests)
    assert sparse.sparse_solves >= 40
    assert sparse.dense_solves <= 0.1 * (sparse.sparse_solves + sparse.dense_solves)
    assert dense.sparse_solves == 0 and dense.dense_solves >= 40
    assert "sparse_solves" in repr(sparse)


def test_make_sim_default_soil_drives_like_the_environments():
    # make_sim's preset soil is the environments' (eps_slip, eps_motion from EnvOptions), under
    # which the rover drives from rest; Table 2's own values stay one call away.
    from ernest_cpp import envs, soil as S
    sim = D.make_sim()
    env = envs.make_options()
    assert sim.options.soil.eps_slip == env.eps_slip
    assert sim.options.soil.eps_motion == env.eps_motion
    assert D.make_options(soil=S.soil_preset("m90")).soil.eps_slip == S.soil_preset("m90").eps_slip
    sim.reset(0.0, 0.0, 0.0)
    for _ in range(60):  # 6 s at 0.15 m/s, the synchroniser re-run every 0.1 s
        sim.set_commands(D.sync_commands(sim, 0.15))
        sim.step_n(round(0.1 / sim.options.dt))
    assert sim.state.position[0] > 0.5  # 0.9 m commanded; Table 2's eps_slip gives 2 cm
