"""Rock contacts: microseconds per step against the number of rocks the rover
is touching at the start of the step (SolverStats.obstacles_touched), not merely present. One
rover drives 0.15 m/s on M90 through two fields: low flat rocks that the wheels roll onto
(their contacts stick: the guessed path) and 100 box rocks that stop the rover (a wheel spinning
against a rock face slides: ODE's bounded contact); every step is timed on its own and binned by
the rocks in contact. Timed with the default obstacle_substeps (1: a step in
contact split only where a wheel's slip grows fast) and with 8 (the defaults of --substeps). Reference in the same run: the same rover with the rock
contacts always solved with their friction bounds (SimOptions.guess_obstacle_contacts = False,
ODE's pivoting solver), on the same rocks; and the cost of an empty call
from Python (step_n(0)), which every timed step includes.

    python benchmarks/bench_rocks.py [--steps 2400] [--contact exact]
    python benchmarks/bench_rocks.py --dump-rocks 20 /tmp/rocks20.txt   # for profile_rocks.cpp
"""

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

from ernest_cpp import dynamics as D
from bench_util import rolling_rover

SPEED = 0.15  # [m/s]


def low_rocks(n: int, seed: int = 3) -> list:
    """n flat box rocks, 0.2-0.5 m across, their tops 1 cm below to 2 cm above the soil surface,
    in x in [0.8, 3.8] m, |y| <= 1 m: the wheels sink onto them and roll over them."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        s = np.array([rng.uniform(0.2, 0.5), rng.uniform(0.2, 0.5), 0.1])
        top = rng.uniform(-0.01, 0.02)
        c = np.array([rng.uniform(0.8, 3.8), rng.uniform(-1.0, 1.0), top - s[2] / 2])
        out.append(D.BoxObstacle(c, s, float(rng.uniform(0, math.pi)), 0.0, 0.0))
    return out


def run(rocks, steps: int, substeps: int, guess: bool, contact=None):
    sim = rolling_rover(rocks, SPEED, substeps, guess, contact=contact)
    sim.step_n(20)
    bins: dict[int, list[float]] = {}
    clock = time.perf_counter_ns
    for _ in range(steps):
        t0 = clock()
        sim.step()
        t = (clock() - t0) * 1e-3
        bins.setdefault(sim.solver_stats.obstacles_touched, []).append(t)
    return bins, sim.solver_stats, sim.state.position[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=2400, help="steps per run (30 s at 0.0125 s)")
    ap.add_argument("--substeps", type=int, nargs="+", default=sorted({D.SimOptions().obstacle_substeps, 8}, reverse=True),
                    help="SimOptions.obstacle_substeps values to time (default: 8 and the default)")
    ap.add_argument("--contact", choices=("ode", "exact"),
                    help="SimOptions.wheel_obstacle_contact (default: the option's default)")
    ap.add_argument("--dump-rocks", nargs=2, metavar=("N", "FILE"),
                    help="write bench_dynamics.py's N rocks (rock_field(N, seed=7, length=2, width=2, "
                         "x0=0.8)) to FILE, one 'cx cy cz sx sy sz yaw' a line, for "
                         "benchmarks/profile_rocks.cpp, and exit")
    args = ap.parse_args()
    if args.dump_rocks:
        n, path = int(args.dump_rocks[0]), args.dump_rocks[1]
        with open(path, "w") as f:
            for r in D.rock_field(n, seed=7, length=2.0, width=2.0, x0=0.8):
                f.write(" ".join(f"{v:.17g}" for v in (*r.centre, *r.size, r.yaw)) + "\n")
        return 0
    fields = {"low flat rocks (rolled over)": low_rocks(60),
              "rock_field(100, seed=7, length=2, x0=0.8) (stalls)":
                  D.rock_field(100, seed=7, length=2.0, width=2.0, x0=0.8)}
    sim = D.make_sim()
    t0 = time.perf_counter_ns()
    for _ in range(10000):
        sim.step_n(0)
    empty = (time.perf_counter_ns() - t0) * 1e-3 / 10000
    print(f"load average {os.getloadavg()[0]:.1f}; M90, {args.steps} steps of {D.SimOptions().dt} s "
          f"at {SPEED} m/s; an empty call from Python costs {empty:.2f} us (included below)")
    print("| field | substeps | rocks in contact | steps | guessed (us/step, median) | "
          "always bounded (us/step) | ratio |")
    print("|---|---|---|---|---|---|---|")
    notes = []
    for name, rocks in fields.items():
        for substeps in args.substeps:
            contact = {None: None, "ode": D.WheelObstacleContact.Ode,
                       "exact": D.WheelObstacleContact.Exact}[args.contact]
            new, stats, x = run(rocks, args.steps, substeps, True, contact)
            old, _, x_old = run(rocks, args.steps, substeps, False, contact)
            for k in sorted(set(new) | set(old)):
                a = statistics.median(new[k]) if k in new else float("nan")
                b = statistics.median(old[k]) if k in old else float("nan")
                print(f"| {name} | {substeps} | {k} | {len(new.get(k, []))} / {len(old.get(k, []))} "
                      f"| {a:.1f} | {b:.1f} | {a / b:.2f} |", flush=True)
            share = stats.obstacle_guessed / max(1, stats.obstacle_guessed + stats.obstacle_bounded)
            notes.append(f"{name}, substeps {substeps}: obstacle (sub)steps solved sticking "
                         f"{stats.obstacle_guessed}, bounded {stats.obstacle_bounded} "
                         f"({100 * share:.0f} % guessed); travelled {x:.2f} m (bounded: {x_old:.2f} m)")
    print("\n".join(notes))
    return 0


if __name__ == "__main__":
    sys.exit(main())
