"""Ctrl-C reaches Python promptly from long C++ calls that release the GIL (within a unit of work,
not at the end of e.g. ``step_n(3e6)``), and the object is usable afterwards (or says it is not).

Each case runs in a child process, which sends SIGINT to itself from a timer thread while the main
thread is inside the call: a failure then cannot hang or kill the test run. The child prints,
per case, the delay from the signal to the KeyboardInterrupt and the result of a call made after.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

CHILD = textwrap.dedent(r"""
    import json, os, signal, sys, threading, time
    import numpy as np

    def interrupt_after(seconds, call):
        # (seconds from SIGINT to KeyboardInterrupt, or None if the call ended first)
        sent = {}
        def fire():
            sent["t"] = time.monotonic()
            os.kill(os.getpid(), signal.SIGINT)
        timer = threading.Timer(seconds, fire)
        timer.start()
        try:
            call()
        except KeyboardInterrupt:
            return time.monotonic() - sent["t"]
        timer.cancel()
        return None

    case = sys.argv[1]
    out = {}
    if case == "step_n":
        from ernest_cpp import dynamics as D
        s = D.make_sim()
        s.reset(0.0, 0.0, 0.0)
        out["delay"] = interrupt_after(0.5, lambda: s.step_n(2**31 - 1))
        t = s.state.time
        s.step_n(4)  # usable afterwards: four more whole steps
        out["after"] = (s.state.time - t) / s.options.dt
    elif case == "batch":
        from ernest_cpp import dynamics as D
        sims = [D.make_sim() for _ in range(3)]
        for s in sims:
            s.reset(0.0, 0.0, 0.0)
        b = D.BatchStepper(sims, 2)
        out["delay"] = interrupt_after(0.5, lambda: b.step(None, 2**31 - 1))
        obs = b.step(None, 1)
        out["after"] = bool(np.all(np.isfinite(obs)))
    elif case == "vector":
        from ernest_cpp import dynamics as D
        from ernest_cpp._core import envs as CE
        from ernest_cpp.envs import make_options
        o = make_options("flat")
        o.policy_dt = 5.0  # 400 physics steps per environment step: ~3 s for the batch
        v = CE.VecRoverEnv(D.RoverParameters(), o, 256, 1)
        v.reset(list(range(256)))
        acts = np.zeros((256, 3))
        out["delay"] = interrupt_after(0.2, lambda: v.step(acts))
        try:
            v.step(acts)
            out["refused"] = None
        except RuntimeError as e:
            out["refused"] = str(e)
        v.reset(list(range(256)))
        out["after"] = bool(np.all(np.isfinite(v.step(acts)[0])))
    elif case == "transition":
        from ernest_cpp import opt as O
        p = O.asterix_problem(1.0)
        o = O.TransitionOptions()
        o.solver.max_time = 600.0
        o.solver.max_eval = 10**9
        o.solver.xtol_rel = o.solver.ftol_rel = o.solver.ftol_abs = 0.0
        # default waypoints; with no tolerance SLSQP runs for minutes (until max_time)
        out["delay"] = interrupt_after(0.5, lambda: O.plan_transition(
            p, O.Strategy.Spline, O.CostWeights(), o))
        out["after"] = bool(np.isfinite(O.plan(p, "bezier").duration))
    elif case == "render":
        from ernest_cpp import dynamics as D, perception as P
        r = P.Raycaster(D.HeightMap.flat(40.0, 20.0, 0.25, 0.0, -10.0, -10.0), [])
        cam = P.StereoCameraParameters()
        cam.width, cam.height = 8000, 6000
        pose = np.eye(4)
        pose[2, 3] = 1.0
        out["delay"] = interrupt_after(0.5, lambda: r.render(pose, cam))
        cam.width, cam.height = 64, 48
        out["after"] = r.render(pose, cam)[0].shape == (48, 64)
    elif case == "walker_hold":
        from ernest_cpp import walker as W, walker_sim as WS
        m = W.WalkerModel(W.sdm_b_parameters())
        q = m.standard_configuration
        sim = WS.WalkerSim(m, m.standard_body_pose(), q)
        out["delay"] = interrupt_after(0.5, lambda: sim.hold(q, 5000.0))  # about an hour
        t = sim.time
        sim.hold(q, 10 * sim.options.dt)
        out["after"] = (sim.time - t) / sim.options.dt
    elif case == "execute_path":
        from ernest_cpp import walker as W, walker_sim as WS
        m = W.WalkerModel(W.sdm_b_parameters())
        q = m.standard_configuration
        sim = WS.WalkerSim(m, m.standard_body_pose(), q)
        o = WS.ExecutionOptions()
        o.pause = 60.0  # a minute of simulated holding at each of the two waypoints
        path = [q[:, 0], q[:, 0]]
        out["delay"] = interrupt_after(0.5, lambda: WS.execute_joint_path(sim, 0, q, path, o))
        out["after"] = bool(np.all(np.isfinite(sim.joint_angles())))
    elif case == "stability_map":
        from ernest_cpp import footfall as F, walker as W
        m = W.WalkerModel(W.sdm_b_parameters())
        body, q = m.standard_body_pose(), m.standard_configuration
        terrain = F.rock_field(F.RockFieldOptions(), m.contact_points(body, q)[:2])
        o = F.StabilityMapOptions()
        o.cell = 0.004  # 1.5 million cells: seconds
        mapper = F.StabilityMapper(m, terrain, body, q, 0, o)
        out["delay"] = interrupt_after(0.5, mapper.map)
        o.cell = 0.1
        out["after"] = F.StabilityMapper(m, terrain, body, q, 0, o).map() is not None
    print(json.dumps(out))
