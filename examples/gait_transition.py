"""Plan a gait transition of the Asterix rover (seed 000): squirming to wheel-walking.

Shows: the transition problem (``opt.asterix_problem``), planning it with each strategy (Naive,
Bezier, Linear, Spline; NLopt SLSQP under a time budget, ``opt.plan``), the metrics of eqs 24–28
(``opt.evaluate_metrics``) and the executed joint trajectory (first gait, transition, second
gait: ``TransitionResult.sample_executed``).

    python examples/gait_transition.py --out out/examples [--t1 1.6] [--max-time 0.5]

Writes OUT/gait_transition.png and prints one line per strategy. Takes about 2 s
(`ernest transitions` runs the paper's whole protocol).
"""

from __future__ import annotations

import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ernest_cpp import opt  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--t1", type=float, default=1.6, help="switching time in the first gait [s]")
    ap.add_argument("--max-time", type=float, default=0.5, help="planning budget [s]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    problem = opt.asterix_problem(t1=args.t1, direction="squirming->wheel_walking")
    t = np.linspace(0.0, args.t1 + 6.0, 1200)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for strategy in ("naive", "bezier", "linear", "spline"):
        result = opt.plan(problem, strategy, "balanced", max_time=args.max_time)
        m = opt.evaluate_metrics(problem, result)
        print(f"{strategy:7s}: T = {m.duration:.2f} s, heading change {np.degrees(m.heading_change):+6.2f}"
              f" deg, position deviation {m.position_deviation:.3f} m, energy {m.energy:.1f} J, "
              f"planned in {1e3 * result.seconds:.0f} ms"
              + (f" (fell back: {result.fallback_reason})" if result.fell_back else ""))
        q = result.sample_executed(problem, t)[0]  # (q, dq, ddq): angles [rad] per joint
        for j, name in ((opt.STEERING, "steering"), (opt.ROLL, "roll")):
            axes[j].plot(t, q[:, j], label=f"{strategy} (T = {result.duration:.2f} s)")
            axes[j].set_ylabel(f"{name} [rad]")
    for ax in axes:
        ax.axvline(args.t1, color="k", lw=0.6)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[1].set_xlabel("t [s]")
    axes[0].set_title(f"Asterix squirming -> wheel-walking at t1 = {args.t1} s (balanced weights)")
    fig.tight_layout()
    path = os.path.join(args.out, "gait_transition.png")
    fig.savefig(path, dpi=90)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
