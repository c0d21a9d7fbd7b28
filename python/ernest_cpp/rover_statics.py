"""ERNEST's statics in Python (seed 004 §3.2 eq 11, §5.5 Fig. 25) and the ``ernest statics``
command. The computations are C++ (``ernest_cpp.statics``); this module runs them over sweeps and
episodes, writes the reports and draws the plots.

``ernest statics --out DIR`` runs the steps of :data:`STEPS` in order (``--steps a,b`` a subset);
each step is a function ``step(args, out_dir) -> list[str]`` returning Markdown lines for
``DIR/report.md`` and writing its PNG. FootFall's steps (seed 003 on the SDM-B model: stability
map, sag, weight distribution, sway gait) live in ``walker_statics`` and ``walker_demo``.
"""

from __future__ import annotations

import argparse
import math
import os

import numpy as np

from . import dynamics as D
from . import statics as S
from . import walker_demo, walker_statics

SLOPE_DEG = 20.0  # Fig. 25's slope
NAMES = ("m_c [kg]", "m_b [kg]", "x_c [m]", "y_c [m]", "z_c [m]", "z_b [m]")


# ---- mass model (eq 11) ------------------------------------------------------------------------

def fit_survey(params: D.RoverParameters | None = None, noise: float = 0.0, seed: int = 0,
               survey: list | None = None) -> dict:
    """The simulated load survey and three fits of eq 11: as printed (vertical forces only, all
    six parameters free), with the FTS's horizontal forces (all free: five identifiable) and with
    those and the bogie mass weighed (fixed at the simulator's value). ``noise`` [N]: Gaussian noise
    added to every load (and horizontal force) first. Returns the poses, the truth and the fits."""
    params = params or D.RoverParameters()
    if not (noise >= 0 and math.isfinite(noise)):
        raise ValueError(f"noise must be >= 0 and finite, got {noise}")
    poses = survey if survey is not None else S.survey_loads(params)
    rng = np.random.default_rng(seed)
    if noise > 0:
        for q in poses:
            q.loads = q.loads + rng.normal(0.0, noise, 4)
    geo = S.RoverGeometry.from_parameters(params)
    truth = S.MassModel.from_parameters(params)
    guess = S.MassModel.from_vector([45.0, 25.0, 0.0, 0.0, 0.4, 0.15])  # rough, not the truth
    printed = []
    for q in poses:
        p = _copy_pose(q)
        p.horizontal_forces = np.zeros((2, 4))
        printed.append(p)
    fixed = S.MassFitOptions()
    fixed.fixed = [False, True, False, False, False, False]
    weighed = S.MassModel.from_vector(np.r_[guess.chassis_mass, truth.bogie_mass, guess.chassis_com,
                                            guess.bogie_com_height])
    return {"poses": poses, "truth": truth, "geometry": geo,
            "printed": S.fit_mass_model(printed, geo, guess),
            "horizontal": S.fit_mass_model(poses, geo, guess),
            "weighed": S.fit_mass_model(poses, geo, weighed, fixed),
            "printed_poses": printed}


def _copy_pose(q: S.LoadPose) -> S.LoadPose:
    p = S.LoadPose()
    for k in ("chassis_quaternion", "psi", "phi", "roll_torque", "ground_normal", "loads",
              "horizontal_forces"):
        setattr(p, k, getattr(q, k))
    return p


def _fit_table(fits: dict) -> list[str]:
    t = fits["truth"].vector()
    lines = ["| parameter | simulator | eq 11 as printed | + FTS horizontal forces | "
             "+ bogie weighed |", "|---|---|---|---|---|"]
    for k, name in enumerate(NAMES):
        cells = []
        for key in ("printed", "horizontal", "weighed"):
            r = fits[key]
            v, s = r.model.vector()[k], r.std_error[k]
            cells.append(f"{v:.4g} (fixed)" if s == 0 else
                         f"{v:.4g} ± {s:.2g}" if math.isfinite(s) else f"{v:.4g} (not identifiable)")
        lines.append(f"| {name} | {t[k]:.4g} | " + " | ".join(cells) + " |")
    lines.append("| R² | | " + " | ".join(f"{fits[k].r_squared:.4f}" for k in
                                          ("printed", "horizontal", "weighed")) + " |")
    lines.append("| RMSE [N] | | " + " | ".join(f"{fits[k].rmse:.2f}" for k in
                                                ("printed", "horizontal", "weighed")) + " |")
    return lines