""")


def run_case(case: str) -> dict:
    r = subprocess.run([sys.executable, "-c", CHILD, case], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def check_prompt(res: dict) -> None:
    assert res["delay"] is not None, "the call ended before the signal: make it longer"
    assert res["delay"] < 0.5, f"KeyboardInterrupt {res['delay']:.3f} s after SIGINT"


def test_ctrl_c_stops_step_n_between_whole_steps():
    res = run_case("step_n")
    check_prompt(res)
    assert res["after"] == pytest.approx(4.0)


def test_ctrl_c_stops_every_thread_of_a_batch_stepper():
    res = run_case("batch")
    check_prompt(res)
    assert res["after"] is True


def test_ctrl_c_in_a_vector_env_step_then_it_asks_for_a_reset():
    res = run_case("vector")
    check_prompt(res)
    assert "interrupted part way" in res["refused"] and "reset()" in res["refused"]
    assert res["after"] is True


def test_ctrl_c_stops_an_slsqp_transition():
    res = run_case("transition")
    check_prompt(res)
    assert res["after"]


def test_ctrl_c_stops_a_stereo_render():
    res = run_case("render")
    check_prompt(res)
    assert res["after"] is True


def test_ctrl_c_stops_a_walker_hold_between_physics_steps():
    res = run_case("walker_hold")
    check_prompt(res)
    assert res["after"] == pytest.approx(10.0)


def test_ctrl_c_stops_a_walker_joint_path():
    res = run_case("execute_path")
    check_prompt(res)
    assert res["after"] is True


def test_ctrl_c_stops_a_stability_map():
    res = run_case("stability_map")
    check_prompt(res)
    assert res["after"] is True


def test_sigint_from_another_process_stops_an_hour_long_hold():
    child = textwrap.dedent("""
        import sys, time
        from ernest_cpp import walker as W, walker_sim as WS
        m = W.WalkerModel(W.sdm_b_parameters())
        q = m.standard_configuration
        sim = WS.WalkerSim(m, m.standard_body_pose(), q)
        print("ready", flush=True)
        try:
            sim.hold(q, 5000.0)
        except KeyboardInterrupt:
            print("KeyboardInterrupt", flush=True)
    """)
    p = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        sent = time.monotonic()
        os.kill(p.pid, signal.SIGINT)
        out, _ = p.communicate(timeout=30)
        assert time.monotonic() - sent < 5.0
    finally:
        p.kill()
        p.wait()
    assert out.strip() == "KeyboardInterrupt" and p.returncode == 0
