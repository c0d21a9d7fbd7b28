"""Step independence of the evaluation results: every evaluation course of
``ernest evaluate`` (seed 004 §5, Table 6) with every controller (passive bogie, crawling gait,
the committed learned policy), run at the default physics step and at a quarter of it. Prints
travel reduction and cost of transport at both steps, their differences, and whether they are
within the targets (2 percentage points of travel reduction, 5 % of cost of transport).

    ./run bench step_independence                # default policy, seed 0
    ./run bench step_independence --seeds 0 1 2  # more episodes (the same seeds at both steps)
    ./run bench step_independence --ensemble 24  # every row: means over 24 perturbed episodes
    ./run bench step_independence --policy '' --course Bickler --course Mixed  # the obstacle rows

The evaluation courses are noise-free: one episode per step is one deterministic trajectory. The
passive bogie and the crawling gait are open loop (they never read the force sensors) and are
compared episode against episode. A learned policy closes the loop through the force sensors, and
its gait is chaotic: a force-sensor perturbation of 1 mN (3e-6 of a wheel load, far below any
sensor's resolution) moves one 60 s episode's travel reduction on the dry slope by 1.3 pp (SD,
range 5 pp) at a fixed step. A single episode is then a sample, not a quantity that two steps can be asked to reproduce to
2 pp, whatever the integrator. For the policy's rows the script therefore also runs an ensemble of
`--learned-ensemble` episodes (default 16) whose force-sensor readings carry that perturbation
(`--perturb`, N; torques a tenth of it in N m), the same seeds at both steps, and prints the
means (on the courses with boxes or rocks the seed also draws their friction, 0.5-0.9 as in seed
004 Table 3, so there the spread is the friction's as well as the perturbation's), their standard errors and the spread at the default step. Such a row is within the targets
when its single noise-free episodes are, or when the ensemble means are ("ens" in the last
column). Where the outcome is bimodal (the policy crosses the Bickler trap or stalls, decided by
the perturbation), 16 episodes cannot resolve 2 pp; the row then says "n.s." when the means'
difference is below twice its standard error (not significant, not resolved either) — it is not
counted as within, and it does not fail the exit status.

Exit status 1 if any row misses a target. A cost of transport is compared only where the rover
made progress at both steps (it is infinite otherwise); an ensemble's cost of transport is its
total energy over its total progress.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
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


def _episodes(env_id, kwargs, pol, passive, seeds, h, perturb):
    kw = dict(kwargs, physics_dt=h)
    if perturb:
        kw.update(fts_noise_force=perturb, fts_noise_torque=perturb / 10)
    return [evaluate.run_episode(env_id, kw, pol, passive, seed)[0] for seed in seeds]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--policy", default="policies/ernest_default.pt",
                    help="exported policy ('' for none; default: the committed one)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--ensemble", type=int, default=0,
                    help="every row: compare means over N perturbed episodes (seeds 0..N-1)")
    ap.add_argument("--learned-ensemble", type=int, default=16,
                    help="the learned policy's rows: means over N perturbed episodes (0: single episodes)")
    ap.add_argument("--controller", action="append",
                    help="only this controller's rows (repeatable), e.g. --controller 'learned policy'")
    ap.add_argument("--course", action="append",
                    help="only the courses whose label contains this (repeatable), e.g. --course Bickler")
    ap.add_argument("--obstacle-substeps", type=int, default=0,
                    help="SimOptions.obstacle_substeps for every episode (0: the simulator's default)")
    ap.add_argument("--perturb", type=float, default=1e-3,
                    help="force-sensor perturbation of the ensembles' episodes [N] (standard deviation)")
    args = ap.parse_args(argv)
    if args.ensemble < 0 or args.learned_ensemble < 0 or args.ensemble == 1 or args.learned_ensemble == 1:
        ap.error("--ensemble and --learned-ensemble must be 0 or at least 2")
    if args.obstacle_substeps < 0:
        ap.error("--obstacle-substeps must be >= 0")
    if not (args.perturb >= 0 and math.isfinite(args.perturb)):
        ap.error("--perturb must be a finite force >= 0 N")
    dt = _dyn.SimOptions().dt
    policy = args.policy if args.policy and os.path.exists(args.policy) else None
    ctrls = evaluate.controllers(policy)
    print(f"physics step {dt} s vs {dt / 4} s; controllers: {', '.join(ctrls)}; seeds {args.seeds}",
          flush=True)
    lines = ["| course | controller | TR [%] dt | TR [%] dt/4 | |dTR| [pp] | CoT dt | CoT dt/4 | "
             "|dCoT| [%] | within |", "|---|---|---|---|---|---|---|---|---|"]
    notes = []
    all_ok, n_unresolved = True, 0
    t_start = time.perf_counter()
    for label, env_id, kwargs in evaluate.COURSES:
        if args.obstacle_substeps:
            kwargs = dict(kwargs, obstacle_substeps=args.obstacle_substeps)
        if args.course and not any(c in label for c in args.course):
            continue
        for name, (pol, passive) in ctrls.items():
            if args.controller and name not in args.controller:
                continue
            n = args.ensemble or (args.learned_ensemble if name == evaluate.LEARNED else 0)
            if n:
                t0 = time.perf_counter()
                single = [_episodes(env_id, kwargs, pol, passive, [0], h, 0.0)[0] for h in (dt, dt / 4)]
                runs = [_episodes(env_id, kwargs, pol, passive, range(n), h, args.perturb) for h in (dt, dt / 4)]
                m = [_mean_metrics(r) for r in runs]
                _, single_ok = _row(label, name, *single)
                line, ens_ok = _row(f"{label} (mean of {n})", name, *m)
                d_tr = abs(m[0]["travel_reduction"] - m[1]["travel_reduction"]) * 100
                se = math.hypot(m[0]["tr_se"], m[1]["tr_se"])
                if single_ok or ens_ok:
                    verdict = "yes (single)" if single_ok else "yes (ens)"
                elif d_tr < 2 * se:
                    verdict, n_unresolved = "n.s.", n_unresolved + 1
                else:
                    verdict, all_ok = "NO", False
                line = line.rsplit("|", 2)[0] + f"| {verdict} |"
                line += f" ±{m[0]['tr_se']:.1f} / ±{m[1]['tr_se']:.1f} pp (SE of TR) |"
                lines.append(line)
                tr = [100 * r["travel_reduction"] for r in runs[0]]
                notes.append(f"- {label}, {name}: one noise-free episode {100 * single[0]['travel_reduction']:.1f} % "
                             f"(CoT {single[0]['cost_of_transport']:.3f}) at dt, "
                             f"{100 * single[1]['travel_reduction']:.1f} % ({single[1]['cost_of_transport']:.3f}) "
                             f"at dt/4; the {n} perturbed episodes at dt span {min(tr):.1f}..{max(tr):.1f} % "
                             f"(SD {statistics.stdev(tr):.2f} pp; seeds 0..{n - 1}, {1e3 * args.perturb:g} mN perturbation)")
                print(f"{line}  ({time.perf_counter() - t0:.1f} s)\n{notes[-1]}", flush=True)
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
    if notes:
        print("\n" + "\n".join(notes))
    unresolved = f", {n_unresolved} not resolved by the ensemble (n.s.)" if n_unresolved else ""
    print(f"\n{'all rows within' if all_ok else 'SOME ROWS MISS'} the targets (|dTR| <= "
          f"{TR_TARGET_PP} pp, |dCoT| <= {100 * COT_TARGET:.0f} %){unresolved}; "
          f"{time.perf_counter() - t_start:.0f} s")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
