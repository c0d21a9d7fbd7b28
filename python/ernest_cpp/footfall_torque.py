"""Torque-aware footholds on the rock-field gait cycle (seed 003 §7.1: "footfalls would be
identified which were reachable and safely kept the CG within the polygon of support, but which
violated joint-torque limits"). The cycle of ``footfall_cycle`` is planned (not executed) twice on
the same rocks: with today's planner, every foothold's peak static joint torque evaluated (the
stance after the step and the stance during it with the leg above the foothold, zero-interaction
loads, ``StabilityMapOptions.torques``), and with the torque-aware planner, which refuses cells over
``max_saturation`` of a joint's limit (``CellStatus.Overloaded``). Reported per step: the peak
torque of the chosen foothold and along the swing, and the step length along the heading. A second
pair with a payload on the chassis shows the regime where lifting the leg itself saturates a joint.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from . import footfall as F
from . import walker as W
from . import walker_sim as WS

#: Chosen torque margin for the nominal robot: refuse footholds and swings above 88 % of a joint's
#: limit (today's cycle peaks at 0.885; its legs lift off at up to 0.87, which no foothold lowers).
MAX_SATURATION = 0.88
#: Payload on the chassis for the saturating case [kg] (SDM-B "was over-weight for its motors", §7.1).
PAYLOAD = 250.0


def plan_cycle(model, terrain, rocks, max_saturation: float = math.inf, cell: float = 0.02, seed: int = 3) -> dict:
    """One planned-only gait cycle (``FootfallCycleOptions.execute = False``) with every foothold's
    peak joint torque evaluated; ``max_saturation`` < inf makes it torque-aware. Per step: leg,
    solved, peak torque fractions (goal: after/during the step at the foothold; path: the swing),
    the step length along the heading [m] and the foothold's distance from the nominal one [m]."""
    from . import footfall_cycle as FC

    o = WS.FootfallCycleOptions()
    o.stride = FC.STRIDE
    o.step.map.cell = cell
    o.step.map.min_margin = FC.MIN_MARGIN
    o.step.map.torques = True
    o.step.map.max_saturation = max_saturation
    if max_saturation < math.inf:  # the torque-aware planner also smooths for the peak torque
        o.step.smoothing.objective = F.SmoothingObjective.PeakTorque
    o.step.planner.seed = seed
    o.step.planner.time_limit = 2.0
    o.execute = False
    t0 = time.perf_counter()
    try:
        r = WS.run_footfall_cycle(model, terrain, rocks, o)
    except ValueError as e:  # a body shift the moved footholds no longer allow
        return {"completed": False, "reason": str(e), "steps": [], "seconds": time.perf_counter() - t0}
    d = np.array([math.cos(o.heading), math.sin(o.heading)])
    steps = []
    for s in r.steps:
        p = s.plan
        start = np.asarray(s.nominal_goal) - o.stride * d
        row = {"leg": s.leg, "solved": bool(p.solved), "reason": p.reason,
               "lift_saturation": float(s.map.lift_saturation),
               "overloaded_cells": int(s.map.count(F.CellStatus.Overloaded)),
               "stable_cells": int(s.map.count(F.CellStatus.Stable))}
        if p.solved:
            goal = np.asarray(p.goal)[:2]
            row.update(goal=goal.tolist(), goal_saturation=float(p.goal_saturation),
                       path_saturation=float(p.path_saturation), step_length=float((goal - start) @ d),
                       moved=float(np.linalg.norm(goal - np.asarray(s.nominal_goal))))
        steps.append(row)
    return {"completed": bool(r.completed), "reason": r.reason, "steps": steps,
            "seconds": time.perf_counter() - t0, "_result": r}


def _peaks(c: dict) -> list[float]:
    return [max(s["goal_saturation"], s["path_saturation"]) for s in c["steps"] if s["solved"]]


def summary(c: dict, limit: float) -> dict:
    """Footholds (with their swings) over ``limit``, peak and mean step length of a planned cycle."""
    peaks = _peaks(c)
    lengths = [s["step_length"] for s in c["steps"] if s["solved"]]
    return {"completed": c["completed"], "reason": c["reason"], "steps": len(lengths),
            "over_limit": int(sum(p > limit for p in peaks)), "peak": max(peaks) if peaks else float("nan"),
            "mean_step": float(np.mean(lengths)) if lengths else float("nan"),
            "min_step": float(np.min(lengths)) if lengths else float("nan"), "seconds": c["seconds"]}


def demo(out: Path, seed: int = 3, cell: float = 0.02, rocks: int = 60, log=print) -> dict:
    """The comparison on the rock field of ``footfall_cycle.rock_world`` (nominal mass at the 87 %
    margin, and with PAYLOAD kg at the torque limit itself); writes ``footfall_torque.png``."""
    from . import footfall_cycle as FC

    out.mkdir(parents=True, exist_ok=True)
    result = {"max_saturation": MAX_SATURATION, "payload_kg": PAYLOAD}
    cycles = {}
    for name, payload, limit in (("nominal", 0.0, MAX_SATURATION), ("payload", PAYLOAD, 1.0)):
        p = W.sdm_b_parameters()
        p.chassis_mass += payload
        model = W.WalkerModel(p)
        boxes, terrain, _ = FC.rock_world(model, seed=seed, rocks=rocks)
        today = plan_cycle(model, terrain, boxes, math.inf, cell, seed)
        aware = plan_cycle(model, terrain, boxes, limit, cell, seed)
        cycles[name] = (today, aware, limit)
        result[name] = {"limit": limit, "today": summary(today, limit), "torque_aware": summary(aware, limit),
                        "today_steps": today["steps"], "torque_aware_steps": aware["steps"]}
        t, a = result[name]["today"], result[name]["torque_aware"]
        log(f"[footfall] torque ({name}, limit {limit:.2f}): today's planner {t['over_limit']}/{t['steps']} footholds "
            f"over, peak {t['peak']:.3f}, mean step {t['mean_step']:.3f} m; torque-aware {a['over_limit']}/{a['steps']} "
            f"over, peak {a['peak']:.3f}, mean step {a['mean_step']:.3f} m"
            + ("" if a["completed"] else f" (stopped: {a['reason']})"))
    _plot(out / "footfall_torque.png", cycles)
    return result


