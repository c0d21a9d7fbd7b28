"""Every kept checkpoint of training runs on the evaluation courses (the ablation tables of
policies/TRAINING.md): wheels over and progress on the wheel-high step and the Bickler trap,
travel reduction on the 20 deg slopes, against the training run's wall time.

    python benchmarks/eval_checkpoints.py runs/abl/B_demo60 [more runs] --seeds 10 \
        --courses step,bickler --out runs/abl/table.md
    python benchmarks/eval_checkpoints.py runs/default/consolidated-s3 --first-seed 100 --seeds 20

A consolidation folder lists its kept agents (``iteration-N``, ``consolidate.keep_every``) and its
final one, with the iterations in the transitions column.

A course row counts a seed as crossed when all four wheels end over the obstacle
(``reproduce.wheels_over``).
"""

from __future__ import annotations

import argparse
import os
import re
import time

from eval_policy import row  # the same episodes and figures as the exported policy's table

from ernest_cpp.rl.checkpoints import STEP_DIR, agent_from_checkpoint, load_checkpoint

ITERATION_DIR = re.compile(r"^iteration-\d+$")
COURSES = {  # name: (env id, kwargs, obstacle kind for wheels_over or None)
    "step": ("ernest/WheelStep-v0", {}, "step"),
    "bickler": ("ernest/BicklerTrap-v0", {}, "bickler"),
    "slope_dry": ("ernest/SlopeEval-v0", {"soil": "m90"}, None),
    "slope_wet": ("ernest/SlopeEval-v0", {"soil": "wet_sand"}, None),
}


def course_result(policy, course: str, seeds: int, first_seed: int = 0) -> dict:
    """``eval_policy.row`` for a policy on normalised observations (a checkpoint's actor)."""
    env_id, kwargs, kind = COURSES[course]
    return row(env_id, kwargs, kind, lambda obs, env=None: policy(obs), False, seeds, first_seed)


def kind_of(course: str) -> str | None:
    return COURSES[course][2]


def checkpoints(run: str) -> list[str]:
    root = os.path.join(run, "checkpoints")
    if not os.path.isdir(root):  # a checkpoint folder itself
        return [run]
    names = sorted((d for d in os.listdir(root) if STEP_DIR.match(d)), key=lambda d: int(d[5:]))
    # a consolidation folder: its kept agents (iteration-N) and its final one
    kept = sorted(d for d in os.listdir(root) if ITERATION_DIR.match(d))
    if kept or os.path.isdir(os.path.join(root, "consolidated")):
        names = kept + ["consolidated"] * os.path.isdir(os.path.join(root, "consolidated"))
    return [os.path.join(root, d) for d in names] or [run]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("runs", nargs="+")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first-seed", type=int, default=0,
                   help="seeds first..first+seeds-1 (e.g. 100: the select stage's validation seeds)")
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
                r = course_result(agent.act, c, a.seeds, a.first_seed)
                cells.append(f"{r['crossed']}/{a.seeds} / {r['progress']:.2f}" if kind_of(c)
                             else f"{r['tr']:.1f} % / {r['lat']:.2f} m")
            done = st.get("consolidation", {}).get("iterations", st["step"])  # or iterations
            row = (f"| {os.path.basename(os.path.normpath(run))} | {done} | "
                   f"{st.get('elapsed', float('nan')) / 60:.1f} | " + " | ".join(cells) + " |")
            lines.append(row)
            print(row, f"({time.perf_counter() - t0:.0f} s)", flush=True)
    if a.out:
        with open(a.out, "a") as fh:
            fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
