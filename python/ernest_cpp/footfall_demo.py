"""``ernest footfall``: a full FootFall gait cycle of SDM-B around rocks, as at D-RATS 2010 (seed
003 §6, Fig. 19), planned and executed in the ODE walker (``footfall_cycle``): for each leg in the
reverse-wave order (§5.3.1) its stability map (§3.3), the gait's nominal foothold moved to the
nearest stable rock-free cell, the sag predicted with the leg in the air (§4.1, §5.1), SBL between
the compliance waypoints against that sagged pose (§3.4.1), the Dijkstra–bisection smoothing
(§3.4.2), the swing and a body shift executed under joint position control with every wheel's
clearance to every rock measured; an animation (GIF). The cycle is rerun with sag compensation off
and at a quarter of the physics step. Then the gait planner's skeleton gait on flat ground and the
Moses Lake lesson (§4.1, ``footfall_gait``), and self-imaging, the raised leg removed from the
hazard camera's depth map by watershed (§4.3, §5.2; ``perception_selfimage``). Writes
footfall.json and footfall_report.md."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from . import _args
from . import footfall as F
from . import footfall_terrain


#: relief allowed around a foothold on a stereo-derived map [m] (FootfallCycleOptions.flat_tolerance)
STEREO_FLAT_TOLERANCE = 0.05


def run(out: Path, seed: int = 3, cell: float = 0.02, rocks: int = 60, variants: bool = True, log=print,
        terrain=None, terrain_source: str = "truth", record: bool = False) -> dict:
    """The executed gait cycle around rocks (``footfall_cycle``), the skeleton gait and the Moses
    Lake scenario (``footfall_gait``) and self-imaging (``perception_selfimage``). ``terrain``: the
    planner's HeightMap (default: the rocks rasterised, or with ``terrain_source="stereo"`` the
    stereo-fused map of them seen from the start pose, ``footfall_terrain``); ``variants``: also
    run the cycle with sag compensation off and at a quarter of the physics step. The simulator
    always collides with the rocks themselves. ``record``: also write the executed cycle as a 3D
    recording, ``out/footfall_cycle.npz`` (``ernest view``: legs, support polygon, each step's
    stability map and planned leg path)."""
    if terrain_source not in footfall_terrain.SOURCES:
        raise ValueError(f"terrain_source must be one of {footfall_terrain.SOURCES}, got {terrain_source!r}")
    out.mkdir(parents=True, exist_ok=True)
    t_all = time.perf_counter()
    from . import footfall_cycle
    from . import walker as W

    flat_tolerance = None  # the cycle's default (1 mm): exact on the rasterised rocks
    if terrain is None and terrain_source != "truth":
        log(f"[footfall] the planner's terrain from {terrain_source}: mast stereo pan over the rocks ...")
        walker = W.WalkerModel(W.sdm_b_parameters())
        _, truth, _ = footfall_cycle.rock_world(walker, seed=seed, rocks=rocks)
        terrain = footfall_terrain.planner_terrain(terrain_source, truth,
                                                   np.asarray(walker.standard_body_pose()))
        # a stereo map is never flat to 1 mm (its noise, raised by k sigma); the rocks stand
        # 10-45 cm, so 5 cm of relief around a foothold still means no rock under the wheel
        flat_tolerance = STEREO_FLAT_TOLERANCE

    cycle = footfall_cycle.demo(out, seed=seed, cell=cell, rocks=rocks, variants=variants, log=log, terrain=terrain,
                                flat_tolerance=flat_tolerance)
    r, model, planner_terrain = cycle.pop("_result"), cycle.pop("_model"), cycle.pop("_terrain")
    if record:
        _record(out, model, r, planner_terrain, seed, rocks, log)
    for k, s in enumerate(r.steps):
        if s.plan.solved:
            F.plot_leg_path(model, planner_terrain, s.plan, s.leg, out / f"step{k + 1}_leg{s.leg}_path.png",
                            f"step {k + 1}, leg {s.leg}: planned (SBL) and smoothed paths")
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
    log("[footfall] torque-aware footholds: the cycle planned by today's and the torque-aware planner (§7.1) ...")
    from . import footfall_torque

    torque = footfall_torque.demo(out, seed=seed, cell=cell, rocks=rocks, log=log)
    result = {"cycle": cycle, "gait": gait, "selfimage": selfimage, "torque": torque, "seed": seed, "cell_m": cell,
              "rocks": rocks, "seconds": time.perf_counter() - t_all}
    (out / "footfall.json").write_text(json.dumps(result, indent=2))
    _report(out, result)
    return result


def _record(out: Path, model, r, terrain, seed: int, rocks: int, log) -> None:
    from . import footfall_cycle
    from .viewer import save_recording
    from .viewer.walker import cycle_recording

    if not len(r.frame_time):
        log("[footfall] no 3D recording: the cycle stopped before its first step")
        return
    boxes, _, _ = footfall_cycle.rock_world(model, seed=seed, rocks=rocks)  # the cycle's rocks
    path = save_recording(cycle_recording(model, r, boxes, terrain, seed=seed),
                          str(out / "footfall_cycle.npz"))
    log(f"[footfall] 3D recording of the executed cycle -> {path} (ernest view {path})")


def _report(out: Path, r: dict) -> None:
    c = r["cycle"]
    m = c["compensated"]
    lines = ["# FootFall: a gait cycle around rocks, planned and executed (seed 003 §3–6, Fig. 19)", "",
             f"SDM-B, {c['rocks']} box rocks (the simulator's boxes, rasterised into the planner's height map), "
             f"stride {c['stride']} m, map cells {100 * r['cell_m']:.0f} cm, seed {r['seed']}, physics step "
             f"{1e3 * c['dt']:.2f} ms; total {r['seconds']:.1f} s. Reverse-wave order, a body shift of stride/6 "
             "after each step; each swing planned against the stance's predicted sag (§4.1, §5.1), executed in "
             "ODE under joint position control.", "",
             "| step | leg | map [s] | stable / unstable cells | foothold moved [cm] | swing-hip sag [cm] | SBL [ms] | "
             "smoothing [ms] | length SBL → smoothed [rad] | swing clearance planned / executed [cm] | "
             "every wheel [cm] |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for k, s in enumerate(m["steps"]):
        row = f"| {k + 1} | {s['leg']} | {s['map_seconds']:.2f} | {s['stable_cells']} / {s['unstable_cells']} | "
        if s["solved"]:
            row += (f"{100 * s['goal_offset']:.1f} | {100 * s['swing_hip_sag']:.1f} | {1e3 * s['plan_seconds']:.0f} | "
                    f"{1e3 * s['smooth_seconds']:.0f} | {s['raw_length']:.2f} → {s['smoothed_length']:.2f} | "
                    f"{100 * s['planned_clearance']:.1f} / {100 * s['executed_swing_clearance']:.1f} | "
                    f"{100 * s['min_rock_clearance']:.1f} |")
        else:
            row += f"– | – | – | – | – | – | no plan: {s['reason']} |"
        lines.append(row)
    lines += ["", "| run | completed | min wheel–rock clearance [cm] | body advance executed / planned [m] | wall [s] |",
              "|---|---|---|---|---|"]
    for name in ("compensated", "uncompensated", "compensated_quarter_dt"):
        if name in c:
            v = c[name]
            lines.append(f"| {name.replace('_', ' ')} | {v['completed']} | {100 * v['min_rock_clearance']:.2f} | "
                         f"{v['executed_advance']:.4f} / {v['planned_advance']:.4f} | {v['wall_seconds']:.1f} |")
    if "uncompensated" in c and "compensated_quarter_dt" in c:
        lines += ["", "Per step, executed: the swing wheel's clearance to the rocks and its lowest point over the "
                  "ground between the compliance waypoints (planned 20 cm above it) [cm]:", "",
                  "| step | leg | rocks: compensated / without sag compensation / compensated at dt/4 | "
                  "ground: compensated / without / dt/4 |", "|---|---|---|---|"]
        for k, (a, b, q) in enumerate(zip(m["steps"], c["uncompensated"]["steps"], c["compensated_quarter_dt"]["steps"])):
            if a["solved"] and b["solved"] and q["solved"]:
                lines.append(f"| {k + 1} | {a['leg']} | {100 * a['executed_swing_clearance']:.1f} / "
                             f"{100 * b['executed_swing_clearance']:.1f} / {100 * q['executed_swing_clearance']:.1f} | "
                             f"{100 * a['transfer_ground_clearance']:.1f} / {100 * b['transfer_ground_clearance']:.1f} / "
                             f"{100 * q['transfer_ground_clearance']:.1f} |")
    gif = " ![cycle](footfall_cycle.gif)" if c["gif_frames"] else " (stopped before any step: no animation)"
    lines += ["", "![maps](footfall_cycle_maps.png)" + gif, ""]
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
    from . import footfall_torque

    lines += footfall_torque.report_lines(r["torque"])
    si = r["selfimage"]
    lines += ["## Self-imaging (§4.3, §5.2)", "",
              f"A raised leg seen by the hazard camera, removed by watershed segmentation of the depth map before "
              f"fusion: intersection over union with the rendered leg {si['min_iou']:.3f} or better on "
              f"{len(si['poses'])} poses; the map under the leg stands up to {100 * si['false_obstacle_before_m']:.0f} cm "
              f"above the ground without the removal, {100 * si['false_obstacle_after_m']:.1f} cm with it. "
              "![self-imaging](selfimage.png)", ""]
    for k, s in enumerate(m["steps"]):
        if s["solved"]:
            lines.append(f"![step {k + 1}](step{k + 1}_leg{s['leg']}_path.png)")
    (out / "footfall_report.md").write_text("\n".join(lines) + "\n")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("footfall", help="seed 003 §3–6: a FootFall gait cycle around rocks, executed in ODE",
                       description=__doc__)
    p.add_argument("--out", type=Path, default=Path("out/footfall"))
    p.add_argument("--seed", type=_args.seed, default=3, help="rock field and planner seed")
    p.add_argument("--cell", type=_args.in_range(0.005, 0.5), default=0.02,
                   help="stability map cell [m], 0.005 to 0.5")
    p.add_argument("--rocks", type=_args.in_range(0, 10**6, int), default=60)
    p.add_argument("--terrain", choices=footfall_terrain.SOURCES, default="truth",
                   help="planner's DEM: the simulator's ground truth or the stereo-fused map")
    p.add_argument("--no-variants", dest="variants", action="store_false",
                   help="skip the cycle without sag compensation and the one at a quarter of the physics step")
    p.add_argument("--record", action="store_true",
                   help="also write the executed cycle as a 3D recording, OUT/footfall_cycle.npz (ernest view)")
    p.set_defaults(func=_main)


def _main(args: argparse.Namespace) -> int:
    r = run(args.out, args.seed, args.cell, args.rocks, args.variants, terrain_source=args.terrain,
            record=args.record)
    c = r["cycle"]["compensated"]
    gif = "footfall_cycle.gif and " if r["cycle"]["gif_frames"] else ""
    print(f"wrote {args.out}/footfall_report.md, footfall.json, {gif}"
          f"{len(list(args.out.glob('*.png')))} PNGs (cycle {'completed' if c['completed'] else 'stopped'}, "
          f"min wheel-rock clearance {100 * c['min_rock_clearance']:.1f} cm, {r['seconds']:.1f} s)")
    return 0


def main(**options) -> int:
    """``ernest footfall`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest footfall --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/footfall")``. Returns the exit status; errors raise."""
    from .cli import run

    return run("footfall", **options)
