"""``ernest footfall``: a gait-cycle-like sequence of single-leg steps of SDM-B through a rock
field, as at D-RATS 2010 (seed 003 §6, Fig. 19), with FootFall's planning core: for each step the
stability map of the leg (§3.3, PNG), the goal (the stable cell nearest a stride ahead), the sag
predicted with the leg in the air (§4.1, §5.1), SBL between the compliance waypoints against that
sagged pose (§3.4.1), the Dijkstra–bisection smoothing (§3.4.2, PNG), then a body shift over the
planted feet; the legs step in the reverse-wave order of the gait planner (§5.3.1). Then the gait
planner's skeleton gait on flat ground and, in the ODE walker simulator, the Moses Lake lesson
(§4.1): a swing planned against the rigid pose hits a rock, one planned against the sag model's
pose clears it (``footfall_gait``); and self-imaging, the raised leg removed from the hazard
camera's depth map by watershed (§4.3, §5.2; ``perception_selfimage``). Writes footfall.json and
footfall_report.md."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from . import footfall as F
from . import footfall_terrain
from . import walker as W


def _stance_q(model, terrain, body, feet, q, mo):
    """Joint angles putting every foot on its ground point for a body pose (IK per leg)."""
    out = np.array(q, dtype=float)
    for k in range(model.legs):
        e = F.StabilityMapper(model, terrain, body, out, k, mo).evaluate(feet[0, k], feet[1, k], out[:, k])
        if e.status == F.CellStatus.Unreachable:
            raise RuntimeError(f"body shift: leg {k} cannot reach its foot")
        out[:, k] = e.q
    return out


def _goal_cell(arrays, target):
    """The stable cell nearest the target point (x, y), or None."""
    st = arrays["status"]
    ii, jj = np.nonzero(st == int(F.CellStatus.Stable))
    if ii.size == 0:
        return None
    xs, ys = arrays["x"][ii], arrays["y"][jj]
    order = np.argsort((xs - target[0]) ** 2 + (ys - target[1]) ** 2)
    return [(float(xs[k]), float(ys[k])) for k in order[:40:4]]


#: CPS margin a goal must keep [m]: our choice (the paper gives no number); on six feet every
#: reachable cell has 0.45–1.0 m, so 0.7 m shows both colours (feet pulled in turn red).
MIN_MARGIN = 0.7


def run(out: Path, steps: int = 6, stride: float = 0.4, seed: int = 3, cell: float = 0.02,
        rocks: int = 40, log=print, terrain_source: str = "truth") -> dict:
    out.mkdir(parents=True, exist_ok=True)
    model = W.WalkerModel(W.sdm_b_parameters())
    # one cycle walking along +x: the gait planner's reverse wave (§5.3.1; front to rear, left of
    # the direction of travel first)
    order = tuple(W.reverse_wave_sequence(model, 0.0))
    body = np.array(model.standard_body_pose())
    q = np.array(model.standard_configuration)
    feet = np.array(model.contact_points(body, q))
    keep = np.hstack([feet[:2], feet[:2] + np.array([[stride], [0.0]]), feet[:2] + np.array([[2 * stride], [0.0]])])
    ro = F.RockFieldOptions()
    ro.rocks, ro.seed, ro.length, ro.centre_x, ro.keep_clear, ro.inner_radius = rocks, seed, 10.0, 1.0, 0.45, 1.4
    ro.max_height = 0.5
    truth = F.rock_field(ro, keep)  # the simulator's terrain
    # the planner's DEM: the ground truth, or stereo -> fused map (footfall_terrain)
    terrain = footfall_terrain.planner_terrain(terrain_source, truth, body)
    mo = F.StabilityMapOptions()
    mo.cell = cell
    mo.min_margin = MIN_MARGIN
    so = F.StepOptions()
    so.map = mo
    so.planner.seed = seed
    so.planner.time_limit = 2.0
    rows = []
    t_all = time.perf_counter()
    for k in range(steps):
        leg = order[k % len(order)]
        t0 = time.perf_counter()
        arrays = F.stability_map(model, terrain, body, q, leg, mo)
        t_map = time.perf_counter() - t0
        target = feet[:2, leg] + np.array([stride, 0.0])
        step, goal = None, None
        for g in _goal_cell(arrays, target) or []:
            step = F.plan_step(model, terrain, body, q, leg, g[0], g[1], so)
            goal = g
            if step.solved:
                break
        row = {"step": k + 1, "leg": leg, "map_seconds": t_map, "stable_cells": int(arrays["map"].count(F.CellStatus.Stable)),
               "unstable_cells": int(arrays["map"].count(F.CellStatus.Unstable)), "criterion": "NESM" if arrays["nesm"] else "SSM",
               "target": target.tolist(), "goal": list(goal) if goal else None,
               "solved": bool(step is not None and step.solved), "reason": step.reason if step else "no stable cell"}
        name = f"step{k + 1}_leg{leg}"
        F.plot_stability_map(arrays, out / f"{name}_map.png", terrain, feet, goal,
                             f"step {k + 1}, leg {leg}: stability map ({row['criterion']} of the CPS)")
        if step is not None and step.sag.status.name == "Converged":
            # §4.1's lesson: the waypoint above the start planned on the rigid pose, placed in the
            # sagged pose the robot really takes, leaves the wheel this high above the ground.
            rigid_up = F.StabilityMapper(model, terrain, body, q, leg, mo).start_above
            c = (step.sag.sagged_body @ np.append(model.contact_point(leg, rigid_up), 1.0))[:3]
            row.update(hip_sag_cm=100 * float(-step.sag.hip_displacement[2]),
                       body_drop_cm=100 * float(body[2, 3] - step.sag.sagged_body[2, 3]),
                       body_tilt_deg=math.degrees(math.acos(min(1.0, float(step.sag.sagged_body[2, 2])))),
                       rigid_plan_lift_cm=100 * float(c[2] - terrain.height(c[0], c[1])))
        if row["solved"]:
            row.update(plan_ms=1e3 * step.plan.seconds, smooth_ms=1e3 * step.smoothing.seconds,
                       raw_length=step.plan.length, smoothed_length=step.smoothing.length,
                       raw_nodes=int(step.plan.path.shape[1]), smoothed_nodes=int(step.smoothing.path.shape[1]),
                       margin_cm=100 * step.goal_margin)
            F.plot_leg_path(model, terrain, step, leg, out / f"{name}_path.png",
                            f"step {k + 1}, leg {leg}: planned (SBL) and smoothed paths")
            q = np.array(q)
            q[:, leg] = step.q_goal
            feet = np.array(model.contact_points(body, q))
        log(f"[footfall] step {k + 1}/{steps} leg {leg}: map {t_map:.2f} s, "
            + (f"plan {row['plan_ms']:.0f} ms, smooth {row['smooth_ms']:.0f} ms, length "
               f"{row['raw_length']:.2f} -> {row['smoothed_length']:.2f} rad, swing-hip sag {row['hip_sag_cm']:.1f} cm"
               if row["solved"] else f"no plan: {row['reason']}"))
        rows.append(row)
        if (k + 1) % len(order) == 0:  # every foot moved: shift the body over them
            body = body.copy()
            body[0, 3] += stride
            q = _stance_q(model, terrain, body, feet, q, mo)
            log(f"[footfall] body shift +{stride:.2f} m")
    log("[footfall] gait plan on flat ground (§5.3.1) and the Moses Lake scenario in ODE (§4.1) ...")
    from . import footfall_gait

    t0 = time.perf_counter()
    gait = footfall_gait.demo(out)
    steps_m = np.asarray(gait["step_lengths"])
    log(f"[footfall] gait: steps {steps_m.min():.3f}..{steps_m.max():.3f} m, "
        f"rigid plan executed clearance {100 * gait['rigid_executed_clearance']:.1f} cm, compensated "
        f"{100 * gait['compensated_executed_clearance']:.1f} cm ({time.perf_counter() - t0:.1f} s)")
    log("[footfall] self-imaging: the raised leg in the hazard camera's depth map, removed by watershed (§4.3, §5.2) ...")
    from . import perception_selfimage

    t0 = time.perf_counter()
    selfimage = perception_selfimage.demo(str(out), seed=seed)
    log(f"[footfall] self-imaging: IoU >= {selfimage['min_iou']:.3f} on {len(selfimage['poses'])} poses, false obstacle "
        f"{100 * selfimage['false_obstacle_before_m']:.0f} cm -> {100 * selfimage['false_obstacle_after_m']:.1f} cm "
        f"({time.perf_counter() - t0:.1f} s)")
    result = {"steps": rows, "stride_m": stride, "lift_m": mo.lift_height, "min_margin_m": mo.min_margin, "seed": seed, "cell_m": cell, "rocks": rocks,
              "gait": gait, "selfimage": selfimage, "seconds": time.perf_counter() - t_all}
    (out / "footfall.json").write_text(json.dumps(result, indent=2))
    _report(out, result)
    return result


def _report(out: Path, r: dict) -> None:
    lines = ["# FootFall: single-leg steps through a rock field (seed 003 §3.3–3.4, §4.1, §5.1, §6)", "",
             f"SDM-B, {r['rocks']} rocks, stride {r['stride_m']} m, map cells {100 * r['cell_m']:.0f} cm, "
             f"seed {r['seed']}; total {r['seconds']:.1f} s. A goal is stable when the SSM of the CPS "
             f"after the step exceeds {100 * r['min_margin_m']:.0f} cm (our threshold; the paper gives none).", "",
             "| step | leg | map [s] | stable / unstable cells | goal margin [cm] | swing-hip sag [cm] | "
             "lift left by a rigid plan [cm] | SBL [ms] | smoothing [ms] | length SBL → smoothed [rad] | nodes | result |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in r["steps"]:
        ok = s["solved"]
        lines.append(
            f"| {s['step']} | {s['leg']} | {s['map_seconds']:.2f} | {s['stable_cells']} / {s['unstable_cells']} | "
            + (f"{s['margin_cm']:.1f} | " if ok else "– | ")
            + (f"{s['hip_sag_cm']:.1f} | {s['rigid_plan_lift_cm']:.1f} | " if "hip_sag_cm" in s else "– | – | ")
            + (f"{s['plan_ms']:.0f} | {s['smooth_ms']:.0f} | {s['raw_length']:.2f} → {s['smoothed_length']:.2f} | "
               f"{s['raw_nodes']} → {s['smoothed_nodes']} | solved |" if ok else f"– | – | – | – | {s['reason']} |"))
    lines += ["", f"The waypoints above start and goal lift the wheel {100 * r['lift_m']:.0f} cm over the ground in the "
              "sagged pose the compliance model predicts (§4.1, §5.1); 'lift left by a rigid plan' is what a "
              "waypoint planned on the unsagged pose leaves once the robot sags.", "",
              "Maps: green stable, red unstable, uncoloured unreachable (§3.3). Paths: the wheel "
              "centre's track over the terrain under the step, SBL's plan against the sagged pose and "
              "the smoothed one through the compliance waypoints above start and goal.", ""]
    g = r["gait"]
    lines += ["## Skeleton gait and execution in simulation (§5.3.1, §4.1)", "",
              f"Reverse-wave order {g['sequence']} on flat ground, {len(g['step_lengths'])} cycles: step lengths "
              f"{np.min(g['step_lengths']):.3f}–{np.max(g['step_lengths']):.3f} m, body shifts "
              f"{np.min(g['shift_lengths']):.3f}–{np.max(g['shift_lengths']):.3f} m, smallest support margin "
              f"{g['min_support_margin']:.3f} m, planned in {g['gait_plan_seconds']:.2f} s"
              + (f"; periodic after the second cycle to {1e3 * g['periodicity_error']:.2f} mm." if g['periodicity_error'] == g['periodicity_error'] else "."), "",
              "The same swing over a rock, executed in the ODE walker (compliant wheels, eq 3):", "",
              "| plan made against | lift [cm] | clearance on paper [cm] | clearance executed [cm] |", "|---|---|---|---|",
              f"| the rigid pose | {100 * g['rigid_lift']:.1f} | {100 * g['rigid_planned_clearance']:.2f} | "
              f"{100 * g['rigid_executed_clearance']:.2f} |",
              f"| the sag model's pose | {100 * g['compensated_lift']:.1f} | {100 * g['compensated_planned_clearance']:.2f} | "
              f"{100 * g['compensated_executed_clearance']:.2f} |", "",
              f"Simulator sag vs the sag model: {1e3 * g['sag_error_six']:.2f} mm (six feet down), "
              f"{1e3 * g['sag_error_lifted']:.2f} mm (leg lifted). ![gait](footfall_gait.png)", ""]
    si = r["selfimage"]
    lines += ["## Self-imaging (§4.3, §5.2)", "",
              f"A raised leg seen by the hazard camera, removed by watershed segmentation of the depth map before "
              f"fusion: intersection over union with the rendered leg {si['min_iou']:.3f} or better on "
              f"{len(si['poses'])} poses; the map under the leg stands up to {100 * si['false_obstacle_before_m']:.0f} cm "
              f"above the ground without the removal, {100 * si['false_obstacle_after_m']:.1f} cm with it. "
              "![self-imaging](selfimage.png)", ""]
    for s in r["steps"]:
        name = f"step{s['step']}_leg{s['leg']}"
        lines.append(f"![{name} map]({name}_map.png)")
        if s["solved"]:
            lines.append(f"![{name} path]({name}_path.png)")
    (out / "footfall_report.md").write_text("\n".join(lines) + "\n")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("footfall", help="seed 003 §3–6: FootFall single-leg steps through rocks",
                       description=__doc__)
    p.add_argument("--out", type=Path, default=Path("out/footfall"))
    p.add_argument("--steps", type=int, default=6, help="leg steps (6 = one cycle, then a body shift)")
    p.add_argument("--stride", type=float, default=0.4, help="step length [m]")
    p.add_argument("--seed", type=int, default=3, help="rock field and planner seed")
    p.add_argument("--cell", type=float, default=0.02, help="stability map cell [m]")
    p.add_argument("--rocks", type=int, default=40)
    p.add_argument("--terrain", choices=footfall_terrain.SOURCES, default="truth",
                   help="planner's DEM: the simulator's ground truth or the stereo-fused map")
    p.set_defaults(func=_main)


def _main(args: argparse.Namespace) -> int:
    if args.steps < 1 or not (0.0 < args.stride < 2.0):
        raise SystemExit("ernest footfall: need --steps >= 1 and 0 < --stride < 2")
    r = run(args.out, args.steps, args.stride, args.seed, args.cell, args.rocks, terrain_source=args.terrain)
    solved = sum(s["solved"] for s in r["steps"])
    print(f"wrote {args.out}/footfall_report.md, footfall.json and {len(list(args.out.glob('*.png')))} PNGs "
          f"({solved}/{len(r['steps'])} steps planned, {r['seconds']:.1f} s)")
    return 0
