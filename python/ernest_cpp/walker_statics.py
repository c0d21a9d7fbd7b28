"""FootFall's statics on the SDM-B model (seed 003 §3.3, §5.1): the stability map of a stance
over centre-of-gravity positions (SSM, NESM, with the support polygon and the conservative
polygon of support) and a Fig. 11-style sag prediction (rigid vs sagged chassis-corner heights,
spring constant calibrated on synthetic measurements). Steps of ``ernest statics``
(``step(args, out_dir) -> list[str]``, see :mod:`ernest_cpp.rover_statics`); the computations
are C++ (``ernest_cpp.statics``, ``ernest_cpp.walker``)."""

from __future__ import annotations

import argparse
import math
import os

import numpy as np

from . import statics as S
from . import walker as W

SLOPE_DEG = 10.0  # ground slope of the NESM map (downhill towards +x)
PAPER_SAG = {"mean_cm": 1.2, "max_cm": 5.0, "height_m": 1.75}  # seed 003 §5.1.2, §5.1.4


def standard_stance(model: W.WalkerModel | None = None):
    """(model, body pose 4x4, q, feet (3, 6), CG (3,)) of the SDM-B standard stance."""
    model = model or W.WalkerModel(W.sdm_b_parameters())
    body, q = model.standard_body_pose(), model.standard_configuration
    return model, body, q, model.contact_points(body, q), model.center_of_mass(body, q)


def slope_gravity(slope_deg: float) -> np.ndarray:
    """Gravity in the robot's frame on a plane of ``slope_deg`` falling towards +x."""
    a = math.radians(slope_deg)
    return 9.81 * np.array([math.sin(a), 0.0, -math.cos(a)])


# ---- stability map (§3.3) ------------------------------------------------------------------------

def stability_map(n: int = 121, extent: float = 2.4, slope_deg: float = SLOPE_DEG) -> dict:
    """SSM, SSM of the CPS and NESM over an n x n grid of CG positions (x, y) in [-extent,
    extent]^2 at the standard stance's CG height, on flat ground, and the NESM with gravity tilted
    by ``slope_deg``. Keys: x, y (n,), ssm, ssm_cps, nesm, nesm_slope, nesm_cps_slope (n x n,
    [i_y, i_x]), feet, cg, support, cps (2 x k polygon vertices), slope_deg."""
    if not (n >= 3 and extent > 0 and math.isfinite(extent) and 0 <= slope_deg < 90):
        raise ValueError(f"stability map: need n >= 3, extent > 0, 0 <= slope_deg < 90 "
                         f"(got n = {n}, extent = {extent}, slope_deg = {slope_deg})")
    _, _, _, feet, cg = standard_stance()
    x = np.linspace(-extent, extent, n)
    flat, tilted = S.EARTH_GRAVITY, slope_gravity(slope_deg)
    out = {k: np.empty((n, n)) for k in ("ssm", "ssm_cps", "nesm", "nesm_slope", "nesm_cps_slope")}
    for iy, yv in enumerate(x):
        for ix, xv in enumerate(x):
            p = [xv, yv, cg[2]]
            m, s = S.stability_margins(feet, p, flat), S.stability_margins(feet, p, tilted)
            out["ssm"][iy, ix], out["ssm_cps"][iy, ix], out["nesm"][iy, ix] = m.ssm, m.ssm_cps, m.nesm
            out["nesm_slope"][iy, ix], out["nesm_cps_slope"][iy, ix] = s.nesm, s.nesm_cps
    frame = S.ProjectionFrame.from_gravity(flat)  # e1 = x, e2 = y
    out.update(x=x, y=x.copy(), feet=feet, cg=cg, slope_deg=slope_deg,
               support=S.support_polygon(feet, frame).vertices,
               cps=S.conservative_support_polygon(feet, frame).vertices)
    return out


def _closed(v: np.ndarray) -> np.ndarray:
    return np.hstack([v, v[:, :1]])