def step_mass_model(args: argparse.Namespace, out_dir: str) -> list[str]:
    """Seed 004 §3.2, eq 11: identify the simulator's mass model from its own FTS loads."""
    clean = fit_survey()
    noisy = fit_survey(noise=args.noise, seed=1, survey=S.survey_loads(D.RoverParameters()))
    n = len(clean["poses"])
    lines = ["## Mass model (seed 004 §3.2, eq 11)", "",
             f"{n} static poses of the simulated rover (gimbal yaw ±40°, an 8 cm block under each "
             f"wheel in turn on flat ground, 12° and 20° rigid slopes at four headings; AGS off, "
             f"clutch open, settled 4 s); each wheel's ground force from its force–torque sensor "
             f"plus the wheel assembly's weight. Paper, on hardware: R² = 0.96.", "",
             "Noise-free:", ""] + _fit_table(clean) + [
             "", f"With Gaussian noise of {args.noise:g} N on every vertical load (1σ from the "
             "Jacobian at the optimum; `tests/cpp/test_statics_rover.cpp` checks over 20 noise "
             "seeds that the scatter matches it):", ""] + _fit_table(noisy) + [
             "", "Eq 11 as printed has vertical forces only; the tyres of the settled rover carry "
             "friction (scrubbed sideways while the bogie rolled onto a block, holding the rover on "
             "a slope), whose moments it misses. With the horizontal forces the six-axis sensors "
             "measure, the statics are exact. The bogie/chassis split is not identifiable from "
             "wheel loads on this rover: its gimbal point lies on the bogie's CoM line, so mass "
             "moved between the two bodies at that point changes no load (rank 5 of 6); weighing "
             "the bogie assembly fixes it.", ""]
    lines.append(f"![loads]({_parity_plot(clean, out_dir)})")
    return lines


def _parity_plot(fits: dict, out_dir: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), sharex=True, sharey=True)
    for ax, key, poses, title in ((axes[0], "printed", fits["printed_poses"], "eq 11 as printed"),
                                  (axes[1], "weighed", fits["poses"],
                                   "+ FTS horizontal forces, bogie weighed")):
        r = fits[key]
        meas = np.array([q.loads for q in poses])
        pred = np.array([S.predict_loads(r.model, fits["geometry"], q) for q in poses])
        for i, (w, mk) in enumerate(zip(D.WHEELS, "os^v")):  # open markers: mirror poses overlap
            ax.plot(meas[:, i], pred[:, i], mk, mfc="none", ms=5, label=w)
        lo, hi = float(meas.min()) - 10, float(meas.max()) + 10
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.7)
        ax.set(xlabel="measured vertical load [N]", ylabel="fitted model [N]",
               title=f"{title}: R² = {r.r_squared:.3f}")
        ax.legend(fontsize=8)
    fig.suptitle("Seed 004 eq 11: mass-model fit on the simulator's FTS loads")
    fig.tight_layout()
    name = "mass_model_fit.png"
    fig.savefig(os.path.join(out_dir, name), dpi=120)
    plt.close(fig)
    return name


# ---- lift-off torque (Fig. 25) -------------------------------------------------------------------

