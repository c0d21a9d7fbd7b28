"""Child process of test_threads.py: `python threads_child.py CASE` contests one bound object from
two threads and prints {"calls", "refused", "other", "after"/"same"} as JSON (last line).

A refusal is the documented RuntimeError "... in use by another thread ..."; any other exception
is listed in "other"; a crash is the parent's failure (non-zero exit).
"""

from __future__ import annotations

import json
import sys
import threading

import numpy as np

REFUSED = "in use by another thread"


def contest(workers, n):
    """Run each worker (a callable) n times on its own thread, all starting together."""
    out = {"calls": 0, "refused": 0, "other": [], "message": ""}
    lock = threading.Lock()
    start = threading.Barrier(len(workers))

    def loop(work):
        start.wait()
        for _ in range(n):
            try:
                work()
                key = "calls"
            except RuntimeError as e:
                if REFUSED not in str(e):
                    raise_other(e)
                    continue
                key = "refused"
                out["message"] = str(e)
            except Exception as e:  # noqa: BLE001 (reported, then the parent fails)
                raise_other(e)
                continue
            with lock:
                out[key] += 1

    def raise_other(e):
        with lock:
            out["other"].append(f"{type(e).__name__}: {e}"[:300])

    threads = [threading.Thread(target=loop, args=(w,)) for w in workers]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return out


def walker():
    from ernest_cpp import walker as W
    return W, W.WalkerModel(W.sdm_b_parameters())


def case_leg_ik():
    W, m = walker()
    ik = W.LegIk(m)
    target = W.upright_foot_pose(m, np.array([2.1, 0.1, -1.75]), 0.0)
    q = m.standard_configuration[:, 0]
    out = contest([lambda: ik.solve(0, target, q)] * 2, 3000)
    out["after"] = bool(ik.solve(0, target, q).solved)
    return out


def vec_options():
    from ernest_cpp.envs import make_options
    return make_options("flat")


def case_vec_env():
    from ernest_cpp import dynamics as D
    from ernest_cpp._core import envs as CE
    v = CE.VecRoverEnv(D.RoverParameters(), vec_options(), 2, 1)
    v.reset([0, 1])
    acts = np.zeros((2, 3))
    out = contest([lambda: v.step(acts), lambda: v.reset([2, 3])], 30)
    v.reset([0, 1])
    out["after"] = bool(np.all(np.isfinite(v.step(acts)[0])))
    return out


def case_gym_env():
    import gymnasium as gym
    import ernest_cpp.envs  # noqa: F401 (registers the ids)
    env = gym.make("ernest/Flat-v0").unwrapped
    env.reset(seed=0)
    out = contest([lambda: env.step(np.zeros(3)), lambda: env.reset(seed=1)], 40)
    env.reset(seed=0)
    out["after"] = bool(np.all(np.isfinite(env.step(np.zeros(3))[0])))
    return out


def case_rover_env():
    from ernest_cpp import dynamics as D
    from ernest_cpp._core import envs as CE
    e = CE.RoverEnv(D.RoverParameters(), vec_options())
    e.reset(0)
    out = contest([lambda: e.step(np.zeros(3)), lambda: (e.reset(1), e.metrics, e.state)], 40)
    e.reset(0)
    out["after"] = bool(np.all(np.isfinite(e.step(np.zeros(3))[0])))
    return out


def footfall_scene():
    from ernest_cpp import footfall as F
    W, model = walker()
    body, q = model.standard_body_pose(), model.standard_configuration
    feet = model.contact_points(body, q)
    return F, model, body, q, feet, F.rock_field(F.RockFieldOptions(), feet[:2])


def case_stability_mapper():
    F, model, body, q, feet, terrain = footfall_scene()
    o = F.StabilityMapOptions()
    o.cell = 0.1
    mapper = F.StabilityMapper(model, terrain, body, q, 0, o)
    x, y = feet[0, 0] + 0.3, feet[1, 0]
    out = contest([lambda: [mapper.evaluate(x, y, q[:, 0]) for _ in range(200)],
                   lambda: mapper.map()], 20)
    out["after"] = mapper.map() is not None
    return out


def case_planner():
    F, model, body, q, feet, terrain = footfall_scene()
    checker = F.LegCollisionChecker(model, terrain, body, q, 0)
    o = F.PlannerOptions()
    o.time_limit = 0.05
    planner = F.LegPlanner(checker, o)
    a = q[:, 0] + 0.05
    path = np.column_stack([q[:, 0], a])
    out = contest([lambda: planner.plan(q[:, 0], a), lambda: checker.valid(a),
                   lambda: F.first_colliding_edge(checker, path, 0.01)], 100)
    out["after"] = isinstance(checker.valid(a), bool)
    return out


