"""The Bickler trap of seed 004 §5.2 (``ernest/BicklerTrap-v0``): which row of rocks, on which
ground, gives the paper's passive outcome (Fig. 17) at every obstacle friction of Table 3?

The passive bogie (``PassiveController`` at 0.2 m/s, ``passive=True``: gimbal off, clutch open)
drives at the trap for the course's episode (60 s), then the episode's simulator drives it
backwards at 0.2 m/s for 20 s (``reproduce.front_wheels_back``). Each cell reports the wheels
over at the end of the forward run (front/rear: centres past the rocks' far edge), the progress,
and the front wheels back before the rocks' near edge after reversing. The paper's outcome
("trap", marked ``*``): front 2, rear 0, and 0 back (the front wheels cannot climb back).

Grid: rock height x obstacle friction (``randomisation`` fields ``bickler_height``,
``obstacle_friction``) x ground (Table 2's M90 and dry sand, our wet sand, rigid ground, on which
the same friction holds for the ground as for the rocks) at the course's depth, then the depth
along the path (``bickler_depth``) on the ground and heights around the course's, then the course
itself (its defaults) over seeds (the rocks' tops differ by up to +-5 mm by seed) at the default
physics step and at a quarter of it.

    ./run bench bickler_scan            # ~8 min on one core
    ./run bench bickler_scan --quick    # a few cells of each part (~10 s)
    ./run bench bickler_scan --course   # only the course: 10 seeds, and 3 at dt / 4
"""

from __future__ import annotations

import argparse
import sys
import time

import gymnasium as gym
import numpy as np

import ernest_cpp.envs  # noqa: F401  (registers the ids)
from ernest_cpp import dynamics as D
from ernest_cpp.envs.baselines import PassiveController
from ernest_cpp.reproduce import front_wheels_back

GROUNDS = {  # label: gym.make kwargs
    "M90": {"soil": "m90"},
    "wet sand": {"soil": "wet_sand"},
    "dry sand": {"soil": "dry_sand"},
    "rigid": {"rigid_ground": True},
}
FRICTIONS = (0.5, 0.6, 0.7, 0.8, 0.9)


def run_cell(ground: dict, friction: float, height: float | None = None,
             depth: float | None = None, seed: int = 0, physics_dt: float = 0.0,
             episode_length: float = 0.0, reverse: float = 20.0) -> dict:
    """One forward episode of the passive bogie and the reverse test. ``height``/``depth`` None:
    the course's defaults. Returns front/rear wheels over, progress [m], front wheels back."""
    rnd = {"obstacle_friction": friction}
    if height is not None:
        rnd["bickler_height"] = height
    if depth is not None:
        rnd["bickler_depth"] = depth
    env = gym.make("ernest/BicklerTrap-v0", passive=True, randomisation=rnd,
                   physics_dt=physics_dt, episode_length=episode_length, **ground)
    policy = PassiveController()
    obs, _ = env.reset(seed=seed)
    while True:
        obs, _, term, trunc, _ = env.step(policy(obs))
        if term or trunc:
            break
    u = env.unwrapped
    far = float(max(o[0] + 0.5 * o[3] for o in np.asarray(u.scenario.obstacles)))
    x = np.asarray(u.core.state.wheel_position)[:, 0]
    out = {"front": int(np.sum(x[:2] > far)), "rear": int(np.sum(x[2:] > far)),
           "progress": float(u.metrics["progress"]), "friction": float(u.core.sim.friction)}
    out["back"] = front_wheels_back(u, reverse)
    out["trap"] = out["front"] == 2 and out["rear"] == 0 and out["back"] == 0
    return out


def run_seeds(seeds, *args, **kwargs) -> dict:
    """``run_cell`` for each seed (the rocks' tops differ by up to +-5 mm by seed): the first
    seed's numbers, and in ``traps`` how many seeds give the paper's outcome."""
    cells = [run_cell(*args, seed=s, **kwargs) for s in seeds]
    out = dict(cells[0])
    out["traps"], out["seeds"] = sum(c["trap"] for c in cells), len(cells)
    out["trap"] = out["traps"] == out["seeds"]
    return out


def cell_text(c: dict) -> str:
    n = f" {c['traps']}/{c['seeds']}" if "seeds" in c else ""
    return (f"{c['front']}/{c['rear']} {c['progress']:4.2f} {c['back']}{n}"
            f"{'*' if c['trap'] else ''}")


class Progress:
    def __init__(self, total: int):
        self.total, self.done, self.t0 = total, 0, time.perf_counter()

    def tick(self, label: str) -> None:
        self.done += 1
        el = time.perf_counter() - self.t0
        eta = el / self.done * (self.total - self.done)
        print(f"  [{self.done}/{self.total}] {label}  ({el:.0f} s, ~{eta:.0f} s left)",
              file=sys.stderr, flush=True)