def liftoff_sweep(psi_deg: np.ndarray | None = None, slope_deg: float = SLOPE_DEG,
                  heading_deg: float = 0.0, model: S.MassModel | None = None,
                  params: D.RoverParameters | None = None) -> dict[str, np.ndarray]:
    """Largest (+) and smallest (-) roll torque before lift-off [N m] and the loads then [N] over
    the gimbal yaw, for the rover on a plane of ``slope_deg`` heading ``heading_deg`` from uphill
    (Fig. 25). Keys: psi_deg, tau_pos, tau_neg, loads_pos (n x 4), loads_neg, loads_zero."""
    params = params or D.RoverParameters()
    model = model or S.MassModel.from_parameters(params)
    geo = S.RoverGeometry.from_parameters(params)
    psi_deg = np.linspace(-45, 45, 91) if psi_deg is None else np.asarray(psi_deg, dtype=float)
    out = {k: [] for k in ("tau_pos", "tau_neg", "loads_pos", "loads_neg", "loads_zero")}
    for psi in psi_deg:
        r = S.max_roll_torque(model, geo, S.slope_pose(math.radians(slope_deg),
                                                       math.radians(heading_deg), math.radians(psi)))
        if not r.feasible:
            raise ValueError(f"the rover tips over at psi = {psi} deg on {slope_deg} deg")
        out["tau_pos"].append(r.positive.torque)
        out["tau_neg"].append(r.negative.torque)
        out["loads_pos"].append(r.positive.loads)
        out["loads_neg"].append(r.negative.loads)
        out["loads_zero"].append(r.loads_at_zero)
    res = {k: np.asarray(v) for k, v in out.items()}
    res["psi_deg"] = psi_deg
    return res


def policy_ascent(policy_file: str, episode_length: float | None = None, seed: int = 0) -> dict:
    """Run the learned policy on ``ernest/SlopeEval-v0`` (dry M90, the Table 6 slope) and, at each
    policy step, the roll torque it applies and the lift-off limits of that configuration
    (chassis attitude, psi, phi, the terrain's normal under the rover) from the mass model."""
    import gymnasium as gym

    import ernest_cpp.envs  # noqa: F401  (registers the ids)

    from .evaluate import LEARNED, controllers

    policy, passive = controllers(policy_file)[LEARNED]
    kwargs = {"soil": "m90"}
    if episode_length is not None:
        kwargs["episode_length"] = float(episode_length)
    env = gym.make("ernest/SlopeEval-v0", passive=passive, **kwargs)
    obs, _ = env.reset(seed=seed)
    while True:
        obs, _, term, trunc, _ = env.step(policy(obs, env))
        if term or trunc:
            break
    u = env.unwrapped
    params = D.RoverParameters()
    model, geo = S.MassModel.from_parameters(params), S.RoverGeometry.from_parameters(params)
    rows = []
    for h in u.history[1:]:
        x, y = h["position"][:2]
        d = 0.3  # normal of the terrain under the rover over about its wheelbase
        sc = u.scenario
        n = np.array([-(sc.height(x + d, y) - sc.height(x - d, y)) / (2 * d),
                      -(sc.height(x, y + d) - sc.height(x, y - d)) / (2 * d), 1.0])
        pose = S.LoadPose()
        cy, sy = math.cos(h["yaw"] / 2), math.sin(h["yaw"] / 2)
        cp, sp = math.cos(h["pitch"] / 2), math.sin(h["pitch"] / 2)
        cr, sr = math.cos(h["roll"] / 2), math.sin(h["roll"] / 2)
        pose.chassis_quaternion = [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                                   cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]
        pose.psi, pose.phi, pose.ground_normal = h["gimbal_yaw"], h["gimbal_roll"], n
        r = S.max_roll_torque(model, geo, pose)
        rows.append((h["time"], h["gimbal_yaw"], h["gimbal_roll"], h["roll_torque"],
                     r.positive.torque if r.feasible else np.nan,
                     r.negative.torque if r.feasible else np.nan))
    a = np.array(rows)
    return {"t": a[:, 0], "psi": a[:, 1], "phi": a[:, 2], "tau": a[:, 3], "tau_pos": a[:, 4],
            "tau_neg": a[:, 5], "progress": float(u.metrics.get("progress", np.nan))}


