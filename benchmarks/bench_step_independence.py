"""Step independence of the evaluation results (issue 13, item 1): every evaluation course of
``ernest evaluate`` (seed 004 §5, Table 6) with every controller (passive bogie, crawling gait,
the committed learned policy), run at the default physics step and at a quarter of it. Prints
travel reduction and cost of transport at both steps, their differences, and whether they are
within the targets (2 percentage points of travel reduction, 5 % of cost of transport).

    ./run bench step_independence                # default policy, seed 0
    ./run bench step_independence --seeds 0 1 2  # more episodes (the same seeds at both steps)
    ./run bench step_independence --ensemble 24  # each row: means over seeds 0..23 at both steps

The environments' sensor noise follows the seed. Where a controller's outcome is a bifurcation
(the learned policy stalling at one rock or another on the mixed course), one episode's travel
reduction changes by tens of points from seed to seed, at any step; --ensemble then compares the
means over the same seeds at both steps and prints their standard errors.

Exit status 1 if any row misses a target. A cost of transport is compared only where the rover
made progress at both steps (it is infinite otherwise).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import ernest_cpp.envs  # noqa: F401  (registers the ids)
from ernest_cpp import evaluate
from ernest_cpp._core import dynamics as _dyn

TR_TARGET_PP = 2.0
COT_TARGET = 0.05


def _row(label, name, coarse, fine):
    tr_c, tr_f = 100 * coarse["travel_reduction"], 100 * fine["travel_reduction"]
    cot_c, cot_f = coarse["cost_of_transport"], fine["cost_of_transport"]
    d_tr = abs(tr_c - tr_f)
    if math.isfinite(cot_c) and math.isfinite(cot_f):
        d_cot = abs(cot_c - cot_f) / max(abs(cot_f), 1e-12)
    else:  # no progress at one step: both must be infinite
        d_cot = 0.0 if math.isinf(cot_c) and math.isinf(cot_f) else math.inf
    ok = d_tr <= TR_TARGET_PP and d_cot <= COT_TARGET
    return (f"| {label} | {name} | {tr_c:.1f} | {tr_f:.1f} | {d_tr:.2f} | {cot_c:.3f} | {cot_f:.3f} | "
            f"{100 * d_cot:.1f} | {'yes' if ok else 'NO'} |"), ok


def _mean_metrics(runs):
    """Means over episodes; the cost of transport as total energy over total progress (a mean of
    ratios would weigh a stalled episode's near-infinite CoT)."""
    tr = [r["travel_reduction"] for r in runs]
    n = len(tr)
    mean = sum(tr) / n
    se = math.sqrt(sum((x - mean) ** 2 for x in tr) / (n - 1) / n) if n > 1 else 0.0
    prog = sum(r["progress"] for r in runs)
    # m g from any episode that moved (CoT = E / (m g d) as the env defines it, Table 6)
    weight = next((r["energy"] / (r["progress"] * r["cost_of_transport"]) for r in runs
                   if r["progress"] > 1e-9 and r["energy"] > 0 and math.isfinite(r["cost_of_transport"])), None)
    cot = sum(r["energy"] for r in runs) / (weight * prog) if weight and prog > 1e-9 else math.inf
    return {"travel_reduction": mean, "cost_of_transport": cot, "tr_se": 100 * se}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--policy", default="policies/ernest_default.pt",
                    help="exported policy ('' for none; default: the committed one)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--ensemble", type=int, default=0,
                    help="compare means over seeds 0..N-1 per row instead of single episodes")
    args = ap.parse_args(argv)
    dt = _dyn.SimOptions().dt
    policy = args.policy if args.policy and os.path.exists(args.policy) else None
    ctrls = evaluate.controllers(policy)
    print(f"physics step {dt} s vs {dt / 4} s; controllers: {', '.join(ctrls)}; seeds {args.seeds}",
          flush=True)
    lines = ["| course | controller | TR [%] dt | TR [%] dt/4 | |dTR| [pp] | CoT dt | CoT dt/4 | "
             "|dCoT| [%] | within |", "|---|---|---|---|---|---|---|---|---|"]
    all_ok = True
    t_start = time.perf_counter()
    for label, env_id, kwargs in evaluate.COURSES:
        for name, (pol, passive) in ctrls.items():
            if args.ensemble:
                t0 = time.perf_counter()
                m = [_mean_metrics([evaluate.run_episode(env_id, dict(kwargs, physics_dt=h), pol, passive,
                                                         seed)[0] for seed in range(args.ensemble)])
                     for h in (dt, dt / 4)]
                line, ok = _row(f"{label} (mean of {args.ensemble})", name, *m)
                line += f" ±{m[0]['tr_se']:.1f} / ±{m[1]['tr_se']:.1f} pp (SE of TR) |"
                all_ok &= ok
                lines.append(line)
                print(f"{line}  ({time.perf_counter() - t0:.1f} s)", flush=True)
                continue
            for seed in args.seeds:
                t0 = time.perf_counter()
                m = [evaluate.run_episode(env_id, dict(kwargs, physics_dt=h), pol, passive, seed)[0]
                     for h in (dt, dt / 4)]
                line, ok = _row(label if len(args.seeds) == 1 else f"{label} (seed {seed})", name, *m)
                all_ok &= ok
                lines.append(line)
                print(f"{line}  ({time.perf_counter() - t0:.1f} s)", flush=True)
    print("\n" + "\n".join(lines))
    print(f"\n{'all rows within' if all_ok else 'SOME ROWS MISS'} the targets (|dTR| <= "
          f"{TR_TARGET_PP} pp, |dCoT| <= {100 * COT_TARGET:.0f} %); {time.perf_counter() - t_start:.0f} s")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
