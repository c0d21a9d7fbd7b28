"""One FootFall step of the ATHLETE walker (seed 003): map, plan and smooth a leg's move.

Shows: the SDM-B walker model (``walker.WalkerModel``), a rock field around its feet
(``footfall.rock_field``), the stability map of leg 0 (``footfall.stability_map``: where the
foot can go and keep the walker statically stable, §3.3) and one planned step
(``footfall.plan_step``: OMPL SBL in joint space against the predicted sag, then smoothed).

    python examples/footfall_step.py --out out/examples [--leg 0] [--dx 0.35]

Writes OUT/footfall_map.png and OUT/footfall_step.png, prints the plan. Takes a second or two
(`ernest footfall` plans and executes a whole gait cycle in ODE).
"""

from __future__ import annotations

import argparse
import os

from ernest_cpp import footfall as F
from ernest_cpp import walker as W


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--leg", type=int, default=0, help="leg to move (0-5)")
    ap.add_argument("--dx", type=float, default=0.35, help="step length forward [m]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    model = W.WalkerModel(W.sdm_b_parameters())
    body, q = model.standard_body_pose(), model.standard_configuration
    feet = model.contact_points(body, q)  # (3, legs) wheel contacts, world frame [m]
    terrain = F.rock_field(F.RockFieldOptions(), feet[:2])
    goal = (feet[0, args.leg] + args.dx, feet[1, args.leg])

    m = F.stability_map(model, terrain, body, q, args.leg)
    stable = int((m["status"] == 2).sum())
    print(f"stability map of leg {args.leg}: {stable} stable cells of {m['status'].size}")
    map_png = os.path.join(args.out, "footfall_map.png")
    F.plot_stability_map(m, map_png, terrain=terrain, feet=feet, goal=goal)

    step = F.plan_step(model, terrain, body, q, args.leg, *goal)
    why = f" ({step.reason})" if step.reason else ""
    print(f"step: {step.status.name}{why}; joint path {step.plan.length:.2f} rad from SBL, "
          f"{step.smoothing.length:.2f} rad smoothed; goal margin {step.goal_margin:.3f} m")
    step_png = os.path.join(args.out, "footfall_step.png")
    if step.solved:
        F.plot_leg_path(model, terrain, step, args.leg, step_png,
                        title=f"leg {args.leg}: {args.dx} m forward")
    print(f"wrote {map_png}" + (f", {step_png}" if step.solved else ""))


if __name__ == "__main__":
    main()
