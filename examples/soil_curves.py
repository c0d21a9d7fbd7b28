"""Bekker–Wong soil curves for ERNEST's wheel (seed 004 §3.3, eqs 12–32).

Shows: one contact evaluation (``soil.BekkerWongModel.evaluate`` on a ``ContactState``) and the
single-wheel rig (``soil.drawbar_curve``): drawbar pull, driving torque and equilibrium sinkage
against slip under a quarter of the 75 kg rover, on the three soil presets (Table 2's dry sand
and M90, and our wet sand).

    python examples/soil_curves.py --out out/examples [--points 37]

Writes OUT/soil_curves.png. Takes under a second (`ernest soil-curves` is the full version).
"""

from __future__ import annotations

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ernest_cpp import soil  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--points", type=int, default=37, help="slip samples in [-0.9, 0.9]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    # One wheel state: 15 mm deep, centre moving at 0.15 m/s, the contact point slipping back
    # at 0.05 m/s: the rim turns at 0.2 m/s.
    model = soil.BekkerWongModel(soil.soil_preset("m90"), soil.ernest_wheel())
    f = model.evaluate(soil.ContactState(sinkage=0.015, vx=0.15, vy=0.0, vcx=-0.05, vcy=0.0))
    print(f"M90, 15 mm sinkage: Fx {f.fx:.1f} N, Fz {f.fz:.1f} N, axle torque "
          f"{f.axle_torque:.2f} N m, slip {f.slip:.3f}")

    load = 75.0 * soil.EARTH_GRAVITY / 4  # N on each wheel
    slips = np.linspace(-0.9, 0.9, args.points)
    fig, ax = plt.subplots(1, 3, figsize=(12, 3.8))
    for name in ("dry_sand", "m90", "wet_sand"):
        c = soil.drawbar_curve(name, load, slips)
        ax[0].plot(slips, c["drawbar_pull"] / load, label=name)
        ax[1].plot(slips, c["torque"], label=name)
        ax[2].plot(slips, 1e3 * c["sinkage"], label=name)
        print(f"{name:9s}: DP/W at s = 0.2: {np.interp(0.2, slips, c['drawbar_pull']) / load:+.3f}")
    for a, label in zip(ax, ("drawbar pull / load [-]", "driving torque [N m]", "sinkage [mm]")):
        a.set(xlabel="slip [-]", ylabel=label)
        a.grid(alpha=0.3)
    ax[0].legend()
    fig.suptitle(f"ERNEST wheel (r 0.17 m, b 0.13 m) under {load:.0f} N, Earth gravity")
    fig.tight_layout()
    path = os.path.join(args.out, "soil_curves.png")
    fig.savefig(path, dpi=90)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
