"""Seed 004 Figs 19–20 for any controller: the wheel-high step climbed, seen through the wheels'
heights and the Active Gimbal Suspension's joint angles and torques over time.

Fig. 19 shows the wheels clearing the step one at a time; Fig. 20 the gimbal's yaw and roll
positions and torques while they do (negative roll torque assists the right-front and left-rear
wheels, positive the other two). ``climb_trace`` records one ``ernest/WheelStep-v0`` episode at
the 2 Hz policy rate; ``plot_climb`` draws the traces of several controllers side by side.
"""

from __future__ import annotations

import math
import os

import numpy as np

WHEELS = ("FL", "FR", "RL", "RR")


def climb_trace(policy, seed: int = 0, kwargs: dict | None = None) -> dict:
    """One episode of ``policy(obs, env)`` on the wheel-high step: time [s], wheel centre heights
    above the ground [m] (4 columns), gimbal yaw and roll [deg] and their torques [N m]."""
    from .evaluate import run_episode

    rows = []

    def recording(obs, env):
        s = env.unwrapped.core.state
        rows.append([s.time, *np.asarray(s.wheel_position)[:, 2], math.degrees(s.gimbal_yaw),
                     math.degrees(s.gimbal_roll), s.yaw_torque, s.roll_torque])
        return policy(obs, env)

    if hasattr(policy, "reset"):
        policy.reset()
    _, _, env, info = run_episode("ernest/WheelStep-v0", kwargs or {}, recording, False, seed)
    a = np.asarray(rows)
    return {"t": a[:, 0], "wheel_z": a[:, 1:5], "yaw": a[:, 5], "roll": a[:, 6],
            "yaw_torque": a[:, 7], "roll_torque": a[:, 8],
            "step_height": float(env.scenario.step_height),
            "progress": float(info["path_progress"])}


def plot_climb(traces: dict, path: str) -> str:
    """Figs 19–20: one column per controller (``traces``: name -> climb_trace result)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(traces)
    fig, axes = plt.subplots(3, n, figsize=(5.5 * n, 8), sharex="col", squeeze=False)
    for j, (name, tr) in enumerate(traces.items()):
        ax = axes[0, j]
        for k, w in enumerate(WHEELS):
            ax.plot(tr["t"], tr["wheel_z"][:, k], label=w)
        ax.axhline(tr["step_height"] + 0.17, color="k", ls=":", lw=0.8, label="on top")
        ax.set_title(f"{name} (progress {tr['progress']:.2f} m)")
        ax.set_ylabel("wheel centre height [m]")
        ax.legend(ncol=5, fontsize=7)
        axes[1, j].plot(tr["t"], tr["yaw"], label="yaw")
        axes[1, j].plot(tr["t"], tr["roll"], label="roll")
        axes[1, j].set_ylabel("gimbal angle [deg]")
        axes[1, j].legend(fontsize=7)
        axes[2, j].plot(tr["t"], tr["yaw_torque"], label="yaw torque")
        axes[2, j].plot(tr["t"], tr["roll_torque"], label="roll torque")
        axes[2, j].set_ylabel("gimbal torque [N m]")
        axes[2, j].set_xlabel("time [s]")
        axes[2, j].legend(fontsize=7)
        for ax in axes[:, j]:
            ax.grid(alpha=0.3)
    fig.suptitle("Wheel-high step (0.34 m), seed 004 Figs 19-20: wheels climb one at a time, "
                 "the gimbal's roll torque assists each")
    fig.tight_layout()
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
