"""FootFall single-leg planning for the wheel-on-leg walker (seed 003 §3.3–3.4, §4.1, §5.1):
reachability and stability maps of one leg over a digital elevation map, OMPL's SBL in the
leg's joint space with lazy bisection edge checks (FCL self and terrain collisions), FootFall's
Dijkstra–bisection path smoothing (by length, or by peak joint torque, §7.1), torque-aware maps
(StabilityMapOptions.max_saturation, CellStatus.Overloaded), and steps planned against the sagged pose the compliance model
predicts. The work is done in C++ (``ernest_cpp._core.footfall``); this module re-exports it and
adds numpy views and plots (matplotlib, Agg).

The terrain is a :class:`ernest_cpp.dynamics.HeightMap`; poses are 4 × 4 matrices; paths are
``(joints, waypoints)`` arrays.
"""

from __future__ import annotations

import numpy as np

from ._core.footfall import (  # noqa: F401  (re-exports)
    CellEvaluation,
    CellStatus,
    CollisionOptions,
    LegCollisionChecker,
    LegPlanner,
    MapTerrain,
    MapTerrainOptions,
    PlannerOptions,
    PlannerType,
    PlanResult,
    PlanStatus,
    RockFieldOptions,
    SmoothingObjective,
    SmoothingOptions,
    SmoothingResult,
    StabilityCriterion,
    StabilityMap,
    StabilityMapOptions,
    StabilityMapper,
    StanceTorques,
    StepOptions,
    StepPlan,
    SwingSag,
    SwingSagOptions,
    TerrainCell,
    TorquePeak,
    default_clearance_table,
    first_colliding_edge,
    path_length,
    plan_step,
    predict_swing_sag,
    rock_field,
    sample_waypoints,
    smooth_path,
    smooth_path_for_torque,
    terrain_from_arrays,
    terrain_from_map,
)

__all__ = [
    "CellEvaluation", "CellStatus", "CollisionOptions", "LegCollisionChecker", "LegPlanner",
    "MapTerrain", "MapTerrainOptions", "PlannerOptions", "PlannerType", "PlanResult", "PlanStatus",
    "RockFieldOptions",
    "SmoothingObjective", "SmoothingOptions", "SmoothingResult", "StabilityCriterion", "StabilityMap",
    "StabilityMapOptions", "StabilityMapper", "StanceTorques", "StepOptions", "StepPlan", "SwingSag",
    "SwingSagOptions", "default_clearance_table", "first_colliding_edge", "map_arrays",
    "path_length", "plan_step", "plot_leg_path", "plot_stability_map", "predict_swing_sag",
    "rock_field", "sample_waypoints", "smooth_path", "smooth_path_for_torque", "stability_map", "TerrainCell",
    "TorquePeak",
    "terrain_from_arrays", "terrain_from_map",
]


def stability_map(model, terrain, body, q, leg: int, options: StabilityMapOptions | None = None) -> dict:
    """The stability map of ``leg`` (§3.3) as numpy arrays: ``x`` (nx,), ``y`` (ny,) cell centres,
    ``status`` (nx, ny) uint8 (0 unreachable, 1 unstable, 2 stable), ``margin`` (nx, ny) [m]
    (NaN where unreachable), plus ``nesm``, ``hip``, ``reach``, ``ik_solves`` and the map."""
    m = StabilityMapper(model, terrain, body, q, leg, options or StabilityMapOptions()).map()
    return map_arrays(m)


def map_arrays(m: StabilityMap) -> dict:
    """numpy view of a :class:`StabilityMap` (see :func:`stability_map`)."""
    status = np.asarray(m.status, dtype=np.uint8)
    nx, ny = status.shape
    return {"x": m.origin_x + m.cell * np.arange(nx), "y": m.origin_y + m.cell * np.arange(ny),
            "status": status, "margin": np.asarray(m.margin), "nesm": m.nesm, "hip": np.asarray(m.hip),
            "reach": m.reach, "ik_solves": m.ik_solves, "map": m}


def _terrain_grid(terrain, x, y):
    return np.array([[terrain.height(float(a), float(b)) for b in y] for a in x])


