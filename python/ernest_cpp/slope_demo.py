"""``ernest slope-demo``: ERNEST climbing a 20° M90 slope in simulation (seed 004 §5.5, Table 6),
with the passive bogie (AGS off, clutch open) and with the scripted crawling gait
(``envs.baselines.CrawlingGaitController``, the same gait ``ernest evaluate`` compares: the roll
joint shifts the load to one side while the yaw joint swings the bogie; wheel speeds from the
synchroniser of §2.3). This demo runs the gait at the physics rate on its own slope; ``ernest
evaluate`` runs it at the environments' 2 Hz. Prints travel reduction (expected no-slip travel vs
actual, as Table 6 defines it) and cost of transport (electrical energy / (m g d)), and writes plots
of the path, the gimbal angles and the wheel loads.
"""

from __future__ import annotations

import argparse
import csv
import math
import os

import numpy as np

from . import dynamics as D
from . import soil as _soil
from ._core import envs as _envs
from .envs.baselines import CrawlingGaitController

SLOPE_DEG = 20.0


def _terrain(slope_deg: float) -> D.HeightMap:
    # 20 m of slope rising along +x from x = -2 (the rover starts on it), 8 m wide.
    return D.HeightMap.slope(math.radians(slope_deg), 24.0, 8.0, 0.25, -4.0, -4.0)


CONTROLLERS = ("passive", "crawling")
MAX_VX = 5.0  # [m/s]: the rolling start's limit (RoverSim.reset speed)


def _option(name: str, lo: float, hi: float, lo_open: bool = True):
    """argparse type: a finite float in (lo, hi] (or [lo, hi]), the error naming the option."""
    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} = {text!r} is not a number") from None
        if not (math.isfinite(v) and (v > lo if lo_open else v >= lo) and v <= hi):
            raise argparse.ArgumentTypeError(
                f"{name} = {v} is outside the allowed range {'(' if lo_open else '['}{lo}, {hi}]")
        return v
    return parse