def case_segmenter():
    from ernest_cpp import perception as P
    from ernest_cpp import perception_selfimage as SI
    W, model = walker()
    scene = P.self_image_scene(model, 3)
    caster = P.Raycaster(scene.terrain, list(scene.rocks))
    camera = P.walker_hazcam()
    depth = SI.render_pose(model, scene, caster, camera, 3, 0.5, 0.1)[1]
    seg = P.SelfImageSegmenter()
    out = contest([lambda: seg.segment(depth, camera)] * 2, 30)
    out["after"] = bool(seg.segment(depth, camera).found())
    return out


def new_walker_sim():
    from ernest_cpp import walker_sim as WS
    W, model = walker()
    q = model.standard_configuration
    return WS.WalkerSim(model, model.standard_body_pose(), q), q


def case_walker_sim():
    sim, q = new_walker_sim()
    out = contest([lambda: sim.step(q), lambda: (sim.hold(q, 0.01), sim.joint_angles(),
                                                 sim.wheel_loads(), sim.body_pose())], 200)
    out["after"] = bool(np.all(np.isfinite(sim.joint_angles())))
    return out


def case_walker_sim_held():
    # one thread inside a long hold: the other's every call in that time is refused
    sim, q = new_walker_sim()
    sim.step(q)
    out = {"calls": 0, "refused": 0, "other": [], "message": ""}

    def hold():
        while True:  # until it gets in between two of the main thread's calls
            try:
                return sim.hold(q, 1.0)
            except RuntimeError:
                continue

    t = threading.Thread(target=hold)
    t.start()
    while t.is_alive():
        try:
            sim.joint_angles()
        except RuntimeError as e:
            out["refused"] += 1
            out["message"] = str(e)
    t.join()
    return out


def case_elevation_map():
    from ernest_cpp import perception as P
    em = P.ElevationMap()
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-2, 2, (5000, 2)), rng.uniform(0, 0.1, 5000)])
    var = np.full(5000, 1e-4)
    out = contest([lambda: em.fuse_points(pts, var),
                   lambda: (em.move_to(0.5, 0.0), em.heights, em.move_to(0.0, 0.0))], 200)
    out["after"] = bool(em.consistent())
    return out


def case_stereo_mapper():
    from ernest_cpp import dynamics as D
    from ernest_cpp import perception as P
    mp = P.StereoMapper(D.HeightMap.flat(30.0, 20.0, 0.05, 0.0, -5.0, -10.0), [])
    p, r = np.array([0.0, 0.0, 0.17]), np.eye(3)
    em = mp.map
    out = contest([lambda: (mp.update(0.0, p, r), mp.capture(p, r)),
                   lambda: (em.heights, em.move_to(0.1, 0.0))], 4)
    out["after"] = bool(mp.map.consistent())
    return out


def case_stereo_matcher():
    from ernest_cpp import dynamics as D
    from ernest_cpp import perception as P
    cam = P.StereoCameraParameters()
    rc = P.Raycaster(D.HeightMap.flat(30.0, 20.0, 0.05, 0.0, -5.0, -10.0), [])
    pos = np.array([0.0, 0.0, 0.17])
    left, _ = rc.render(cam.camera_pose(pos, np.eye(3), 0), cam, 0)
    right, _ = rc.render(cam.camera_pose(pos, np.eye(3), 1), cam, 1)
    m = P.StereoMatcher()
    out = contest([lambda: m.compute(left, right)] * 2, 20)
    out["after"] = m.compute(left, right).shape == left.shape
    return out


def shared(make, n):
    """Each thread's results equal the single-thread ones (no refusal: nothing to guard)."""
    ref = make()
    results = []
    out = contest([lambda: results.append(make())] * 2, n)
    out["same"] = all(all(np.array_equal(a, b, equal_nan=True) for a, b in zip(r, ref))
                      for r in results)
    return out


def case_raycaster():
    from ernest_cpp import dynamics as D
    from ernest_cpp import perception as P
    cam = P.StereoCameraParameters()
    cam.width, cam.height = 160, 120
    rc = P.Raycaster(D.HeightMap.flat(30.0, 20.0, 0.05, 0.0, -5.0, -10.0), [])
    pose = cam.camera_pose(np.array([0.0, 0.0, 0.17]), np.eye(3), 0)
    return shared(lambda: rc.render(pose, cam, 0), 20)


def case_soil():
    from ernest_cpp import soil as S
    m = S.BekkerWongModel(S.soil_preset("m90"), S.ernest_wheel(), 32)
    rng = np.random.default_rng(0)
    states = np.column_stack([rng.uniform(1e-3, 0.1, 2000), rng.uniform(-0.3, 0.3, (2000, 4))])
    return shared(lambda: (m.evaluate_batch(states),), 20)


def case_walker_model():
    W, model = walker()
    q = model.standard_configuration
    body = model.standard_body_pose()
    return shared(lambda: (model.foot_pose(1, q[:, 1]), model.center_of_mass(body, q),
                           model.contact_jacobian(2, q[:, 2])), 500)


if __name__ == "__main__":
    print(json.dumps(globals()["case_" + sys.argv[1]]()))
