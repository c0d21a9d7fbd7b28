"""FootFall's gait planning and its execution in simulation (seed 003 §5.3.1 and §4.1), for the
``ernest footfall`` command: the skeleton gait of a reverse-wave discontinuous gait on flat ground
(footprints, body shifts, step lengths by successive IK; periodic after the second cycle) and the
Moses Lake lesson in ODE — a swing planned against the rigid pose hits a rock that the plan made
against the sag model's pose clears — with the simulator's sag checked against the sag model.

``demo(out_dir)`` writes ``footfall_gait.png`` and returns the figures as a dict.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from . import walker as W
from . import walker_sim as WS


def gait(model: W.WalkerModel, cycles: int = 4, max_step: float = 0.78) -> W.GaitPlan:
    """The skeleton gait from the standard stance, travelling +x. The default ``max_step`` is a
    little longer than SDM-B's front leg reaches from the standard stance (0.752 m), so the gait
    starts with a transient that decays six-fold a cycle."""
    o = W.GaitPlannerOptions()
    o.cycles, o.max_step = cycles, max_step
    body = model.standard_body_pose()[:3, 3]
    return W.plan_gait(model, body, model.standard_configuration, o)


def periodicity(plan: W.GaitPlan, after: int = 2) -> float:
    """Largest difference of a step or shift length from its value one cycle earlier, over the
    cycles after the first ``after`` ones (the paper: periodic after the second cycle) [m]."""
    s, b = np.asarray(plan.step_lengths), np.asarray(plan.shift_lengths)
    if s.shape[0] < after + 2:
        raise ValueError(f"periodicity: the plan has {s.shape[0]} cycles, needs at least {after + 2}")
    return float(max(np.abs(np.diff(s[after:], axis=0)).max(), np.abs(np.diff(b[after:], axis=0)).max()))


def plot(plan: W.GaitPlan, sag: WS.SagScenarioResult, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(13, 10))
    # (a) footprints and body path
    a = ax[0, 0]
    bodies = [plan.events[0].body_before] + [e.body_after for e in plan.events]
    bodies = np.array(bodies)
    colours = plt.cm.viridis(np.linspace(0, 1, len(plan.sequence)))
    for e in plan.events:
        if e.kind == W.GaitEventKind.Step:
            f0, f1 = e.feet_before[:, e.leg], e.feet_after[:, e.leg]
            i = plan.sequence.index(e.leg)
            a.annotate("", f1[:2], f0[:2], arrowprops=dict(arrowstyle="->", color=colours[i], lw=1.2))
            a.plot(*f1[:2], "o", color=colours[i], ms=4)
    f = plan.events[0].feet_before
    a.plot(f[0], f[1], "ks", ms=5, label="start footprints")
    a.plot(bodies[:, 0], bodies[:, 1], "r.-", lw=1, ms=4, label="body (shift after each step)")
    for i, leg in enumerate(plan.sequence):
        a.plot([], [], "o", color=colours[i], label=f"{i + 1}: leg {leg}")
    a.set_aspect("equal")
    a.set_xlabel("x [m] (travel)")
    a.set_ylabel("y [m]")
    a.set_title("(a) reverse-wave skeleton gait (§5.3.1): steps and body shifts")
    a.set_ylim(-2.6, 2.9)
    a.legend(fontsize=7, loc="upper center", ncol=4)
    # (b) step and shift lengths per cycle
    b = ax[0, 1]
    s, h = np.asarray(plan.step_lengths), np.asarray(plan.shift_lengths)
    n = s.shape[1]
    x = np.arange(s.size) + 1
    b.plot(x, 100 * s.ravel(), "o-", color="tab:blue", label="step of the leg [cm]")
    b.plot(x, 600 * h.ravel(), "s--", color="tab:orange", ms=4, label="6 × body shift after it [cm]")
    for c in range(1, s.shape[0]):
        b.axvline(c * n + 0.5, color="0.6", ls=":")
    b.set_xlabel(f"step in the gait ({n} a cycle; order {plan.sequence})")
    b.set_ylabel("length [cm]")
    err = f"{1000 * periodicity(plan):.2g} mm" if s.shape[0] > 3 else "n/a"
    b.set_title(f"(b) front leg reach-limited at first; repeats after cycle 2 to {err}")
    b.legend(fontsize=8, loc="lower right")
    # (c) clearance traces
    c = ax[1, 0]
    for run, plan_, name, col in ((sag.rigid_run, sag.rigid, "rigid plan", "tab:red"),
                                  (sag.compensated_run, sag.compensated, "sag-compensated plan", "tab:green")):
        c.plot(run.time, 100 * np.asarray(run.rock_clearance), color=col,
               label=f"{name}: lift {100 * plan_.lift_height:.1f} cm, on paper "
                     f"{100 * plan_.planned_clearance:.1f} cm, executed {100 * run.min_rock_clearance:.1f} cm")
    c.axhline(0, color="k", lw=0.8)
    c.set_ylim(-3, 15)
    c.set_xlabel("time [s]")
    c.set_ylabel("swing wheel to rock [cm]")
    c.set_title("(c) the same swing planner, rigid vs sagged pose, executed in ODE (§4.1)")
    c.legend(fontsize=8)
    # (d) sag: corners
    d = ax[1, 1]
    k = np.arange(len(sag.rigid_corners))
    d.plot(k, sag.rigid_corners, "s--", color="0.5", label="rigid kinematics")
    d.plot(k, sag.predicted_six_corners, "b^-", label="sag model, six wheels down")
    d.plot(k, sag.measured_six_corners, "bx", ms=10, label="ODE, six wheels down")
    d.plot(k, sag.predicted_lifted_corners, "g^-", label="sag model, leg lifted")
    d.plot(k, sag.measured_lifted_corners, "gx", ms=10, label="ODE, leg lifted")
    d.set_xlabel("chassis corner (hip mount of leg)")
    d.set_ylabel("height [m]")
    d.set_title(f"(d) sag: model vs simulator (max error {1000 * sag.lifted_error:.1f} mm lifted)")
    d.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def demo(out_dir, cycles: int = 4) -> dict:
    """Gait plan and sag-compensation scenario on SDM-B; writes ``footfall_gait.png`` in
    ``out_dir`` and returns the numbers (lengths in m, times in s)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    model = W.WalkerModel(W.sdm_b_parameters())
    plan = gait(model, cycles=cycles)
    t0 = time.perf_counter()
    sag = WS.run_sag_scenario(model)
    sim_wall = time.perf_counter() - t0
    figure = out / "footfall_gait.png"
    plot(plan, sag, figure)
    simulated = sag.rigid_run.simulated_seconds + sag.compensated_run.simulated_seconds
    return {
        "figure": str(figure),
        "sequence": list(plan.sequence),
        "step_lengths": np.asarray(plan.step_lengths).tolist(),
        "shift_lengths": np.asarray(plan.shift_lengths).tolist(),
        "periodicity_error": periodicity(plan) if cycles > 3 else float("nan"),
        "min_support_margin": min(e.support_margin for e in plan.events),
        "gait_plan_seconds": plan.seconds,
        "rigid_lift": sag.rigid.lift_height,
        "rigid_planned_clearance": sag.rigid.planned_clearance,
        "rigid_executed_clearance": sag.rigid_run.min_rock_clearance,
        "compensated_lift": sag.compensated.lift_height,
        "compensated_planned_clearance": sag.compensated.planned_clearance,
        "compensated_executed_clearance": sag.compensated_run.min_rock_clearance,
        "sag_error_six": sag.six_error,
        "sag_error_lifted": sag.lifted_error,
        "simulated_seconds": simulated,
        "simulation_wall_seconds": sim_wall,
    }