def run(controller: str, soil: str = "m90", duration: float = 60.0, vx: float = 0.2,
        slope_deg: float = SLOPE_DEG, gait: CrawlingGaitController | None = None,
        eps_slip: float | None = None) -> dict[str, np.ndarray | float | str]:
    """Simulate one controller ('passive' or 'crawling'); returns time series and the metrics.

    ``gait``: the crawling gait (default ``CrawlingGaitController(speed=vx)``); its ``rates`` are
    evaluated every ``gait.dt`` (the environments' 2 Hz) and held in between, as in ``ernest
    evaluate``; the wheel speeds follow from the synchroniser every physics step. ``eps_slip`` (eq 12's regularisation) defaults to the environments' value
    (1e4 (m/s)^-2, see ``EnvOptions.eps_slip``) so this demo and ``ernest evaluate`` agree; 100 is
    Table 2's."""
    if controller not in CONTROLLERS:
        raise ValueError(f"controller must be one of {CONTROLLERS}, got {controller!r}")
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration = {duration} must be finite and > 0")
    if not (math.isfinite(vx) and 0 < vx <= MAX_VX):
        raise ValueError(f"vx = {vx} is outside the allowed range (0, {MAX_VX}] m/s")
    if gait is None:
        gait = CrawlingGaitController(speed=vx)
    params = _soil.soil_preset(soil)
    params.eps_slip = _envs.EnvOptions().eps_slip if eps_slip is None else float(eps_slip)
    sim = D.make_sim("soil", terrain=_terrain(slope_deg), soil=params)
    # Rolling start at the commanded speed: under eq 12's slip regularisation a wheel cannot build
    # slip from rest (see benchmarks/RESULTS.md, "Model findings").
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, vx)
    dt = sim.options.dt
    n = int(round(duration / dt))
    keys = ("t", "x", "y", "z", "psi", "phi", "roll_torque", "energy")
    rec = {k: np.zeros(n) for k in keys}
    loads = np.zeros((n, 4))
    fts_z = np.zeros((n, 4))
    start = sim.state.position.copy()
    expected = 0.0
    hold = max(1, int(round(gait.dt / dt)))  # physics steps per gait command (the env's 2 Hz)
    cmd = (gait.speed, 0.0, 0.0)
    for k in range(n):
        t = k * dt
        if controller == "passive":
            c = D.sync_commands(sim, vx, 0.0, 0.0, gimbal_enabled=False, clutch_engage=False)
        else:
            # the crawling gait (envs.baselines), its command held for the gait's period as the
            # environments hold a policy's: the roll presses the wheel on the side the bogie
            # swings away from, which anchors while the other advances; the synchroniser turns
            # (Vx, psi_dot, phi_dot) into wheel speeds every step. The slope runs along +x.
            if k % hold == 0:
                st = sim.state
                cmd = gait.rates(t, hold * dt, yaw=st.gimbal_yaw, roll=st.gimbal_roll,
                                 heading=st.yaw, lateral=st.position[1])
            c = D.sync_commands(sim, *cmd, gimbal_enabled=True, clutch_engage=True)
        sim.set_commands(c)
        sim.step()
        # no-slip travel of the chassis at the commanded Vx
        expected += (vx if controller == "passive" else gait.speed) * dt
        s = sim.state
        rec["t"][k] = s.time
        rec["x"][k], rec["y"][k], rec["z"][k] = s.position
        rec["psi"][k], rec["phi"][k] = s.gimbal_yaw, s.gimbal_roll
        rec["roll_torque"][k] = s.roll_torque
        rec["energy"][k] = s.energy
        loads[k] = s.wheel_load
        fts_z[k] = s.fts[:, 2]
    end = sim.state.position
    # Travel along the slope (3-D displacement projected on the uphill direction).
    up = np.array([math.cos(math.radians(slope_deg)), 0.0, math.sin(math.radians(slope_deg))])
    actual = float(np.dot(end - start, up))
    m = sim.parameters.total_mass()
    g = sim.options.soil.gravity
    energy = float(sim.state.energy)
    out: dict[str, np.ndarray | float | str] = dict(rec)
    out.update(controller=controller, loads=loads, fts_z=fts_z, expected=expected, actual=actual,
               travel_reduction=(expected - actual) / expected,
               cost_of_transport=energy / (m * g * actual) if actual > 1e-6 else math.inf,
               energy_J=energy)
    return out