def plot_stability_map(arrays: dict, path, terrain=None, feet=None, goal=None, title: str = "") -> None:
    """Stable cells green, unstable red, unreachable uncoloured (§3.3, Fig. 19), over the terrain's
    heights (grey) when given; ``feet`` (3, legs) marked, ``goal`` (x, y) starred."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    x, y, status = arrays["x"], arrays["y"], arrays["status"]
    fig, ax = plt.subplots(figsize=(6.2, 5.6))
    ext = (x[0], x[-1], y[0], y[-1])
    if terrain is not None:
        xs, ys = x[::4], y[::4]
        hz = _terrain_grid(terrain, xs, ys)
        # capped at 1.5 m: a stereo DEM's unknown cells are columns far above the rocks
        im = ax.imshow(hz.T, origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]), cmap="Greys",
                       alpha=0.9, vmin=0.0, vmax=min(1.5, max(0.05, float(hz.max()))))
        fig.colorbar(im, ax=ax, label="terrain height [m]", shrink=0.8)
    colour = np.ma.masked_equal(status.astype(float), 0.0)
    ax.imshow(colour.T, origin="lower", extent=ext, cmap=ListedColormap(["#d62728", "#2ca02c"]),
              vmin=1, vmax=2, alpha=0.55, interpolation="nearest")
    if feet is not None:
        f = np.asarray(feet)
        ax.plot(f[0], f[1], "ko", ms=6, label="feet")
    if goal is not None:
        ax.plot(goal[0], goal[1], "*", color="gold", mec="k", ms=14, label="goal")
    hip = arrays["hip"]
    ax.plot(hip[0], hip[1], "b^", ms=7, label="hip")
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(y[0], y[-1])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    crit = "NESM" if arrays["nesm"] else "SSM"
    ax.set_title(title or f"stability map ({crit} of the CPS): green stable, red unstable")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def wheel_track(model, body, leg: int, path: np.ndarray, samples: int = 20) -> np.ndarray:
    """World wheel-centre positions (3, k) along a joint-space path (straight edges sampled)."""
    body = np.asarray(body)
    pts = []
    for k in range(path.shape[1] - 1):
        for t in np.linspace(0.0, 1.0, samples, endpoint=False):
            qk = path[:, k] + t * (path[:, k + 1] - path[:, k])
            pts.append((body @ model.foot_pose(leg, qk))[:3, 3])
    pts.append((body @ model.foot_pose(leg, path[:, -1]))[:3, 3])
    return np.array(pts).T


def plot_leg_path(model, terrain, step: StepPlan, leg: int, path, title: str = "") -> None:
    """Left: the wheel centre's track (side view along the step) for the raw SBL plan and the
    smoothed one, over the terrain profile under it. Right: joint angles along the path."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    body = step.planning_body
    raw, smooth = np.asarray(step.plan.path), np.asarray(step.smoothing.path)
    full = np.asarray(step.path)
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    start, goal = wheel_track(model, body, leg, full[:, :1])[:, 0], np.asarray(step.goal)
    d = goal[:2] - start[:2]
    u = d / max(1e-9, np.linalg.norm(d))
    for p, style, label in ((raw, "C1--", f"SBL ({step.plan.length:.2f} rad)"),
                            (full, "C0-", f"smoothed ({step.smoothing.length:.2f} rad)")):
        w = wheel_track(model, body, leg, p)
        a.plot((w[:2].T - start[:2]) @ u, w[2], style, label=label)
    s = np.linspace(-0.4, np.linalg.norm(d) + 0.4, 200)
    a.fill_between(s, [terrain.height(*(start[:2] + si * u)) for si in s], -0.05, color="0.6",
                   label="terrain under the step")
    a.set_xlabel("along the step [m]")
    a.set_ylabel("wheel centre height [m]")
    a.set_aspect("equal")
    a.legend(fontsize=8)
    names = [j.name for j in model.params.joints]
    t = np.linspace(0.0, 1.0, smooth.shape[1])
    tr = np.linspace(0.0, 1.0, raw.shape[1])
    for i, name in enumerate(names):
        b.plot(tr, np.degrees(raw[i]), f"C{i}--", lw=0.8)
        b.plot(t, np.degrees(smooth[i]), f"C{i}-", label=name)
    b.set_xlabel("waypoint (normalised); dashed: SBL, solid: smoothed")
    b.set_ylabel("joint angle [deg]")
    b.legend(fontsize=7, ncol=2)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