def _plot(path: Path, cycles: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    for ax, name in zip(axes[:2], ("nominal", "payload")):
        today, aware, limit = cycles[name]
        legs = [s["leg"] for s in today["steps"]]
        x = np.arange(len(legs))
        for off, c, label in ((-0.2, today, "today's planner"), (0.2, aware, "torque-aware")):
            vals = [max(s["goal_saturation"], s["path_saturation"]) if s.get("solved") else np.nan for s in c["steps"]]
            vals += [np.nan] * (len(legs) - len(vals))
            ax.bar(x[: len(vals)] + off, vals[: len(legs)], width=0.4, label=label)
        ax.axhline(limit, color="k", ls="--", lw=1, label=f"max_saturation {limit:.2f}")
        ax.axhline(1.0, color="r", lw=1, label="torque limit")
        ax.set_xticks(x, [f"leg {leg}" for leg in legs])
        ax.set_ylabel("peak |tau| / limit (foothold and swing)")
        ax.set_title(f"{name}: peak joint torque per step" + (" (+%.0f kg)" % PAYLOAD if name == "payload" else ""))
        ax.legend(fontsize=7, loc="lower right")
    # The map of the first step where the two planners chose differently (nominal robot).
    today, aware, limit = cycles["nominal"]
    k = next((i for i, (a, b) in enumerate(zip(today["steps"], aware["steps"]))
              if a.get("goal") != b.get("goal")), 0)
    rec = today["_result"].steps[k]
    m = rec.map
    sat = np.asarray(m.saturation)
    status = np.asarray(m.status)
    nx, ny = sat.shape
    xs, ys = m.origin_x + m.cell * np.arange(nx), m.origin_y + m.cell * np.arange(ny)
    shown = np.ma.masked_where(status != 2, sat)
    ax = axes[2]
    im = ax.pcolormesh(xs, ys, shown.T, shading="nearest", cmap="viridis")
    over = np.ma.masked_where(~((status == 2) & (sat > limit)), np.ones_like(sat))
    ax.pcolormesh(xs, ys, over.T, shading="nearest", cmap="Reds", alpha=0.45, vmin=0, vmax=1)
    fig.colorbar(im, ax=ax, label="peak |tau| / limit")
    for c, mk, label in ((today, "*", "today's foothold"), (aware, "P", "torque-aware foothold")):
        if k < len(c["steps"]) and c["steps"][k].get("goal"):
            g = c["steps"][k]["goal"]
            ax.plot(g[0], g[1], mk, ms=13, mec="k", mfc="w", label=label)
    ax.plot(*np.asarray(rec.nominal_goal), "kx", ms=9, label="nominal foothold")
    ii, jj = np.nonzero(status == 2)
    if len(ii):
        ax.set_xlim(xs[ii].min() - 0.2, xs[ii].max() + 0.2)
        ax.set_ylim(ys[jj].min() - 0.2, ys[jj].max() + 0.2)
    ax.set_aspect("equal")
    ax.set_title(f"leg {rec.leg}: stable cells, peak torque (red > {limit:.2f})")
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def report_lines(t: dict) -> list[str]:
    """The report's section (markdown lines)."""
    lines = ["## Torque-aware footholds (§7.1)", "",
             "The cycle planned (not executed) with every foothold's peak static joint torque evaluated (after the "
             "step, and during it with the leg at the waypoint above the foothold; zero-interaction loads), by "
             "today's planner and by the torque-aware one, which refuses stable cells over max_saturation of a "
             "joint's limit (the map's Overloaded class).", "",
             "| robot | limit | planner | footholds over the limit | peak | mean / shortest step [m] | completed |",
             "|---|---|---|---|---|---|---|"]
    for name, label in (("nominal", "SDM-B"), ("payload", f"SDM-B + {t['payload_kg']:.0f} kg")):
        r = t[name]
        for key, planner in (("today", "today's"), ("torque_aware", "torque-aware")):
            s = r[key]
            last = r[key + "_steps"][-1] if r[key + "_steps"] else None
            if not s["completed"] and last is not None and last["lift_saturation"] > r["limit"]:
                s = dict(s, reason=f"{s['reason']} (lifting leg {last['leg']} alone loads a joint to "
                                   f"{last['lift_saturation']:.2f} of its limit)")
            lines.append(f"| {label} | {r['limit']:.2f} | {planner} | {s['over_limit']}/{s['steps']} | {s['peak']:.3f} | "
                         f"{s['mean_step']:.3f} / {s['min_step']:.3f} | "
                         f"{'yes' if s['completed'] else 'no: ' + s['reason']} |")
    lines += ["", "![torque](footfall_torque.png)", ""]
    return lines