def _plot(runs: list[dict], out_dir: str, tag: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, ax = plt.subplots(figsize=(6, 4))
    for r in runs:
        ax.plot(r["x"], r["y"], label=r["controller"])
    ax.plot([runs[0]["x"][0]], [runs[0]["y"][0]], "ko", label="start")
    ax.set(xlabel="x up the slope [m]", ylabel="y [m]",
           title=f"Path on a {SLOPE_DEG:.0f}° {tag} slope")
    ax.axis("equal")
    ax.legend()
    fig.tight_layout()
    paths.append(os.path.join(out_dir, f"path_{tag}.png"))
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    fig, axes = plt.subplots(len(runs), 2, figsize=(10, 3 * len(runs)), squeeze=False)
    for row, r in zip(axes, runs):
        row[0].plot(r["t"], np.degrees(r["psi"]), label="yaw ψ")
        row[0].plot(r["t"], np.degrees(r["phi"]), label="roll φ")
        row[0].set(xlabel="t [s]", ylabel="[deg]", title=f"{r['controller']}: gimbal angles")
        row[0].legend()
        for i, name in enumerate(D.WHEELS):
            row[1].plot(r["t"], r["loads"][:, i], label=name, lw=0.8)
        row[1].set(xlabel="t [s]", ylabel="[N]", title=f"{r['controller']}: wheel normal loads")
        row[1].legend(ncol=4, fontsize=8)
    fig.suptitle(f"{SLOPE_DEG:.0f}° slope, {tag}")
    fig.tight_layout()
    paths.append(os.path.join(out_dir, f"gait_{tag}.png"))
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    return paths


def main_args(args: argparse.Namespace) -> int:
    soils = [x.strip() for x in args.soils.split(",") if x.strip()]
    if not soils:
        raise ValueError(f"--soils = {args.soils!r} names no soil (m90, dry_sand, wet_sand)")
    for soil in soils:
        if soil not in ("m90", "dry_sand", "wet_sand"):
            raise ValueError(f"unknown soil {soil!r} (m90, dry_sand, wet_sand)")
    os.makedirs(args.out, exist_ok=True)
    lines = [f"# {SLOPE_DEG:.0f}° slope, {args.duration:.0f} s at Vx = {args.vx} m/s "
             "(travel reduction and cost of transport as in seed 004 Table 6)", "",
             "| soil | controller | expected [m] | actual [m] | travel reduction [%] | energy [J] | "
             "CoT E/(m g d) | E/(m d) [J/(kg m)] |", "|---|---|---|---|---|---|---|---|"]
    all_runs = {}
    for soil in soils:
        runs = [run(c, soil, args.duration, args.vx, eps_slip=args.eps_slip)
                for c in CONTROLLERS]
        all_runs[soil] = runs
        for r in runs:
            m_d = D.RoverParameters().total_mass() * r["actual"]
            lines.append(f"| {soil} | {r['controller']} | {r['expected']:.2f} | {r['actual']:.2f} | "
                         f"{100 * r['travel_reduction']:.1f} | {r['energy_J']:.0f} | "
                         f"{r['cost_of_transport']:.3f} | "
                         f"{(r['energy_J'] / m_d if m_d > 1e-6 else math.inf):.2f} |")
    lines += ["", "Travel reduction > 100 % means the rover slid back down; CoT is infinite when it "
              "made no progress (Table 6 writes ∞ for the immobilised passive rover)."]
    summary = "\n".join(lines)
    print(summary)
    with open(os.path.join(args.out, "summary.md"), "w") as fh:
        fh.write(summary + "\n")
    with open(os.path.join(args.out, "slope_runs.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["soil [-]", "controller [-]", "t [s]", "x [m]", "y [m]", "z [m]", "psi [rad]",
                    "phi [rad]", "roll_torque [N m]", "energy [J]", "load_FL [N]", "load_FR [N]",
                    "load_RL [N]", "load_RR [N]"])
        for soil, runs in all_runs.items():
            for r in runs:
                for k in range(0, len(r["t"]), 5):
                    w.writerow([soil, r["controller"]] + [f"{r[c][k]:.5g}" for c in
                               ("t", "x", "y", "z", "psi", "phi", "roll_torque", "energy")] +
                               [f"{v:.5g}" for v in r["loads"][k]])
    for soil, runs in all_runs.items():
        for p in _plot(runs, args.out, soil):
            print(f"wrote {p}")
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("slope-demo", help="passive bogie vs the crawling gait on a 20° "
                              "slope (M90 and dry sand): travel reduction, cost of transport, plots",
                              description=__doc__)
    p.add_argument("--out", default="out/dynamics", help="output folder (default out/dynamics)")
    p.add_argument("--soils", default="m90,dry_sand",
                   help="comma-separated soil presets (default m90,dry_sand)")
    p.add_argument("--duration", type=_option("--duration", 0.0, 1e6), default=60.0, help="simulated seconds (default 60)")
    p.add_argument("--vx", type=_option("--vx", 0.0, MAX_VX), default=0.2,
                   help="commanded forward speed [m/s] of both controllers (default 0.2, the "
                        "crawling gait's and the evaluation's)")
    p.add_argument("--eps-slip", type=float, default=None,
                   help="eq 12 slip regularisation [(m/s)^-2] (default: the environments' 1e4; "
                        "Table 2's is 100)")
    p.set_defaults(func=main_args)


def main(**options) -> int:
    """``ernest slope-demo`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest slope-demo --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/dynamics")``. Returns the exit status; errors raise."""
    from .cli import run

    return run("slope-demo", **options)
