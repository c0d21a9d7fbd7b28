"""Step ladder of the obstacle courses: cost of transport and travel
reduction of ``ernest evaluate``'s Bickler trap, wheel-high step and mixed course (passive bogie
and crawling gait, seed 0) at dt, dt/2, dt/4, dt/8 and dt/16 with one obstacle substep, and at
dt, dt/2 and dt/4 with the default substeps. Comparing dt with dt/4 alone can miss a step size in
between where the result moves (bench_step_independence.py compares those two only).

    python benchmarks/bench_step_ladder.py [--course Bickler ...]     (about 1 minute)
"""

import argparse
import sys
import time

import ernest_cpp.envs  # noqa: F401  (registers the ids)
from ernest_cpp import evaluate
from ernest_cpp._core import dynamics as _dyn

COURSES = ("Bickler", "Wheel-high", "Mixed")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--course", action="append", default=[],
                    help="only courses whose label contains this (repeatable; default: the three "
                         "obstacle courses)")
    args = ap.parse_args(argv)
    wanted = args.course or list(COURSES)
    dt = _dyn.SimOptions().dt
    default = _dyn.SimOptions().obstacle_substeps
    ctrls = evaluate.controllers(None)
    print(f"CoT (travel reduction %) at dt / k, dt = {dt} s, seed 0; substeps 1 and {default} "
          "(default)", flush=True)
    print("| course, controller | substeps | " + " | ".join(f"dt/{k}" for k in (1, 2, 4, 8, 16)) + " |")
    print("|---|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    for label, env_id, kwargs in evaluate.COURSES:
        if not any(c in label for c in wanted):
            continue
        for name, (pol, passive) in ctrls.items():
            # With the default of one substep the second row would repeat the first.
            rows = ((1, (1, 2, 4, 8, 16)),) + (((default, (1, 2, 4)),) if default != 1 else ())
            for sub, ks in rows:
                cells = []
                for k in (1, 2, 4, 8, 16):
                    if k not in ks:
                        cells.append("")
                        continue
                    m = evaluate.run_episode(env_id, dict(kwargs, physics_dt=dt / k, obstacle_substeps=sub),
                                             pol, passive, 0)[0]
                    cells.append(f"{m['cost_of_transport']:.3f} ({100 * m['travel_reduction']:.1f})")
                print(f"| {label}, {name} | {sub} | " + " | ".join(cells) + " |", flush=True)
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
