"""Every kept checkpoint of training runs on the evaluation courses (the ablation tables of
policies/TRAINING.md): wheels over and progress on the wheel-high step and the Bickler trap,
travel reduction on the 20 deg slopes, against the training run's wall time.

    python benchmarks/eval_checkpoints.py runs/abl/B_demo60 [more runs] --seeds 10 \
        --courses step,bickler --out runs/abl/table.md

A course row counts a seed as crossed when all four wheels end over the obstacle
(``reproduce.wheels_over``).
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

import ernest_cpp.envs  # noqa: F401
from ernest_cpp.reproduce import wheels_over
from ernest_cpp.rl.checkpoints import STEP_DIR, agent_from_checkpoint, load_checkpoint
from ernest_cpp.rl.envs_util import make_env

COURSES = {  # name: (env id, kwargs, obstacle kind for wheels_over or None)
    "step": ("ernest/WheelStep-v0", {}, "step"),
    "bickler": ("ernest/BicklerTrap-v0", {}, "bickler"),
    "slope_dry": ("ernest/SlopeEval-v0", {"soil": "m90"}, None),
    "slope_wet": ("ernest/SlopeEval-v0", {"soil": "wet_sand"}, None),
}


def course_result(policy, course: str, seeds: int) -> dict:
    env_id, kwargs, kind = COURSES[course]
    env = make_env(env_id, kwargs)
    over, prog, tr, lat = [], [], [], []
    for s in range(seeds):
        obs, _ = env.reset(seed=s)
        worst = 0.0
        while True:
            obs, _, term, trunc, info = env.step(policy(obs))
            worst = max(worst, abs(float(info["lateral_deviation"])))
            if term or trunc:
                break
        u = env.unwrapped
        prog.append(float(info["path_progress"]))
        tr.append(float(u.metrics["travel_reduction"]))
        lat.append(worst)
        if kind:
            over.append(wheels_over(kind, u))
    env.close()
    out = {"progress": float(np.mean(prog)), "travel_reduction": float(np.mean(tr)),
           "max_lateral": float(np.max(lat))}
    if kind:
        out["crossed"] = int(sum(w == 4 for w in over))
        out["wheels_over"] = over
    return out


def checkpoints(run: str) -> list[str]:
    root = os.path.join(run, "checkpoints")
    if not os.path.isdir(root):  # a checkpoint folder itself
        return [run]
    names = sorted((d for d in os.listdir(root) if STEP_DIR.match(d)), key=lambda d: int(d[5:]))
    return [os.path.join(root, d) for d in names] or [run]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("runs", nargs="+")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--courses", default="step")
    p.add_argument("--last", action="store_true", help="only each run's newest checkpoint")
    p.add_argument("--out", help="append the markdown rows to this file")
    a = p.parse_args()
    courses = [c.strip() for c in a.courses.split(",")]
    bad = sorted(set(courses) - set(COURSES))
    if bad:
        raise SystemExit(f"--courses: unknown {', '.join(bad)}; choose from {', '.join(COURSES)}")
    head = "| run | transitions | wall time [min] | " + " | ".join(
        f"{c}: crossed / progress [m]" if COURSES[c][2] else f"{c}: travel reduction / max |lateral|"
        for c in courses) + " |"
    lines = [head, "|" + "---|" * (3 + len(courses))]
    print(lines[0], flush=True)
    t0 = time.perf_counter()
    for run in a.runs:
        cks = checkpoints(run)
        for ck_path in cks[-1:] if a.last else cks:
            ck = load_checkpoint(ck_path, with_buffer=False)
            agent = agent_from_checkpoint(ck)
            st = ck["state"]
            cells = []
            for c in courses:
                r = course_result(agent.act, c, a.seeds)
                cells.append(f"{r['crossed']}/{a.seeds} / {r['progress']:.2f}" if "crossed" in r
                             else f"{100 * r['travel_reduction']:.1f} % / {r['max_lateral']:.2f} m")
            row = (f"| {os.path.basename(os.path.normpath(run))} | {st['step']} | "
                   f"{st.get('elapsed', float('nan')) / 60:.1f} | " + " | ".join(cells) + " |")
            lines.append(row)
            print(row, f"({time.perf_counter() - t0:.0f} s)", flush=True)
    if a.out:
        with open(a.out, "a") as fh:
            fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
