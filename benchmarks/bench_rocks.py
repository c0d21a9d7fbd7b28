"""Rock contacts (issue 17, item 2): microseconds per step against the number of rocks the rover
is touching at the start of the step (SolverStats.obstacles_touched), not merely present. One
rover drives 0.15 m/s on M90 through a dense field of box rocks; every step is timed on its own
and binned by the rocks in contact. Each step in contact is obstacle_substeps = 8 substeps
(issue 13); "substeps off" is timed too. Reference in the same run: the same rover with the rock
contacts always solved with their friction bounds (SimOptions.guess_obstacle_contacts = False,
ODE's pivoting solver, as before issue 17), on the same rocks; and the cost of an empty call
from Python (step_n(0)), which every timed step includes.

    python benchmarks/bench_rocks.py [--steps 2400]
"""

import argparse
import os
import statistics
import sys
import time

from ernest_cpp import dynamics as D

SPEED = 0.15  # [m/s]


def run(rocks, steps: int, substeps: int, guess: bool):
    o = D.make_options("soil", friction=0.8)
    o.obstacle_substeps = substeps
    o.guess_obstacle_contacts = guess
    sim = D.make_sim(obstacles=rocks, options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, SPEED)
    c = D.Commands()
    c.wheel_speed = [SPEED / sim.parameters.wheel_radius] * 4
    sim.set_commands(c)
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
    args = ap.parse_args()
    rocks = D.rock_field(100, seed=7, length=2.0, width=2.0, x0=0.8)
    sim = D.make_sim()
    t0 = time.perf_counter_ns()
    for _ in range(10000):
        sim.step_n(0)
    empty = (time.perf_counter_ns() - t0) * 1e-3 / 10000
    print(f"load average {os.getloadavg()[0]:.1f}; 100 box rocks (rock_field(100, seed=7, "
          f"length=2, x0=0.8)), M90, {args.steps} steps of {D.SimOptions().dt} s; an empty call "
          f"from Python costs {empty:.2f} us (included below)")
    print("| rocks in contact | substeps | steps | guessed (us/step, median) | bounded, before "
          "(us/step) | ratio |")
    print("|---|---|---|---|---|---|")
    for substeps in (8, 1):
        new, stats, x = run(rocks, args.steps, substeps, True)
        old, _, x_old = run(rocks, args.steps, substeps, False)
        for k in sorted(set(new) | set(old)):
            a = statistics.median(new[k]) if k in new else float("nan")
            b = statistics.median(old[k]) if k in old else float("nan")
            print(f"| {k} | {substeps} | {len(new.get(k, []))} / {len(old.get(k, []))} | {a:.1f} | "
                  f"{b:.1f} | {a / b:.2f} |")
        shares = stats.obstacle_guessed / max(1, stats.obstacle_guessed + stats.obstacle_bounded)
        print(f"substeps {substeps}: obstacle (sub)steps solved sticking (sparse) "
              f"{stats.obstacle_guessed}, bounded (pivoted) {stats.obstacle_bounded} "
              f"({100 * shares:.0f} % guessed); travelled {x:.2f} m (bounded: {x_old:.2f} m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