def tipping_x(slope_deg: float = SLOPE_DEG) -> float:
    """CG x (y = 0, standard height) where the NESM on the slope reaches zero downhill, by
    bisection on the margin itself (NESM is quadratic near zero, so grid interpolation is off)."""
    _, _, _, feet, cg = standard_stance()
    g = slope_gravity(slope_deg)
    lo, hi = 0.0, float(np.max(feet[0]))
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if S.stability_margins(feet, [mid, 0.0, cg[2]], g).nesm > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def plot_stability_map(m: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = (("ssm", "SSM, flat ground [m]"),
              ("ssm_cps", "SSM of the CPS (one foot may fail), flat [m]"),
              ("nesm_slope", f"NESM on a {m['slope_deg']:g}° slope (downhill +x) [m]"))
    fig, axes = plt.subplots(1, 3, figsize=(16, 5.2))
    for ax, (key, title) in zip(axes, panels):
        z = m[key]
        lim = float(np.nanmax(np.abs(z[np.isfinite(z)])))
        im = ax.pcolormesh(m["x"], m["y"], np.clip(z, -lim, lim), cmap="RdYlGn", vmin=-lim,
                           vmax=lim, shading="auto")
        ax.contour(m["x"], m["y"], z, levels=[0.0], colors="k", linewidths=1.2)
        s, c = _closed(m["support"]), _closed(m["cps"])
        ax.plot(s[0], s[1], "b-", lw=1.5, label="support polygon")
        ax.plot(c[0], c[1], "m--", lw=1.5, label="conservative polygon (CPS)")
        ax.plot(m["feet"][0], m["feet"][1], "ko", ms=6, label="feet")
        ax.plot(m["cg"][0], m["cg"][1], "r+", ms=12, mew=2, label="standard CG")
        ax.set(aspect="equal", xlabel="CG x [m]", ylabel="CG y [m]", title=title)
        fig.colorbar(im, ax=ax, shrink=0.8)
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle(f"SDM-B standard stance: stability over CG positions (CG height "
                 f"{m['cg'][2]:.2f} m; black line: margin 0) — seed 003 §3.3")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def step_stability(args: argparse.Namespace, out_dir: str) -> list[str]:
    """Seed 003 §3.3: stability map of the SDM-B standard stance over CG positions."""
    m = stability_map()
    name = "stability_map.png"
    plot_stability_map(m, os.path.join(out_dir, name))
    _, _, _, feet, cg = standard_stance()
    flat = S.stability_margins(feet, cg, S.EARTH_GRAVITY)
    tilt = S.stability_margins(feet, cg, slope_gravity(m["slope_deg"]))
    frame = S.ProjectionFrame.from_gravity(S.EARTH_GRAVITY)
    area_s = S.support_polygon(feet, frame).area()
    area_c = S.conservative_support_polygon(feet, frame).area()
    cell = (m["x"][1] - m["x"][0]) ** 2
    r = float(np.max(np.linalg.norm(feet[:2], axis=0)))
    h = cg[2]
    return [
        "## Stability map of a stance (seed 003 §3.3)", "",
        f"SDM-B standard stance (six feet on a circle of radius {r:.2f} m, CG at height "
        f"{h:.3f} m); margins over a {len(m['x'])}×{len(m['x'])} grid of CG positions (x, y) at "
        f"that height. `{name}`: the static stability margin (SSM: distance to the nearest edge "
        "of the support polygon, negative outside), the SSM of the conservative polygon of "
        "support (CPS: the intersection of the support polygons with one foot removed) and the "
        f"normalised energy stability margin (NESM) with the ground tilted {m['slope_deg']:g}°. "
        "FootFall maps stability over the target of the moving foot; this is the same margin "
        "seen from the CG. The paper gives no numbers for these maps.", "",
        "| quantity | ours | closed form |", "|---|---|---|",
        f"| support polygon area [m²] | {area_s:.4f} | 3√3/2 r² = {1.5 * math.sqrt(3) * r * r:.4f} |",
        f"| CPS area [m²] | {area_c:.4f} | hexagon of inradius r/2: 2√3 (r/2)² = "
        f"{2 * math.sqrt(3) * (r / 2) ** 2:.4f} |",
        f"| SSM at the standard CG [m] | {flat.ssm:.4f} | r cos 30° = {r * math.cos(math.pi / 6):.4f} |",
        f"| SSM of the CPS at the standard CG [m] | {flat.ssm_cps:.4f} | r/2 = {r / 2:.4f} |",
        f"| NESM at the standard CG, flat [m] | {flat.nesm:.4f} | √(SSM² + h²) − h = "
        f"{math.hypot(flat.ssm, h) - h:.4f} |",
        f"| NESM at the standard CG, {m['slope_deg']:g}° slope [m] | {tilt.nesm:.4f} | |",
        f"| NESM of the CPS, {m['slope_deg']:g}° slope [m] | {tilt.nesm_cps:.4f} | |",
        f"| grid area with SSM > 0 (flat) [m²] | {cell * np.sum(m['ssm'] > 0):.3f} | "
        f"the polygon's, {area_s:.3f} (up to the grid's resolution) |",
        f"| grid area with NESM > 0 ({m['slope_deg']:g}°) [m²] | "
        f"{cell * np.sum(m['nesm_slope'] > 0):.3f} | the same (the polygon shifted) |",
        f"| downhill tipping point on y = 0 (NESM = 0) [m] | {tipping_x(m['slope_deg']):.4f} | "
        f"r − h tan θ = {r - h * math.tan(math.radians(m['slope_deg'])):.4f} |",
        "", f"![stability]({name})", ""]


# ---- sag prediction (§5.1, Fig. 11) ----------------------------------------------------------------

#: Stances of the sag experiment: (title, lifted legs). Fig. 11 shows the first two; §5.1.2 also
#: measured one and two legs lifted.
SAG_STANCES = (("all six feet load-bearing (Fig. 11a)", ()), ("leg 5 lifted (Fig. 11b)", (5,)),
               ("leg 0 lifted", (0,)), ("legs 0 and 3 lifted", (0, 3)))


def sag_stances(lift_height: float = 0.2) -> list[tuple[str, tuple, S.SagProblem]]:
    """The SDM-B sag problems of :data:`SAG_STANCES`: unsagged feet of the standard stance, the CG
    of the pose with the legs lifted (``walker.lift_legs``), those feet raised ``lift_height``
    (eq 9), relative stiffness 1 (isotropic) and the six leg attachment points (chassis corners)
    as body points."""
    model, body, q, feet, _ = standard_stance()
    corners = np.array([(body @ model.hip_mount(k))[:3, 3] for k in range(model.legs)]).T
    out = []
    for title, legs in SAG_STANCES:
        ql = W.lift_legs(model, body, q, list(legs), lift_height) if legs else q
        p = S.sag_problem(feet, model.center_of_mass(body, ql), model.params.total_mass(), 1.0,
                          gravity=[0.0, 0.0, -model.params.gravity], body_points=corners,
                          chassis_position=body[:3, 3], chassis_rotation=body[:3, :3])
        for leg in legs:
            p = S.lift_foot(p, leg, lift_height)
        out.append((title, legs, p))
    return out


def _scaled(p: S.SagProblem, k: np.ndarray) -> S.SagProblem:
    return S.sag_problem(p.feet, p.cg, p.mass, np.asarray(p.stiffness) * k, lift=p.lift,
                         gravity=p.gravity, body_points=p.body_points,
                         chassis_position=p.chassis_position, chassis_rotation=p.chassis_rotation)


def sag_experiment(k_true: float = 6e4, spread: float = 0.125, noise: float = 0.003,
                   seed: int = 3) -> dict:
    """Synthetic version of §5.1.2's measurements and §5.1.3's calibration. The "measured" corner
    heights are the sag model's own answer with per-tyre constants k_true·(1 + u_i), u_i uniform
    in ±``spread`` (the paper's unequal tyre pressures, ±12.5 %), plus Gaussian noise of
    ``noise`` [m] (a hand-held laser meter). Then one constant is fitted to all stances
    (exhaustive search + Brent) and, from there, one per tyre (§5.1.4). Returns the stances, the
    truth, the fits and the heights (rigid, measured, predicted) per stance."""
    for name, v, ok in (("k_true", k_true, k_true > 0), ("spread", spread, 0 <= spread < 1),
                        ("noise", noise, noise >= 0)):
        if not (ok and math.isfinite(v)):
            raise ValueError(f"sag_experiment: {name} = {v} is out of range")
    rng = np.random.default_rng(seed)
    stances = sag_stances()
    k_tyres = k_true * (1.0 + rng.uniform(-spread, spread, stances[0][2].feet.shape[1]))
    calib, rows = [], []
    for title, legs, p in stances:
        truth = S.solve_sag(_scaled(p, k_tyres))
        if truth.status != S.SagStatus.Converged:
            raise ValueError(f"sag of the synthetic truth did not converge ({title}): {truth.status}")
        measured = truth.body_points[2] + rng.normal(0.0, noise, truth.body_points.shape[1])
        calib.append(S.CalibrationStance(p, measured))
        rows.append({"title": title, "legs": legs, "rigid": np.asarray(p.body_points)[2],
                     "true": truth.body_points[2], "measured": measured})
    fit = S.calibrate_spring_constant(calib)
    per_foot = S.calibrate_per_foot_constants(calib, fit.k)
    for row, (_, _, p) in zip(rows, stances):
        row["predicted"] = S.solve_sag(_scaled(p, np.full(len(k_tyres), fit.k))).body_points[2]
        row["per_foot"] = S.solve_sag(_scaled(p, per_foot.k)).body_points[2]
    return {"rows": rows, "k_tyres": k_tyres, "k_true": k_true, "noise": noise, "spread": spread,
            "fit": fit, "per_foot": per_foot}


def plot_sag(e: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(12, 8), sharey=True)
    k = e["fit"].k
    for ax, row in zip(axes.flat, e["rows"]):
        i = np.arange(len(row["rigid"]))
        err = 100 * np.mean(np.abs(row["predicted"] - row["measured"]))
        ax.plot(i, row["rigid"], "s--", color="0.5", label="rigid kinematics (no sag)")
        ax.errorbar(i, row["measured"], yerr=e["noise"], fmt="kx", ms=8, capsize=3,
                    label="measured (SYNTHETIC)")
        ax.plot(i, row["predicted"], "o-", color="C0", label=f"predicted, k = {k / 1e3:.1f} kN/m")
        ax.plot(i, row["per_foot"], ".:", color="C2", label="predicted, per-tyre k")
        for leg in row["legs"]:
            ax.axvspan(leg - 0.3, leg + 0.3, color="C1", alpha=0.15)
        ax.set(title=f"{row['title']}: mean |error| {err:.2f} cm", xticks=i,
               xlabel="chassis corner (leg attachment) — orange: lifted leg",
               ylabel="height [m]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="lower left")
    fig.suptitle("SDM-B chassis-corner heights, predicted vs measured (seed 003 Fig. 11 style; "
                 "the measurements are synthetic: per-tyre truth ±12.5 % + noise)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def step_sag(args: argparse.Namespace, out_dir: str) -> list[str]:
    """Seed 003 §5.1.2–5.1.4, Fig. 11: sag prediction on SDM-B stances after calibration."""
    e = sag_experiment()
    name = "fig11_sag.png"
    plot_sag(e, os.path.join(out_dir, name))
    fit, pf = e["fit"], e["per_foot"]
    errs = np.concatenate([r["predicted"] - r["measured"] for r in e["rows"]])
    lines = [
        "## Fig. 11: sag prediction (seed 003 §5.1.2–5.1.4, eqs 1–12)", "",
        "**The measurements here are synthetic**: the heights of SDM-B's six chassis corners (leg "
        "attachment points) computed by our own sag model with per-tyre spring constants "
        f"{e['k_true'] / 1e3:.0f} kN/m × (1 ± up to {100 * e['spread']:.1f} %, the paper's unequal "
        f"tyre pressures), plus Gaussian noise of {100 * e['noise']:.1f} cm. From them one "
        "spring constant is calibrated as in §5.1.3 (exhaustive search over 1e3–1e7 N/m, then "
        "Brent), then one per tyre (§5.1.4). So this checks that the calibration recovers a known "
        "constant and what the prediction error is with the paper's tyre spread; it is not "
        "evidence that the model fits the hardware (the paper's errors include unmodelled leg "
        f"compliance). Legs lifted 0.2 m; rigid kinematics puts every corner at "
        f"{e['rows'][0]['rigid'][0]:.2f} m. `{name}`.", "",
        "| stance | rigid height [m] | measured mean / min [m] | predicted mean / min [m] | "
        "mean \\|error\\| [cm] | max \\|error\\| [cm] |", "|---|---|---|---|---|---|"]
    for r in e["rows"]:
        d = np.abs(r["predicted"] - r["measured"])
        lines.append(f"| {r['title']} | {r['rigid'].mean():.3f} | {r['measured'].mean():.3f} / "
                     f"{r['measured'].min():.3f} | {r['predicted'].mean():.3f} / "
                     f"{r['predicted'].min():.3f} | {100 * d.mean():.2f} | {100 * d.max():.2f} |")
    k_mean = e["k_tyres"].mean()
    p0 = sag_stances()[0][2]  # closed form: six equal springs, CG over the centre -> m g / (6 k)
    uniform = S.solve_sag(_scaled(p0, np.full(6, fit.k)))
    lines += [
        "", "| | ours (synthetic) | paper (SDM-B hardware) |", "|---|---|---|",
        f"| mean \\|height error\\| | {100 * np.mean(np.abs(errs)):.2f} cm | "
        f"{PAPER_SAG['mean_cm']} cm |",
        f"| max \\|height error\\| | {100 * np.max(np.abs(errs)):.2f} cm | < {PAPER_SAG['max_cm']:.0f} cm |",
        f"| chassis height | {e['rows'][0]['rigid'][0]:.2f} m | {PAPER_SAG['height_m']} m |",
        f"| sag on six equal springs (fitted k) | {100 * (p0.body_points[2] - uniform.body_points[2]).mean():.3f} cm "
        f"(closed form m g / 6k = {100 * p0.mass * 9.81 / (6 * fit.k):.3f} cm) | |",
        f"| calibrated constant | {fit.k / 1e3:.2f} kN/m (grid {fit.k_grid / 1e3:.2f}; true tyres "
        f"mean {k_mean / 1e3:.2f}) | \"slight adjustments\" to the manufacturer's |",
        "", "Per-tyre constants [kN/m] (true → fitted): " + ", ".join(
            f"{a / 1e3:.1f} → {b / 1e3:.1f}" for a, b in zip(e["k_tyres"], pf.k)) +
        f"; mean error then {100 * pf.mean_error:.2f} cm (the noise floor: "
        f"{100 * e['noise'] * math.sqrt(2 / math.pi):.2f} cm). {fit.sag_solves + pf.sag_solves} sag solves.",
        "", f"![sag]({name})", ""]
    return lines