def step_liftoff(args: argparse.Namespace, out_dir: str) -> list[str]:
    """Seed 004 Fig. 25: the lift-off roll torque on a 20 deg slope, and the policy against it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sweep = liftoff_sweep()
    actuator = D.RoverParameters().gimbal_motor.max_output_torque()
    trace = None
    if args.policy and os.path.exists(args.policy):
        trace = policy_ascent(args.policy, episode_length=args.episode_length)
    fig, axes = plt.subplots(1, 3 if trace else 2, figsize=(16 if trace else 11, 4.6))
    ax = axes[0]
    ax.fill_between(sweep["psi_deg"], sweep["tau_neg"], sweep["tau_pos"], color="C0", alpha=0.15,
                    label="no wheel lifts")
    ax.plot(sweep["psi_deg"], sweep["tau_pos"], "C0-", label="lift-off limit (LP)")
    ax.plot(sweep["psi_deg"], sweep["tau_neg"], "C0-")
    for s in (1, -1):
        ax.axhline(s * actuator, color="0.5", ls=":", lw=1,
                   label="roll actuator limit" if s > 0 else None)
    if trace:
        ax.plot(np.degrees(trace["psi"]), trace["tau"], "r.", ms=4, label="learned policy")
    ax.set(xlabel="gimbal yaw ψ [deg]", ylabel="roll torque on the bogie [N m]",
           title=f"Max roll torque before lift-off, {SLOPE_DEG:.0f}° slope (uphill)")
    ax.legend(fontsize=8, loc="lower left")
    ax = axes[1]
    for i, w in enumerate(D.WHEELS):
        ax.plot(sweep["psi_deg"], sweep["loads_pos"][:, i], f"C{i}-", label=f"{w}, τ = max")
        ax.plot(sweep["psi_deg"], sweep["loads_neg"][:, i], f"C{i}--", label=f"{w}, τ = min")
    ax.set(xlabel="gimbal yaw ψ [deg]", ylabel="vertical wheel load [N]",
           title="Load distribution at the limit")
    ax.legend(fontsize=7, ncol=2)
    lines = ["## Lift-off roll torque (seed 004 §5.5, Fig. 25)", "",
             f"Linear program (GLPK) on the mass model of §3.2 for the rover on a {SLOPE_DEG:.0f}° "
             "slope heading uphill, gimbal roll 0: the largest torque of either sign the roll "
             "clutch can apply before a wheel's vertical load reaches zero, and the loads then. "
             f"Over ψ ∈ [-45°, 45°]: max {sweep['tau_pos'].min():.0f}–{sweep['tau_pos'].max():.0f} "
             f"N m, min {sweep['tau_neg'].max():.0f} to {sweep['tau_neg'].min():.0f} N m; the roll "
             f"actuator gives at most {actuator:.0f} N m."]
    if trace:
        ax = axes[2]
        ax.fill_between(trace["t"], trace["tau_neg"], trace["tau_pos"], color="C0", alpha=0.15,
                        step="mid", label="no wheel lifts (its configuration)")
        ax.plot(trace["t"], trace["tau"], "r.-", ms=3, lw=0.7, label="policy's roll torque")
        ax.set(xlabel="t [s]", ylabel="[N m]", title="Policy on SlopeEval-v0 (M90) vs the limit")
        ax.legend(fontsize=8)
        lim = np.where(trace["tau"] >= 0, trace["tau_pos"], -trace["tau_neg"])
        frac = np.abs(trace["tau"]) / lim
        lines += ["", f"Learned policy `{args.policy}` on `ernest/SlopeEval-v0` (M90, "
                  f"{trace['t'][-1]:.0f} s, progress {trace['progress']:.2f} m): |τ| / limit of "
                  f"its configuration: median {np.nanmedian(frac):.2f}, 90th percentile "
                  f"{np.nanpercentile(frac, 90):.2f}, max {np.nanmax(frac):.2f} (the paper: the "
                  "controller operates close to the limit)."]
    fig.tight_layout()
    name = "liftoff_torque.png"
    fig.savefig(os.path.join(out_dir, name), dpi=120)
    plt.close(fig)
    lines += ["", f"![lift-off]({name})", ""]
    return lines


#: The policy of the liftoff step when --policy is not given.
DEFAULT_POLICY = "policies/ernest_default.pt"

#: The steps of ``ernest statics``, in order: (name, function(args, out_dir) -> report lines).
#: The first four are FootFall's (seed 003, SDM-B model); the last two ERNEST's (seed 004).
STEPS = [("stability", walker_statics.step_stability), ("sag", walker_statics.step_sag),
         ("weight-distribution", walker_demo.step_weight_distribution),
         ("sway-gait", walker_demo.step_sway_gait),
         ("liftoff", step_liftoff), ("mass-model", step_mass_model)]


def main_args(args: argparse.Namespace) -> int:
    names = [s.strip() for s in args.steps.split(",") if s.strip()] if args.steps else \
        [n for n, _ in STEPS]
    known = dict(STEPS)
    if not names:
        raise ValueError(f"--steps names no step (steps: {', '.join(known)})")
    for n in names:
        if n not in known:
            raise ValueError(f"unknown step {n!r} (steps: {', '.join(known)})")
    if not (args.noise >= 0 and math.isfinite(args.noise)):
        raise ValueError(f"--noise must be >= 0, got {args.noise}")
    if not (args.stride > 0 and math.isfinite(args.stride)):
        raise ValueError(f"--stride must be > 0, got {args.stride}")
    # Only the default policy may be missing (the plot goes without it); one named on the command
    # line must exist and be used by a step that is run ("" means none).
    if args.policy is None:
        args.policy = DEFAULT_POLICY
    elif args.policy:
        if "liftoff" not in names:
            raise ValueError("--policy is used only by the liftoff step, which --steps leaves out")
        if not os.path.isfile(args.policy):
            raise ValueError(f"--policy {args.policy}: no such file")
    os.makedirs(args.out, exist_ok=True)
    lines = ["# Statics", "", "Seed 003 (FootFall, ATHLETE SDM-B model) and seed 004 (ERNEST); "
             "steps: " + ", ".join(names) + ".", ""]
    for n in names:
        print(f"ernest statics: {n}", flush=True)
        lines += known[n](args, args.out)
    path = os.path.join(args.out, "report.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print(f"wrote {path}")
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("statics", help="statics: stability map, sag (seed 003 Fig. 11), "
                              "legs lifted (Fig. 16), sway gait (Fig. 15), lift-off roll torque "
                              "(seed 004 Fig. 25), mass-model fit (eq 11)", description=__doc__)
    p.add_argument("--out", default="out/statics", help="output folder (default out/statics)")
    p.add_argument("--steps", default="",
                   help=f"comma-separated steps (default all: {', '.join(n for n, _ in STEPS)})")
    p.add_argument("--policy", default=None,
                   help="learned policy whose slope ascent is plotted against the limit (default "
                        f"{DEFAULT_POLICY}, skipped if that file does not exist; a named file "
                        "must exist; \"\" for none)")
    p.add_argument("--episode-length", type=float, default=None,
                   help="seconds of the policy's SlopeEval-v0 episode (default: the env's 60)")
    p.add_argument("--noise", type=float, default=10.0,
                   help="noise [N] on the loads of the noisy mass-model fit (default 10)")
    p.add_argument("--stride", type=float, default=0.5,
                   help="foot advance per cycle of the sway gait [m] (default 0.5)")
    p.set_defaults(func=main_args)


def main(**options) -> int:
    """``ernest statics`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest statics --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/statics", steps="stability,sag")``. Returns the exit status; errors raise."""
    from .cli import run

    return run("statics", **options)
