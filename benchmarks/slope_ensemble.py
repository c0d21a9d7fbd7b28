"""The 20 deg slope course as an ensemble: the course has no randomness (its seeds all run one
episode), so a chaotic gait is judged on one trajectory. This runs the learned policy and the
crawling gait on slopes spread evenly over [20 - spread, 20 + spread] deg, at the default physics
step and at a quarter of it, and prints mean and standard deviation of the travel reduction and
the largest lateral deviation.

    python benchmarks/slope_ensemble.py [--policy policies/ernest_default.pt] [--angles 11]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import ernest_cpp.envs  # noqa: F401  (registers the environments)
from ernest_cpp import evaluate as ev

DT = 0.0125


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", default="policies/ernest_default.pt")
    p.add_argument("--angles", type=int, default=11)
    p.add_argument("--spread", type=float, default=0.5, help="[deg] either side of 20")
    a = p.parse_args()
    if a.angles < 1 or not 0 <= a.spread < 20:
        raise SystemExit("--angles must be >= 1 and --spread in [0, 20)")
    ctrls = ev.controllers(a.policy)
    angles = np.linspace(20 - a.spread, 20 + a.spread, a.angles)
    print(f"{a.angles} slopes {angles[0]:g}-{angles[-1]:g} deg, policy {a.policy}")
    print("| soil | physics step [s] | controller | travel reduction [%] mean ± sd | "
          "max lateral [m] |")
    print("|---|---|---|---|---|")
    t0 = time.perf_counter()
    for soil in ("m90", "wet_sand"):
        for div in (1, 4):
            for name in (ev.LEARNED, ev.CRAWLING):
                ctrl, passive = ctrls[name]
                tr, lat = [], []
                for deg in angles:
                    kw = {"soil": soil, "randomisation": {"eval_slope_deg": float(deg)},
                          "physics_dt": DT / div}
                    m, hist, env, _ = ev.run_episode("ernest/SlopeEval-v0", kw, ctrl, passive, 0)
                    tr.append(100 * m["travel_reduction"])
                    lat.append(ev.max_lateral(env, hist))
                print(f"| {soil} | {DT / div:g} | {name} | {np.mean(tr):.1f} ± {np.std(tr):.1f} | "
                      f"{max(lat):.2f} |", flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
