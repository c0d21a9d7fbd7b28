"""A full FootFall gait cycle around rocks, planned and executed in the ODE walker (seed 003 §6,
Fig. 19: D-RATS 2010; execution in simulation is beyond the paper). One rock field feeds both
sides: box rocks (``walker_sim.box_rock_field``) that the simulator collides with, rasterised into
the planner's height map (``walker_sim.rock_height_map``). The C++ driver
(``walker_sim.run_footfall_cycle``) builds each leg's stability map (§3.3), moves the gait's nominal
foothold to the nearest stable rock-free cell, plans the swing against the sag-predicted stance
(§4.1, §5.1; SBL §3.4.1, smoothing §3.4.2), executes swing and body shift under joint position
control and measures every wheel's clearance to every rock. This module builds the world, runs the
cycle and draws the stability maps and an animation (matplotlib, Agg; GIF by Pillow).

The planner's terrain is a parameter: :func:`run`, :func:`demo` and ``footfall_demo.run`` take any
``dynamics.HeightMap`` (by default the rasterised rocks; a perceived map, stereo and fused, plugs
in there unchanged while the simulator keeps the boxes).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from . import footfall as F
from . import walker as W
from . import walker_sim as WS

#: Stride of every foot and the body's advance over the cycle [m] (the demo's).
STRIDE = 0.4
#: CPS margin a foothold must keep [m]: our choice (the paper gives no number); on six feet every
#: reachable cell has 0.45–1.0 m, so 0.7 m shows both colours (feet pulled in turn red).
MIN_MARGIN = 0.7


def rock_world(model, seed: int = 3, rocks: int = 60, spacing: float = 0.02):
    """Box rocks around the standard stance (none within 0.45 m of the feet nor within 1.4 m of the
    body centre; the nominal footholds a stride ahead may be taken, and the planner then moves
    them) and the planner's height map of the same rocks, footprints dilated by a grid cell's
    diagonal so the bilinear map never lies below a box. Returns (rocks, terrain, RockFieldOptions)."""
    body = np.asarray(model.standard_body_pose())
    keep = np.asarray(model.contact_points(body, model.standard_configuration))[:2].copy()
    ro = F.RockFieldOptions()
    ro.rocks, ro.seed, ro.length, ro.centre_x, ro.keep_clear, ro.inner_radius = rocks, seed, 8.0, 0.5, 0.45, 1.4
    ro.min_height, ro.max_height, ro.min_radius, ro.max_radius = 0.1, 0.45, 0.1, 0.3
    boxes = WS.box_rock_field(ro, keep)
    mo = WS.RockMapOptions()
    mo.length, mo.centre_x, mo.centre_y, mo.spacing = ro.length, ro.centre_x, ro.centre_y, spacing
    mo.dilation = np.sqrt(2.0) * spacing
    return boxes, WS.rock_height_map(boxes, mo), ro


def cycle_options(cell: float = 0.02, seed: int = 3, sag_compensation: bool = True, dt: float | None = None,
                  frame_interval: float | None = None, stride: float = STRIDE,
                  flat_tolerance: float | None = None) -> WS.FootfallCycleOptions:
    o = WS.FootfallCycleOptions()
    o.stride = stride
    if flat_tolerance is not None:
        o.flat_tolerance = flat_tolerance
    o.step.map.cell = cell
    o.step.map.min_margin = MIN_MARGIN
    o.step.planner.seed = seed
    o.step.planner.time_limit = 2.0
    o.step.sag_compensation = sag_compensation
    o.execution.frame_interval = frame_interval
    if dt is not None:
        o.sim.dt = dt
    return o


def run(model, terrain, rocks, options: WS.FootfallCycleOptions) -> WS.FootfallCycleResult:
    """The planned and executed cycle: plans on ``terrain`` (any HeightMap), executes among ``rocks``."""
    return WS.run_footfall_cycle(model, terrain, rocks, options)


def summary(r: WS.FootfallCycleResult) -> dict:
    """Per-step and whole-cycle figures (lengths in m and rad, times in s)."""
    steps = []
    for s in r.steps:
        p = s.plan
        row = {"leg": s.leg, "solved": bool(p.solved), "reason": p.reason, "map_seconds": s.map_seconds,
               "stable_cells": int(s.map.count(F.CellStatus.Stable)),
               "unstable_cells": int(s.map.count(F.CellStatus.Unstable)),
               "nominal_goal": np.asarray(s.nominal_goal).tolist(), "candidates_tried": s.candidates_tried}
        if p.solved:
            row.update(goal=np.asarray(p.goal)[:2].tolist(),
                       goal_offset=float(np.linalg.norm(np.asarray(p.goal)[:2] - np.asarray(s.nominal_goal))),
                       plan_seconds=p.plan.seconds, smooth_seconds=p.smoothing.seconds,
                       raw_length=p.plan.length, smoothed_length=p.smoothing.length,
                       swing_hip_sag=float(-p.sag.hip_displacement[2]),
                       planned_clearance=s.planned_clearance, executed_swing_clearance=s.swing_rock_clearance,
                       min_rock_clearance=s.min_rock_clearance, transfer_ground_clearance=s.transfer_ground_clearance)
        steps.append(row)
    advance = float(np.asarray(r.body_end)[0] - np.asarray(r.body_start)[0])
    return {"completed": bool(r.completed), "reason": r.reason, "steps": steps,
            "min_rock_clearance": r.min_rock_clearance, "planned_advance": r.planned_advance,
            "executed_advance": advance, "planning_seconds": r.planning_seconds,
            "simulated_seconds": r.simulated_seconds, "simulation_wall_seconds": r.simulation_wall_seconds}


def _rock_patches(ax, rocks, side: bool = False, **kw):
    from matplotlib.patches import Polygon, Rectangle

    for rk in rocks:
        c, h = np.asarray(rk.centre), np.asarray(rk.half_extents)
        if side:  # x–z: the box's x extent over its yawed footprint
            cy, sy = abs(np.cos(rk.yaw)), abs(np.sin(rk.yaw))
            hx = cy * h[0] + sy * h[1]
            ax.add_patch(Rectangle((c[0] - hx, 0.0), 2 * hx, 2 * h[2], **kw))
            continue
        R = np.array([[np.cos(rk.yaw), -np.sin(rk.yaw)], [np.sin(rk.yaw), np.cos(rk.yaw)]])
        corners = (R @ (np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * h[:2]).T).T + c[:2]
        ax.add_patch(Polygon(corners, closed=True, **kw))


def plot_maps(model, r: WS.FootfallCycleResult, rocks, path: Path) -> None:
    """One panel per step: the leg's stability map (stable green, unstable red, unreachable blank,
    §3.3), the rocks, the feet, the gait's nominal foothold (x) and the chosen one (star)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    n = len(r.steps)
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.6 * rows), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for k, (s, ax) in enumerate(zip(r.steps, axes.ravel())):
        a = F.map_arrays(s.map)
        x, y = a["x"], a["y"]
        colour = np.ma.masked_equal(a["status"].astype(float), 0.0)
        ax.imshow(colour.T, origin="lower", extent=(x[0], x[-1], y[0], y[-1]), interpolation="nearest",
                  cmap=ListedColormap(["#d62728", "#2ca02c"]), vmin=1, vmax=2, alpha=0.55)
        _rock_patches(ax, rocks, facecolor="0.35", edgecolor="k", lw=0.5)
        p = s.plan
        ax.plot(*np.asarray(s.nominal_goal), "kx", ms=9, mew=2, label="nominal foothold")
        if p.solved:
            ax.plot(*np.asarray(p.goal)[:2], "*", color="gold", mec="k", ms=15, label="chosen foothold")
            w = np.asarray(s.planned_wheel)
            ax.plot(w[0], w[1], "b-", lw=1, label="planned wheel path")
        ax.plot(*np.asarray(s.map.hip)[:2], "b^", ms=7, label="hip")
        ax.set_xlim(x[0] - 0.3, x[-1] + 0.3)
        ax.set_ylim(y[0] - 0.3, y[-1] + 0.3)
        ax.set_aspect("equal")
        crit = "NESM" if s.map.nesm else "SSM"
        ax.set_title(f"step {k + 1}: leg {s.leg} ({crit}; {s.map_seconds:.2f} s)", fontsize=10)
        if k == 0:
            ax.legend(fontsize=7, loc="lower left")
    fig.suptitle("FootFall stability maps per step (§3.3): green stable, red unstable, blank unreachable; "
                 "grey boxes rocks")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def animate(model, r: WS.FootfallCycleResult, rocks, path: Path, frames: int = 60, fps: int = 8) -> int:
    """GIF of the executed cycle: the walker's links as lines over the rocks, top view (x–y) and
    side view (x–z), with each step's planned (dashed) and executed (solid) wheel path. Returns the
    number of frames written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    t = np.asarray(r.frame_time)
    if t.size == 0:
        raise ValueError("animate: the result has no frames (set execution.frame_interval)")
    pick = np.unique(np.linspace(0, t.size - 1, min(frames, t.size)).round().astype(int))
    bodies, qs = r.frame_body, r.frame_q
    fig, (top, side) = plt.subplots(1, 2, figsize=(10, 4.4), gridspec_kw={"width_ratios": [1.25, 1]})
    _rock_patches(top, rocks, facecolor="0.55", edgecolor="k", lw=0.5)
    _rock_patches(side, rocks, side=True, facecolor="0.55", edgecolor="none", alpha=0.5)
    for s in r.steps:
        if not s.plan.solved:
            continue
        pw, ew = np.asarray(s.planned_wheel), np.asarray(s.executed_wheel)
        for ax, (i, j) in ((top, (0, 1)), (side, (0, 2))):
            ax.plot(pw[i], pw[j], "b--", lw=0.8)
            ax.plot(ew[i], ew[j], "g-", lw=0.9)
    top.plot([], [], "b--", label="planned wheel path")
    top.plot([], [], "g-", label="executed")
    top.legend(fontsize=7, loc="lower left")
    top.set(xlim=(-2.9, 3.4), ylim=(-2.8, 2.8), aspect="equal", xlabel="x [m]", ylabel="y [m]")
    side.set(xlim=(-2.9, 3.4), ylim=(-0.1, 2.4), aspect="equal", xlabel="x [m]", ylabel="z [m]")
    side.axhline(0.0, color="k", lw=0.8)
    lines_top = [top.plot([], [], "-", color="C3", lw=2)[0] for _ in range(model.legs * model.joints_per_leg)]
    lines_side = [side.plot([], [], "-", color="C3", lw=2)[0] for _ in range(model.legs * model.joints_per_leg)]
    chassis_top, = top.plot([], [], "k-", lw=1.5)
    chassis_side, = side.plot([], [], "k-", lw=1.5)
    title = fig.suptitle("")
    hips = np.array([np.asarray(model.hip_mount(k))[:3, 3] for k in range(model.legs)] + [
        np.asarray(model.hip_mount(0))[:3, 3]]).T

    def draw(i):
        b, q = np.asarray(bodies[pick[i]]), np.asarray(qs[pick[i]])
        caps = model.capsules(b, q)
        for ln_t, ln_s, c in zip(lines_top, lines_side, caps):
            p0, p1 = np.asarray(c.p0), np.asarray(c.p1)
            ln_t.set_data([p0[0], p1[0]], [p0[1], p1[1]])
            ln_s.set_data([p0[0], p1[0]], [p0[2], p1[2]])
        h = b[:3, :3] @ hips + b[:3, 3:4]
        chassis_top.set_data(h[0], h[1])
        chassis_side.set_data(h[0], h[2])
        title.set_text(f"FootFall gait cycle executed in ODE, t = {t[pick[i]]:.1f} s")
        return [*lines_top, *lines_side, chassis_top, chassis_side, title]

    fig.tight_layout()
    anim = FuncAnimation(fig, draw, frames=len(pick), blit=False)
    anim.save(str(path), writer=PillowWriter(fps=fps), dpi=75)
    plt.close(fig)
    return len(pick)


def demo(out_dir, seed: int = 3, cell: float = 0.02, rocks: int = 60, variants: bool = True, log=print,
         terrain=None, flat_tolerance: float | None = None) -> dict:
    """The cycle with sag compensation (maps, animation) and, with ``variants``, the same world
    with it off and the compensated cycle again at a quarter of the physics step. ``terrain``: the
    planner's HeightMap (default: the rocks rasterised). Writes footfall_cycle_maps.png and
    footfall_cycle.gif; returns the figures (and, under ``_result``, ``_model``, ``_terrain``, the
    compensated cycle's objects)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    model = W.WalkerModel(W.sdm_b_parameters())
    boxes, rasterised, _ = rock_world(model, seed=seed, rocks=rocks)
    terrain = rasterised if terrain is None else terrain
    cases = [("compensated", dict(frame_interval=0.25))]
    if variants:
        cases += [("uncompensated", dict(sag_compensation=False)),
                  ("compensated_quarter_dt", dict(dt=WS.WalkerSimOptions().dt / 4))]
    runs = {}
    for name, kw in cases:
        t0 = time.perf_counter()
        r = run(model, terrain, boxes, cycle_options(cell=cell, seed=seed, flat_tolerance=flat_tolerance, **kw))
        runs[name] = (r, summary(r), time.perf_counter() - t0)
        s = runs[name][1]
        log(f"[footfall] cycle ({name}): {'completed' if s['completed'] else 'stopped: ' + s['reason']}, "
            f"min wheel-rock clearance {100 * s['min_rock_clearance']:.1f} cm, body advance "
            f"{s['executed_advance']:.3f} m (planned {s['planned_advance']:.3f}), {runs[name][2]:.1f} s")
        if name == "compensated":
            for k, st in enumerate(s["steps"]):
                log(f"[footfall]   step {k + 1} leg {st['leg']}: map {st['map_seconds']:.2f} s, "
                    + (f"plan {1e3 * st['plan_seconds']:.0f} ms, smooth {1e3 * st['smooth_seconds']:.0f} ms, length "
                       f"{st['raw_length']:.2f} -> {st['smoothed_length']:.2f} rad, clearance planned "
                       f"{100 * st['planned_clearance']:.1f} / executed {100 * st['executed_swing_clearance']:.1f} cm"
                       if st["solved"] else f"no plan: {st['reason']}"))
    r = runs["compensated"][0]
    t0 = time.perf_counter()
    plot_maps(model, r, boxes, out / "footfall_cycle_maps.png")
    frames = 0
    if len(r.frame_time):
        frames = animate(model, r, boxes, out / "footfall_cycle.gif")
        log(f"[footfall] cycle figures: maps and a {frames}-frame GIF ({time.perf_counter() - t0:.1f} s)")
    else:  # the cycle stopped before its first step: nothing was executed to animate
        (out / "footfall_cycle.gif").unlink(missing_ok=True)
        log(f"[footfall] cycle figures: maps only, no GIF (nothing executed) ({time.perf_counter() - t0:.1f} s)")
    result = {name: v[1] | {"wall_seconds": v[2]} for name, v in runs.items()}
    result.update(rocks=len(boxes), seed=seed, cell=cell, dt=WS.WalkerSimOptions().dt, stride=STRIDE,
                  gif_bytes=(out / "footfall_cycle.gif").stat().st_size if frames else 0, gif_frames=frames)
    result.update(_result=r, _model=model, _terrain=terrain)
    return result
