"""The slope course as an ensemble around several angles: travel reduction on dry M90 is a steep
function of the slope angle for every gimbal gait, so one fixed angle judges a gait on one point of
a steep curve. For each centre angle this runs the learned policy and the crawling gait over
seeds 0..n-1, each seed drawing its slope within centre +- spread (``eval_slope_spread_deg``, the
draw ``ernest reproduce`` makes around 20 deg), on dry M90 and wet sand, and prints the mean and
standard deviation of the travel reduction and the largest lateral deviation.

    python benchmarks/slope_ensemble.py [--policy policies/ernest_default.pt] [--centres 19,20,21]
        [--seeds 10] [--spread 0.5] [--dt-divisor 1]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import ernest_cpp.envs  # noqa: F401  (registers the environments)
from ernest_cpp import evaluate as ev

DT = 0.0125


def ensemble(ctrl, passive: bool, soil: str, centre: float, spread: float, seeds: int,
             physics_dt: float) -> tuple[float, float, float]:
    """(mean, std of the travel reduction [%], largest lateral deviation [m]) over the seeds."""
    tr, lat = [], []
    for s in range(seeds):
        kw = {"soil": soil, "physics_dt": physics_dt,
              "randomisation": {"eval_slope_deg": centre, "eval_slope_spread_deg": spread}}
        m, hist, env, _ = ev.run_episode("ernest/SlopeEval-v0", kw, ctrl, passive, s)
        tr.append(100 * m["travel_reduction"])
        lat.append(ev.max_lateral(env, hist))
    return float(np.mean(tr)), float(np.std(tr)), float(np.max(lat))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", default="policies/ernest_default.pt")
    p.add_argument("--centres", default="19,20,21", help="comma-separated slope angles [deg]")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--spread", type=float, default=0.5, help="[deg] either side of each centre")
    p.add_argument("--dt-divisor", type=int, default=1, help="physics step = 0.0125 s / this")
    a = p.parse_args()
    try:
        centres = [float(v) for v in a.centres.split(",")]
    except ValueError:
        raise SystemExit(f"--centres {a.centres!r}: comma-separated angles in degrees")
    if a.seeds < 1 or a.dt_divisor < 1 or not all(0 <= c - a.spread and c + a.spread <= 45
                                                  for c in centres):
        raise SystemExit("--seeds and --dt-divisor must be >= 1, every centre +- spread in [0, 45]")
    ctrls = ev.controllers(a.policy)
    print(f"slopes within +-{a.spread:g} deg of {', '.join(f'{c:g}' for c in centres)} deg, "
          f"seeds 0-{a.seeds - 1}, physics step {DT / a.dt_divisor:g} s, policy {a.policy}")
    print("| soil | centre [deg] | controller | travel reduction [%] mean ± sd | max lateral [m] |")
    print("|---|---|---|---|---|")
    t0 = time.perf_counter()
    for soil in ("m90", "wet_sand"):
        for centre in centres:
            for name in (ev.LEARNED, ev.CRAWLING):
                ctrl, passive = ctrls[name]
                mean, sd, lat = ensemble(ctrl, passive, soil, centre, a.spread, a.seeds,
                                         DT / a.dt_divisor)
                print(f"| {soil} | {centre:g} | {name} | {mean:.1f} ± {sd:.1f} | {lat:.2f} |",
                      flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
