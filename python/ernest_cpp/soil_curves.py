"""``ernest soil-curves``: drawbar pull, torque and sinkage vs slip of ERNEST's wheel on the paper's
soils (seed 004 Table 2 and our wet-sand preset), under a quarter of the rover's weight at Earth and
Mars gravity. Writes PNG plots and a CSV and prints a summary table.
"""

from __future__ import annotations

import argparse
import csv
import os
import time

import numpy as np

from . import soil as S

ROVER_MASS = 75.0  # kg, seed 004 Table 1 / §2
SOILS = ("dry_sand", "m90", "wet_sand")
GRAVITIES = {"Earth": S.EARTH_GRAVITY, "Mars": S.MARS_GRAVITY}


def compute(slips: np.ndarray, carriage_speed: float, log=print) -> list[dict]:
    rows = []
    wheel = S.ernest_wheel()
    for soil_name in SOILS:
        for planet, g in GRAVITIES.items():
            load = ROVER_MASS * g / 4.0
            t0 = time.perf_counter()
            curve = S.drawbar_curve(S.soil_preset(soil_name, g), load, slips, wheel, carriage_speed)
            log(f"  {soil_name:9s} {planet:5s} load {load:6.1f} N: {len(slips)} slips in "
                f"{1e3 * (time.perf_counter() - t0):.1f} ms")
            rows.append({"soil": soil_name, "planet": planet, "load": load, **curve})
    return rows


def write_csv(rows: list[dict], path: str) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["soil [-]", "planet [-]", "load [N]", "slip [-]", "model_slip [-]",
                    "sinkage [m]", "drawbar_pull [N]", "normal_force [N]", "torque [N m]",
                    "converged [-]"])
        for r in rows:
            for i in range(len(r["slip"])):
                w.writerow([r["soil"], r["planet"], f"{r['load']:.3f}", f"{r['slip'][i]:.4f}",
                            f"{r['model_slip'][i]:.5f}", f"{r['sinkage'][i]:.6f}",
                            f"{r['drawbar_pull'][i]:.4f}", f"{r['normal_force'][i]:.4f}",
                            f"{r['torque'][i]:.5f}", int(r["converged"][i])])
    os.replace(tmp, path)


def plot(rows: list[dict], out_dir: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"dry_sand": "tab:orange", "m90": "tab:red", "wet_sand": "tab:blue"}
    styles = {"Earth": "-", "Mars": "--"}
    paths = []
    specs = [("drawbar_pull", "Drawbar pull / load [-]", True, "drawbar_pull.png"),
             ("sinkage", "Equilibrium sinkage [mm]", False, "sinkage.png"),
             ("torque", "Driving torque [N m]", False, "torque.png")]
    for key, ylabel, per_load, fname in specs:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for r in rows:
            y = r[key] / r["load"] if per_load else r[key]
            if key == "sinkage":
                y = 1e3 * y
            ax.plot(r["slip"], y, styles[r["planet"]], color=colors[r["soil"]],
                    label=f"{r['soil']} ({r['planet']}, {r['load']:.0f} N)")
        ax.axhline(0, color="0.6", lw=0.8)
        ax.axvline(0, color="0.6", lw=0.8)
        ax.set_xlabel("Slip s [-] (braking < 0 < driving)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"ERNEST wheel (r 0.17 m, b 0.13 m), quarter of 75 kg: {ylabel.split(' [')[0]}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, fname)
        fig.savefig(path + ".tmp.png", dpi=110)
        os.replace(path + ".tmp.png", path)
        plt.close(fig)
        paths.append(path)
    return paths


def summary(rows: list[dict]) -> str:
    lines = ["| soil | gravity | load [N] | sinkage at s=0 [mm] | DP/W at s=0.2 | DP/W at s=0.6 | "
             "torque at s=0.2 [N m] |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        def at(key, s):
            return float(np.interp(s, r["slip"], r[key]))
        lines.append(f"| {r['soil']} | {r['planet']} | {r['load']:.1f} | {1e3 * at('sinkage', 0):.1f} | "
                     f"{at('drawbar_pull', 0.2) / r['load']:+.3f} | "
                     f"{at('drawbar_pull', 0.6) / r['load']:+.3f} | {at('torque', 0.2):.2f} |")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    if not 0 < args.points <= 1000:
        raise ValueError(f"--points = {args.points} must be in [1, 1000]")
    os.makedirs(args.out, exist_ok=True)
    slips = np.linspace(-0.9, 0.9, args.points)
    print(f"ernest soil-curves: {len(SOILS)} soils x {len(GRAVITIES)} gravities, "
          f"{args.points} slips, carriage speed {args.carriage_speed} m/s")
    rows = compute(slips, args.carriage_speed)
    csv_path = os.path.join(args.out, "soil_curves.csv")
    write_csv(rows, csv_path)
    pngs = plot(rows, args.out)
    table = summary(rows)
    with open(os.path.join(args.out, "summary.md"), "w") as fh:
        fh.write(table + "\n")
    print(table)
    print(f"wrote {csv_path}, " + ", ".join(pngs))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("soil-curves", help="drawbar pull / sinkage vs slip plots for the paper's soils",
                       description=__doc__)
    p.add_argument("--out", default="out/soil", help="output folder (default: out/soil)")
    p.add_argument("--points", type=int, default=73, help="slip samples in [-0.9, 0.9]")
    p.add_argument("--carriage-speed", type=float, default=0.2, help="rig carriage speed [m/s]")
    p.set_defaults(func=run)


def main(**options) -> int:
    """``ernest soil-curves`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest soil-curves --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/soil")``. Returns the exit status; errors raise."""
    from .cli import run

    return run("soil-curves", **options)
