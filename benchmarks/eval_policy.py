"""An exported policy against the passive bogie (and the scripted crawling gait) on every course and
training scenario of seed 004, over ten seeds, at the default physics step or a finer one: the
checks of the default policy that ``ernest reproduce`` does not make (rock field, ripples, mixed
course, path tracking on the slope, a quarter of the physics step).

    python benchmarks/eval_policy.py [--policy policies/ernest_default.pt] [--seeds 10] [--dt-divisor 4]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ernest_cpp import evaluate as ev
from ernest_cpp.reproduce import SLOPE_SPREAD_DEG, wheels_over

# each seed's slope within 20 +- 0.5 deg (ernest reproduce's ensemble): the slope gaits are chaotic
_ENSEMBLE = {"randomisation": {"eval_slope_spread_deg": SLOPE_SPREAD_DEG}}
SCENARIOS = [  # (label, env id, kwargs, obstacle kind or None)
    ("rock field", "ernest/RockField-v0", {}, None),
    ("ripples", "ernest/Ripples-v0", {}, None),
    ("mixed course", "ernest/Course-v0", {}, None),
    ("20 deg slope, dry M90", "ernest/SlopeEval-v0", {"soil": "m90", **_ENSEMBLE}, None),
    ("20 deg slope, wet sand", "ernest/SlopeEval-v0", {"soil": "wet_sand", **_ENSEMBLE}, None),
    ("wheel-high step", "ernest/WheelStep-v0", {}, "step"),
    ("Bickler trap", "ernest/BicklerTrap-v0", {}, "bickler"),
]
DT = 0.0125  # the environments' default physics step [s]


def row(env_id, kwargs, kind, ctrl, passive, seeds, first_seed=0) -> dict:
    """Means over seeds first_seed..first_seed+seeds-1 of ``ctrl(obs, env)``: progress [m], travel reduction ``tr``
    [%], cost of transport (inf if any episode made no progress), the largest lateral deviation
    ``lat`` [m] over all seeds, and (with an obstacle ``kind``) the seeds with all four wheels
    over."""
    prog, tr, cot, lat, crossed = [], [], [], [], 0
    for s in range(first_seed, first_seed + seeds):
        m, hist, env, info = ev.run_episode(env_id, kwargs, ctrl, passive, s)
        prog.append(float(info["path_progress"]))
        tr.append(float(m["travel_reduction"]))
        cot.append(float(m["cost_of_transport"]))
        lat.append(ev.max_lateral(env, hist))
        if kind:
            crossed += wheels_over(kind, env) == 4
    finite = [c for c in cot if np.isfinite(c)]
    return {"progress": np.mean(prog), "tr": 100 * np.mean(tr), "tr_std": 100 * np.std(tr),
            "lat": np.max(lat),
            "cot": np.mean(finite) if len(finite) == len(cot) else float("inf"),
            "crossed": crossed if kind else None}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", default="policies/ernest_default.pt")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--dt-divisor", type=int, default=1, help="physics step = 0.0125 s / this")
    p.add_argument("--only", help="comma-separated labels' first words (e.g. rock,ripples)")
    a = p.parse_args()
    ctrls = ev.controllers(a.policy)
    extra = {"physics_dt": DT / a.dt_divisor} if a.dt_divisor > 1 else {}
    print(f"physics step {DT / a.dt_divisor:g} s, seeds 0-{a.seeds - 1}, policy {a.policy}")
    print("| course | controller | progress [m] | travel reduction [%] (± std over seeds) | CoT | "
          "max lateral [m] | "
          "crossed |")
    print("|---|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    for label, env_id, kwargs, kind in SCENARIOS:
        if a.only and not any(label.startswith(w) for w in a.only.split(",")):
            continue
        for name, (ctrl, passive) in ctrls.items():
            r = row(env_id, {**kwargs, **extra}, kind, ctrl, passive, a.seeds)
            crossed = f"{r['crossed']}/{a.seeds}" if kind else "—"
            print(f"| {label} | {name} | {r['progress']:.2f} | {r['tr']:.1f} ± {r['tr_std']:.1f} | "
                  f"{r['cot']:.3f} | "
                  f"{r['lat']:.2f} | {crossed} |", flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
