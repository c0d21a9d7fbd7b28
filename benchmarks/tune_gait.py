"""Tune a scripted obstacle gait of ``envs.climbing`` by CMA-ES, then check it over ten seeds at
the default physics step and at a quarter of it.

    python benchmarks/tune_gait.py step                    # check the committed step climb
    python benchmarks/tune_gait.py step --generations 25   # tune it from its defaults
    python benchmarks/tune_gait.py bickler --generations 25

``step``: ``StepClimbController`` (seven phases after the front wheels reach the face);
``bickler``: ``BicklerCrossController`` (four phases after the rear wheels reach the rocks).
A gait's numbers (the approach yaw, each phase's duration, yaw, roll and speed, the trigger
distance) are searched in a box normalised to [0, 1] (durations 0.5-8 s, yaw +-45 deg, roll +-30
deg, speed 0-0.2 m/s, trigger 0.02-0.22 m). The objective is the mean over six episodes of
(wheels over + 0.05 x episode return): the course's seeds 0-3 (the obstacle friction differs per
seed) and, for the step, two aligned ``ernest/Step-v0`` trials with other step heights, for the
trap seeds 4-5. Needs ``pip install cma``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import ernest_cpp.envs  # noqa: F401
from ernest_cpp.envs import climbing as CL
from ernest_cpp.envs.climbing import PhaseGait
from ernest_cpp.reproduce import wheels_over
from ernest_cpp.rl.envs_util import make_env

LO = np.array([0.5, -45.0, -30.0, 0.0])
HI = np.array([8.0, 45.0, 30.0, 0.2])
TRIGGER = (0.02, 0.22)
ALIGNED_STEPS = {"episode_length": 60.0,
                 "randomisation": {"range_scale": 0.0, "step_height_range": [0.2, 0.36]}}
#: course: (defaults, trigger, trigger wheels, env id, obstacle kind, tuning trials)
COURSES = {
    "step": (CL.STEP_CLIMB_PHASES, CL.STEP_CLIMB_TRIGGER, "front", "ernest/WheelStep-v0", "step",
             [("ernest/WheelStep-v0", {}, s) for s in range(4)] +
             [("ernest/Step-v0", ALIGNED_STEPS, s) for s in (2000001, 2000002)]),
    "bickler": (CL.BICKLER_PHASES, CL.BICKLER_TRIGGER, "rear", "ernest/BicklerTrap-v0",
                "bickler", [("ernest/BicklerTrap-v0", {}, s) for s in range(6)]),
}


def decode(z: np.ndarray):
    z = np.clip(z, 0.0, 1.0)
    phases = [(0.0, -45.0 + 90.0 * z[0], 0.0, 0.2)]
    for i in range((len(z) - 2) // 4):
        phases.append(tuple(float(v) for v in LO + (HI - LO) * z[1 + 4 * i:5 + 4 * i]))
    return phases, TRIGGER[0] + (TRIGGER[1] - TRIGGER[0]) * float(z[-1])


def encode(phases, trigger) -> np.ndarray:
    z = [(phases[0][1] + 45.0) / 90.0]
    for p in phases[1:]:
        z += list((np.asarray(p) - LO) / (HI - LO))
    return np.array(z + [(trigger - TRIGGER[0]) / (TRIGGER[1] - TRIGGER[0])])


def episode(gait, env, seed: int, kind: str = "step") -> tuple[int, float, float]:
    """(wheels over, return, progress along the path) of one episode."""
    gait.reset()
    obs, _ = env.reset(seed=seed)
    ret = 0.0
    while True:
        obs, r, term, trunc, info = env.step(gait(obs, env))
        ret += r
        if term or trunc:
            return wheels_over(kind, env.unwrapped), ret, float(info["path_progress"])


def tune(course: str, generations: int, popsize: int, sigma: float, seed: int):
    import cma

    phases0, trigger0, wheels, _, kind, trials = COURSES[course]
    trials = [(make_env(env_id, kw), s) for env_id, kw, s in trials]

    def objective(z):
        phases, trigger = decode(z)
        g = PhaseGait(phases, trigger, trigger_wheels=wheels)
        total = 0.0
        for env, s in trials:
            w, ret, _ = episode(g, env, s, kind)
            total += w + 0.05 * ret
        return -total / len(trials)

    x0 = encode(phases0, trigger0)
    best = (objective(x0), x0)
    print(f"defaults: objective {-best[0]:.3f}", flush=True)
    es = cma.CMAEvolutionStrategy(x0, sigma, {"bounds": [0, 1], "popsize": popsize,
                                              "seed": seed, "verbose": -9})
    t0 = time.perf_counter()
    for gen in range(generations):
        zs = es.ask()
        fs = [objective(z) for z in zs]
        es.tell(zs, fs)
        i = int(np.argmin(fs))
        if fs[i] < best[0]:
            best = (fs[i], np.array(zs[i]))
        print(f"generation {gen + 1}/{generations}: best {-best[0]:.3f}, this generation "
              f"{-fs[i]:.3f} (median {-np.median(fs):.3f}), {time.perf_counter() - t0:.0f} s",
              flush=True)
    return decode(best[1])


def check(course: str, phases, trigger, seeds: int = 10) -> None:
    _, _, wheels, env_id, kind, _ = COURSES[course]
    for label, kw in (("dt 0.0125 s", {}), ("dt / 4", {"physics_dt": 0.003125})):
        env = make_env(env_id, kw)
        rows = [episode(PhaseGait(phases, trigger, trigger_wheels=wheels), env, s, kind)
                for s in range(seeds)]
        over = [r[0] for r in rows]
        print(f"{env_id}, {label}: all four wheels over in {sum(w == 4 for w in over)}/"
              f"{seeds} seeds (wheels {over}), progress {np.mean([r[2] for r in rows]):.2f} m "
              f"(min {min(r[2] for r in rows):.2f})", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("course", choices=sorted(COURSES))
    p.add_argument("--generations", type=int, default=0, help="CMA-ES generations (0: check only)")
    p.add_argument("--popsize", type=int, default=10)
    p.add_argument("--sigma", type=float, default=0.08, help="initial step in the unit box")
    p.add_argument("--seed", type=int, default=3)
    p.add_argument("--out", help="write the best phases and trigger to this JSON file")
    a = p.parse_args()
    phases, trigger = list(COURSES[a.course][0]), COURSES[a.course][1]
    if a.generations > 0:
        phases, trigger = tune(a.course, a.generations, a.popsize, a.sigma, a.seed)
        for ph in phases:
            print("    (%.2f, %.2f, %.2f, %.3f)," % ph)
        print(f"trigger {trigger:.3f}")
        if a.out:
            with open(a.out, "w") as fh:
                json.dump({"phases": phases, "trigger": trigger}, fh, indent=1)
    check(a.course, phases, trigger)


if __name__ == "__main__":
    main()
