"""Drive the ERNEST rover across a rock field on soft soil and plot what it did.

Shows: building a simulator (``dynamics.make_sim``), commanding a forward speed through the
wheel synchroniser of seed 004 §2.3 (``dynamics.sync_commands``), stepping it and reading
``sim.state`` (position, gimbal angles, wheel loads, slip).

    python examples/drive_rover.py --out out/examples [--seconds 20] [--seed 7]

Writes OUT/drive_rover.png (path over the rocks, wheel loads, gimbal angles) and prints a
summary. Takes about a second.
"""

from __future__ import annotations

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ernest_cpp import dynamics as D  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--seconds", type=float, default=20.0, help="simulated time [s]")
    ap.add_argument("--speed", type=float, default=0.15, help="forward speed command [m/s]")
    ap.add_argument("--seed", type=int, default=7, help="rock field seed")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    rocks = D.rock_field(20, seed=args.seed)
    sim = D.make_sim("soil", soil="m90", obstacles=rocks)  # the environments' soil (docs/soil.md)
    sim.reset(0.0, 0.0, 0.0, speed=args.speed)
    control_dt = 0.1  # re-run the synchroniser every 0.1 s, as the onboard loop does
    steps = max(1, round(control_dt / sim.options.dt))
    log = []
    for _ in range(int(args.seconds / control_dt)):
        sim.set_commands(D.sync_commands(sim, vx=args.speed))
        sim.step_n(steps)
        s = sim.state
        log.append([s.time, *s.position, *s.wheel_load, s.gimbal_yaw, s.gimbal_roll])
    a = np.array(log)
    t, x, y = a[:, 0], a[:, 1], a[:, 2]

    fig, ax = plt.subplots(3, 1, figsize=(7, 8))
    for r in rocks:
        c, s = r.centre, r.size
        ax[0].add_patch(plt.Rectangle((c[0] - s[0] / 2, c[1] - s[1] / 2), s[0], s[1],
                                      angle=np.degrees(r.yaw), rotation_point="center", color="0.7"))
    ax[0].plot(x, y, "C0", lw=2, label="chassis path")
    ax[0].set(xlabel="x [m]", ylabel="y [m]", title="ERNEST on M90 soil through rocks")
    ax[0].set_aspect("equal")
    for k, name in enumerate(D.WHEELS):
        ax[1].plot(t, a[:, 4 + k], label=name)
    ax[1].set(xlabel="t [s]", ylabel="wheel load [N]")
    ax[1].legend(ncol=4, fontsize=8)
    ax[2].plot(t, np.degrees(a[:, 8]), label="gimbal yaw")
    ax[2].plot(t, np.degrees(a[:, 9]), label="gimbal roll")
    ax[2].set(xlabel="t [s]", ylabel="angle [deg]")
    ax[2].legend(fontsize=8)
    fig.tight_layout()
    path = os.path.join(args.out, "drive_rover.png")
    fig.savefig(path, dpi=90)
    print(f"drove {np.hypot(x[-1], y[-1]):.2f} m in {t[-1]:.1f} s "
          f"(commanded {args.speed * t[-1]:.2f} m); wrote {path}")


if __name__ == "__main__":
    main()
