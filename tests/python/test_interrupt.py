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
    elif case == "leg_ik":
        from ernest_cpp import walker as W
        m = W.WalkerModel(W.sdm_b_parameters())
        o = W.IkOptions()
        o.seeds, o.max_evaluations = 10000, 10**6
        ik = W.LegIk(m, o)
        far = np.eye(4)
        far[:3, 3] = [50.0, 50.0, 0.0]  # unreachable: every one of the 10000 starts runs
        seed = m.standard_configuration[:, 0]
        out["delay"] = interrupt_after(0.5, lambda: ik.solve(0, far, seed))
        out["after"] = len(ik.solve_from(0, far, seed)[1]) == len(seed)
    elif case == "colliding_edge":
        from ernest_cpp import dynamics as D, footfall as F, walker as W
        m = W.WalkerModel(W.sdm_b_parameters())
        body, q = m.standard_body_pose(), m.standard_configuration
        ground = D.HeightMap.flat(8.0, 8.0, 0.05, -5.0, -4.0, -4.0)  # far below the feet
        checker = F.LegCollisionChecker(m, ground, body, q, 0)
        a, b = q[:, 0].copy(), q[:, 0].copy()
        b[0] += 0.05
        path = np.stack([a, b] * 500, axis=1)  # 999 edges of 5000 checks at 1e-5 rad
        out["delay"] = interrupt_after(0.5, lambda: F.first_colliding_edge(checker, path, 1e-5))
        out["after"] = F.first_colliding_edge(checker, path[:, :2], 1e-3)
    elif case == "stereo":
        from ernest_cpp import perception as P
        rng = np.random.default_rng(0)
        left = rng.integers(0, 256, (1600, 2400), dtype=np.uint8)
        right = np.roll(left, -8, axis=1)
        o = P.StereoMatcherOptions()
        o.num_disparities = 128
        matcher = P.StereoMatcher(o)
        assert o.max_lr_difference is not None  # two passes: the left-right check is on
        t = time.monotonic()
        matcher.compute(left, right)
        out["whole"] = time.monotonic() - t
        out["delay"] = interrupt_after(0.1 * out["whole"], lambda: matcher.compute(left, right))
        out["after"] = matcher.compute(left[:64, :600], right[:64, :600]).shape == (64, 600)
    elif case == "segment":
        from ernest_cpp import perception as P
        cam = P.StereoCameraParameters()
        cam.width, cam.height = 2400, 1600
        rng = np.random.default_rng(0)
        depth = (1.0 + rng.random((1600, 2400))).astype(np.float32)  # every pixel an edge
        seg = P.SelfImageSegmenter()
        t = time.monotonic()
        small = P.StereoCameraParameters()
        small.width, small.height = 600, 400
        seg.segment(depth[:400, :600], small)
        out["whole"] = 16 * (time.monotonic() - t)
        out["delay"] = interrupt_after(0.2 * out["whole"], lambda: seg.segment(depth, cam))
        out["after"] = seg.segment(depth[:400, :600], small).removed.shape == (400, 600)
    elif case == "soil_batch":
        from ernest_cpp import soil as S
        m = S.BekkerWongModel(S.SoilParameters())
        # about 0.2 us a row: 4e6 rows take ~0.9 s, the signal comes at 0.1 s
        states = np.tile([0.02, 0.1, 0.0, 0.2, 0.0], (4_000_000, 1))
        out["delay"] = interrupt_after(0.1, lambda: m.evaluate_batch(states))
        out["after"] = bool(np.all(np.isfinite(m.evaluate_batch(states[:10]))))
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


def test_ctrl_c_stops_an_ik_solve_between_starts():
    res = run_case("leg_ik")
    check_prompt(res)
    assert res["after"] is True


def test_ctrl_c_stops_a_dense_path_check_between_configurations():
    res = run_case("colliding_edge")
    check_prompt(res)
    assert res["after"] == -1


def test_ctrl_c_stops_a_soil_batch_between_rows():
    res = run_case("soil_batch")
    check_prompt(res)
    assert res["after"] is True


def test_ctrl_c_stops_a_stereo_match_between_its_passes():
    # OpenCV's block matching is one uninterruptible pass: the call stops at the next pass or
    # output row, well before its end
    res = run_case("stereo")
    assert res["delay"] is not None, "the call ended before the signal: make it longer"
    assert res["delay"] < 0.7 * res["whole"], res
    assert res["after"] is True


def test_ctrl_c_stops_a_self_image_segmentation_between_rows_and_passes():
    res = run_case("segment")
    assert res["delay"] is not None, "the call ended before the signal: make it longer"
    assert res["delay"] < 0.3 * res["whole"] + 0.2, res
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