def table(title: str, rows: list[tuple[str, list[dict]]], head: str, cols) -> list[str]:
    out = [f"### {title}", "", f"| {head} | " + " | ".join(f"mu {m}" for m in cols) + " |",
           "|---|" + "---|" * len(cols)]
    out += [f"| {label} | " + " | ".join(cell_text(c) for c in cells) + " |"
            for label, cells in rows]
    return out + [""]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a few cells of each part")
    ap.add_argument("--reverse", type=float, default=20.0, help="reversing time [s]")
    ap.add_argument("--seeds", type=int, default=3, help="seeds per cell of the grids")
    ap.add_argument("--course", action="store_true", help="only the course (part 3)")
    args = ap.parse_args()
    from ernest_cpp._core import envs as _envs

    course = _envs.ScenarioOptions()  # the course's defaults
    h0, d0 = course.bickler_height, course.bickler_depth
    if args.quick:
        heights, frictions, grounds = (0.06, h0, 0.12), (0.5, 0.9), GROUNDS
        depths, dheights, seeds = (0.2,), (h0,), (0,)
        args.seeds = 1
    else:
        heights = (0.06, 0.07, 0.08, 0.09, 0.10, 0.11, 0.12, 0.13, 0.14, 0.16, 0.18, 0.20)
        frictions, grounds = FRICTIONS, GROUNDS
        depths, dheights, seeds = (0.2, 0.45), (0.07, 0.08, 0.09, 0.10, 0.11), tuple(range(10))
    if args.course:
        heights, grounds, depths = (), {}, ()
    # the course's ground: the registered kwargs of ernest/BicklerTrap-v0
    soil = gym.spec("ernest/BicklerTrap-v0").kwargs.get("soil", "m90")
    chosen = next(g for g, kw in GROUNDS.items() if kw.get("soil") == soil)
    dt = D.SimOptions().dt
    grid_seeds = range(args.seeds)
    n = (len(heights) * len(grounds) + len(depths) * len(dheights)) * len(frictions) \
        + (len(seeds) + len(seeds[:3])) * len(frictions)
    prog = Progress(n)
    rv = args.reverse
    md = ["Cells: front/rear wheels over after the forward run, progress [m], front wheels back "
          f"after {rv:g} s reversing (seed 0); in the grids, then the seeds of {args.seeds} (0, "
          "1, ...) that give the paper's outcome (2/0, 0 back); * = all of them do.", ""]

    # 1. height x friction x ground, the course's depth
    for g, kw in grounds.items():
        rows = []
        for h in heights:
            cells = []
            for mu in frictions:
                cells.append(run_seeds(grid_seeds, kw, mu, height=h, reverse=rv))
                prog.tick(f"{g} h {h:.2f} mu {mu}: {cell_text(cells[-1])}")
            rows.append((f"{h:.2f}", cells))
        md += table(f"{g}, depth {d0:g} m: height [m] x friction", rows, "height [m]", frictions)

    # 2. depth along the path, on the course's ground
    rows = []
    dheights = dheights if depths else ()
    for d in depths:
        for h in dheights:
            cells = []
            for mu in frictions:
                cells.append(run_seeds(grid_seeds, GROUNDS[chosen], mu, height=h, depth=d,
                                       reverse=rv))
                prog.tick(f"{chosen} depth {d} h {h:.2f} mu {mu}: {cell_text(cells[-1])}")
            rows.append((f"{d:g} / {h:.2f}", cells))
    if rows:
        md += table(f"{chosen}: depth / height [m] x friction", rows, "depth / height [m]",
                    frictions)

    # 3. the course (its defaults): seeds, and a quarter of the physics step
    rows = []
    for s in seeds:
        cells = []
        for mu in frictions:
            cells.append(run_cell({}, mu, seed=s, reverse=rv))  # the course as registered
            prog.tick(f"course seed {s} mu {mu}: {cell_text(cells[-1])}")
        rows.append((f"seed {s}, dt {dt:g} s", cells))
    for s in seeds[:3]:
        cells = []
        for mu in frictions:
            cells.append(run_cell({}, mu, seed=s, physics_dt=dt / 4, reverse=rv))
            prog.tick(f"course seed {s} dt/4 mu {mu}: {cell_text(cells[-1])}")
        rows.append((f"seed {s}, dt {dt / 4:g} s", cells))
    md += table(f"The course: {chosen}, height {h0:g} m, depth {d0:g} m", rows, "run", frictions)
    print("\n".join(md))
    ok = all(c["trap"] for _, cs in rows for c in cs)
    print(f"course gives the paper's passive outcome at every friction: {'yes' if ok else 'NO'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
