"""Implicit slip's warm start: how many solves a step takes for its
slip (1 + the step's SolverStats.slip_solves), step by step, with SimOptions.slip_warm_start on
(the default) and off (eq 12 at the step's start and the last step's soil-row levels), on bench_dynamics.py's driving runs: the rover rolling at 0.15 m/s on flat M90, into
rock_field(20) (it stalls against a rock) and into rock_field(100). Prints, per scenario, the
share of steps (and of steps touching a rock) accepted after one solve, the mean solves per step,
and the median microseconds per step with the ratio warm / cold measured in the same run
(wall clock: say the load average next to it; the instruction counts of profile_rocks.cpp decide).

    python benchmarks/bench_slip_warm.py [--steps 800] [--run-up 50]
"""

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from ernest_cpp import dynamics as D  # noqa: E402
from bench_util import rolling_rover  # noqa: E402


def run(rocks, warm: bool, steps: int, run_up: int):
    sim = rolling_rover(rocks, slip_warm_start=warm)
    sim.step_n(run_up)
    solves, touching, us = [], [], []
    clock = time.perf_counter_ns
    for _ in range(steps):
        before = sim.solver_stats.slip_solves
        t0 = clock()
        sim.step()
        us.append((clock() - t0) * 1e-3)
        solves.append(1 + sim.solver_stats.slip_solves - before)
        touching.append(sim.solver_stats.obstacles_touched > 0)
    return solves, touching, us, sim.state.position[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=800)
    ap.add_argument("--run-up", type=int, default=50, help="steps not counted (profile_rocks' 50)")
    args = ap.parse_args(argv)
    fields = {"flat M90": [], "M90 + 20 rocks": D.rock_field(20, seed=7, length=2.0, width=2.0, x0=0.8),
              "M90 + 100 rocks": D.rock_field(100, seed=7, length=2.0, width=2.0, x0=0.8)}
    print(f"{args.steps} steps after {args.run_up}; load average {os.getloadavg()[0]:.2f}")
    print("| scenario | warm start | x [m] | 1 solve (all) | 1 solve (touching) | 2 | 3+ | "
          "solves/step | us/step | warm / cold |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, rocks in fields.items():
        med = {}
        for warm in (False, True):
            s, t, us, x = run(rocks, warm, args.steps, args.run_up)
            st = [v for v, k in zip(s, t) if k]
            one_t = f"{sum(v == 1 for v in st)} / {len(st)}" if st else "-"
            med[warm] = statistics.median(us)
            ratio = f"{med[True] / med[False]:.3f}" if warm else ""
            print(f"| {name} | {'on' if warm else 'off'} | {x:.3f} | {sum(v == 1 for v in s)} / {len(s)} | "
                  f"{one_t} | {sum(v == 2 for v in s)} | {sum(v >= 3 for v in s)} | "
                  f"{statistics.fmean(s):.3f} | {med[warm]:.2f} | {ratio} |", flush=True)
    print(f"load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
