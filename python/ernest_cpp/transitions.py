"""``ernest transitions``: the gait-transition experiment of seed 000 §5 in simulation.

Asterix switches from squirming to wheel-walking at 5 uniform points over the squirming period
and back at 5 points over the wheel-walking period, for Bezier, Linear and Spline with each of
Table 1's three weight sets, plus Naive (10 configurations x 10 transitions). Writes a CSV of every
transition, a markdown table of the per-configuration means, bar charts like Figs 8–11 (duration,
heading change, max steering/roll acceleration, cost of transport) and example transitions like
Figs 2–4 (joint angle vs time with g1, g2 and the transition), and findings.md: each qualitative
statement of seed 000 §6 with the paper's and our ranking and whether it holds (findings.py).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import time

import numpy as np

from . import opt as O
from ._csv import header
from .findings import findings_markdown, paper_findings  # noqa: F401  (paper_findings: public)

COLORS = {"bezier": "tab:blue", "spline": "tab:orange", "linear": "tab:green", "naive": "tab:red"}
CSV_COLUMNS = ("configuration", "strategy", "weights", "direction", "used", "t1", "duration_s",
               "phase_shift_s", "heading_change_deg", "heading_deviation_deg",
               "position_deviation_m", "distance_m", "max_acc_steering", "max_acc_roll",
               "energy_J", "energy_wheels_J", "energy_articulation_J", "cost_of_transport",
               "res_start_pos", "res_start_vel", "res_end_pos", "res_end_vel", "cost",
               "max_violation", "solver_status", "evaluations", "solve_ms", "fell_back",
               "fallback_reason")
#: Each column's unit, named in the CSV header (``t1 [s]``); joint residuals are the largest over
#: the steering and roll joints (eqs 2–5); cost (eq 8) and max_violation (eqs 16–17, normalised
#: by the joint limits) are pure numbers.
CSV_UNITS = {
    "configuration": "-", "strategy": "-", "weights": "-", "direction": "-", "used": "-",
    "t1": "s", "duration_s": "s", "phase_shift_s": "s", "heading_change_deg": "deg",
    "heading_deviation_deg": "deg", "position_deviation_m": "m", "distance_m": "m",
    "max_acc_steering": "rad/s^2", "max_acc_roll": "rad/s^2", "energy_J": "J",
    "energy_wheels_J": "J", "energy_articulation_J": "J", "cost_of_transport": "-",
    "res_start_pos": "rad", "res_start_vel": "rad/s", "res_end_pos": "rad", "res_end_vel": "rad/s",
    "cost": "-", "max_violation": "-", "solver_status": "-", "evaluations": "-", "solve_ms": "ms",
    "fell_back": "-", "fallback_reason": "-",
}


def _atomic_path(path: str) -> str:
    root, ext = os.path.splitext(path)
    return f"{root}.tmp{os.getpid()}{ext}"


def write_csv(rows: list[dict], path: str) -> None:
    tmp = _atomic_path(path)
    with open(tmp, "w", newline="") as fh:
        csv.writer(fh).writerow(header(CSV_COLUMNS, CSV_UNITS))
        w = csv.DictWriter(fh, fieldnames=CSV_COLUMNS, extrasaction="ignore")
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    os.replace(tmp, path)


def markdown_table(summary: list[dict]) -> str:
    lines = ["| configuration | n | duration [s] | \\|heading change\\| [deg] | "
             "\\|heading dev. vs eq 7\\| [deg] | max acc. steering [rad/s²] | max acc. roll [rad/s²] | "
             "CoT [-] | median solve [ms] | fallbacks |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        lines.append(
            f"| {s['configuration']} | {s['n']} | {s['duration_s']:.3f} | "
            f"{s['heading_change_deg']:.2f} | {s['heading_deviation_deg']:.2f} | "
            f"{s['max_acc_steering']:.2f} | {s['max_acc_roll']:.2f} | "
            f"{s['cost_of_transport']:.3f} | {s['solve_ms_median']:.1f} | {s['fallbacks']} |")
    return "\n".join(lines)


def _save(fig, path: str) -> str:
    tmp = _atomic_path(path)
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)
    return path


def bar_charts(summary: list[dict], out_dir: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [s["configuration"] for s in summary]
    colors = [COLORS[s["strategy"]] for s in summary]
    x = np.arange(len(summary))
    specs = [("duration_s", "Transition duration [s]", "fig8_duration.png", "Fig. 8"),
             # Fig. 9 is the "heading deviation caused by transition": the heading reached minus
             # eq 7's (what g2 would have reached over the same window); see findings.py.
             ("heading_deviation_deg", "|Heading deviation vs eq 7| [deg]", "fig9_heading.png",
              "Fig. 9"),
             ("cost_of_transport", "Cost of transport [-]", "fig11_cost_of_transport.png",
              "Fig. 11")]
    paths = []
    for key, ylabel, fname, ref in specs:
        fig, ax = plt.subplots(figsize=(9, 4.2))
        ax.bar(x, [s[key] for s in summary], yerr=[s[key + "_std"] for s in summary],
               color=colors, capsize=3)
        ax.set_xticks(x, labels, rotation=35, ha="right", fontsize=8)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{ylabel.split(' [')[0]} per configuration (like seed 000 {ref})")
        ax.grid(axis="y", alpha=0.3)
        fig.tight_layout()
        paths.append(_save(fig, os.path.join(out_dir, fname)))
        plt.close(fig)
    # Fig. 10: steering (dark) and roll (light) maximum accelerations side by side.
    fig, ax = plt.subplots(figsize=(9, 4.2))
    w = 0.4
    ax.bar(x - w / 2, [s["max_acc_steering"] for s in summary], w, color=colors,
           yerr=[s["max_acc_steering_std"] for s in summary], capsize=2, label="steering")
    ax.bar(x + w / 2, [s["max_acc_roll"] for s in summary], w, color=colors, alpha=0.45,
           yerr=[s["max_acc_roll_std"] for s in summary], capsize=2, label="roll (light)")
    ax.set_xticks(x, labels, rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("Max joint acceleration [rad/s²]")
    ax.set_yscale("log")
    ax.set_title("Max steering (dark) / roll (light) acceleration (like seed 000 Fig. 10)")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    paths.append(_save(fig, os.path.join(out_dir, "fig10_max_acceleration.png")))
    plt.close(fig)
    return paths


def sinusoid_problem(t1: float) -> O.TransitionProblem:
    """The one-dimensional example of Figs 2–4: g1 = sin(t), g2 = 0.5 sin(2t) + 0.2."""
    rover = O.AsterixParameters()
    rover.steering_limit = 1.3
    g1 = O.Gait("sin(t)", 2 * math.pi, [0.0], [1.0], [0.0])
    g2 = O.Gait("0.5 sin(2t) + 0.2", math.pi, [0.2], [0.5], [0.0])
    return O.TransitionProblem(rover, g1, g2, t1, [1.3], [1.5], [2.0])


def example_plots(out_dir: str, max_time: float) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    # Figs 2–4: Naive at t1 = 2, Bezier at 3 pi / 2, Linear at pi / 4; Spline added at pi / 4.
    cases = [("naive", 2.0, "fig2_naive.png", "Fig. 2"),
             ("bezier", 1.5 * math.pi, "fig3_bezier.png", "Fig. 3"),
             ("linear", 0.25 * math.pi, "fig4_linear.png", "Fig. 4"),
             ("spline", 0.25 * math.pi, "fig4b_spline.png", "Fig. 4 (Spline)")]
    for strategy, t1, fname, ref in cases:
        pb = sinusoid_problem(t1)
        r = O.plan(pb, strategy, None, max_time)
        t = np.linspace(0.0, t1 + r.duration + 4.0, 800)
        g1 = pb.from_gait.sample(t)[0][:, 0]
        g2 = pb.to_gait.sample(t - r.phase_shift)[0][:, 0]
        tau = np.linspace(0.0, r.duration, 200)
        q = r.sample(tau)[0][:, 0]
        fig, ax = plt.subplots(figsize=(7, 3.6))
        ax.plot(t, g1, color="0.6", lw=1, label="g1(t) = sin(t)")
        ax.plot(t, g2, color="0.6", lw=1, ls="--", label="g2(t − φ)")
        ax.plot(t1 + tau, q, color=COLORS[strategy], lw=2.5, label=f"{strategy} transition")
        if strategy != "naive" and r.waypoints.size and r.waypoints.shape[1] > 2:
            ax.plot(t1 + np.linspace(0, r.duration, r.waypoints.shape[1]), r.waypoints[0], ".",
                    color=COLORS[strategy], ms=3)
        ax.axvline(t1, color="k", lw=0.6)
        ax.axvline(t1 + r.duration, color="k", lw=0.6, ls=":")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("joint angle [rad]")
        ax.set_title(f"{strategy.capitalize()} transition, t1 = {t1:.3g} s, T = {r.duration:.2f} s "
                     f"(like seed 000 {ref})", fontsize=9)
        ax.legend(fontsize=7, loc="lower left")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        paths.append(_save(fig, os.path.join(out_dir, fname)))
        plt.close(fig)
    # Asterix: squirming -> wheel-walking at t1 = 0.2 P, every strategy (balanced weights).
    pb = O.asterix_problem(1.6)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for strategy in ("naive", "bezier", "linear", "spline"):
        r = O.plan(pb, strategy, "balanced", max_time)
        t = np.linspace(0.0, pb.t1 + 6.0, 1200)
        q = r.sample_executed(pb, t)[0]
        for j, name in ((O.STEERING, "steering"), (O.ROLL, "roll")):
            axes[j].plot(t, q[:, j], color=COLORS[strategy], lw=1.4,
                         label=f"{strategy} (T = {r.duration:.2f} s)")
            axes[j].set_ylabel(f"{name} [rad]")
    for ax in axes:
        ax.axvline(pb.t1, color="k", lw=0.6)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("t [s]")
    axes[0].set_title("Asterix squirming → wheel-walking at t1 = 1.6 s (balanced weights)")
    fig.tight_layout()
    paths.append(_save(fig, os.path.join(out_dir, "asterix_example.png")))
    plt.close(fig)
    return paths


def run(args: argparse.Namespace) -> int:
    if not 0.001 <= args.max_time <= 60:
        raise ValueError(f"--max-time = {args.max_time} must be in [0.001, 60] s")
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    print(f"ernest transitions: {len(O.CONFIGURATIONS)} configurations x 2 directions x "
          f"{args.points} switch points, SLSQP budget {args.max_time} s", flush=True)
    rows = O.run_protocol(args.points, args.max_time,
                          log=lambda s: print(s, flush=True))
    summary = O.summarise(rows)
    csv_path = os.path.join(args.out, "transitions.csv")
    write_csv(rows, csv_path)
    table = markdown_table(summary)
    md_path = os.path.join(args.out, "summary.md")
    tmp = _atomic_path(md_path)
    with open(tmp, "w") as fh:
        fh.write("# Gait transitions (seed 000 protocol, simulated Asterix)\n\n" + table + "\n")
    os.replace(tmp, md_path)
    findings_path = os.path.join(args.out, "findings.md")
    findings = findings_markdown(paper_findings(summary))
    tmp = _atomic_path(findings_path)
    with open(tmp, "w") as fh:
        fh.write("# Seed 000 Figs 8–11: the paper's findings against ours\n\n" + findings + "\n")
    os.replace(tmp, findings_path)
    print("plots ...", flush=True)
    pngs = bar_charts(summary, args.out)
    if not args.no_examples:
        pngs += example_plots(args.out, args.max_time)
    print(table)
    print(findings)
    print(f"wrote {csv_path}, {md_path}, {findings_path}, {len(pngs)} plots in {time.perf_counter() - t0:.1f} s")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("transitions", help="gait-transition experiment of seed 000 (Figs 2–4, 8–11)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="out/transitions", help="output folder (default: out/transitions)")
    p.add_argument("--points", type=int, default=5,
                   help="uniform switch points per direction over the gait period (paper: 5)")
    p.add_argument("--max-time", type=float, default=0.5, help="SLSQP budget per transition [s]")
    p.add_argument("--no-examples", action="store_true", help="skip the Figs 2–4 example plots")
    p.set_defaults(func=run)


def main(**options) -> int:
    """``ernest transitions`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest transitions --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/transitions", points=5)``. Returns the exit status; errors raise."""
    from .cli import run

    return run("transitions", **options)
