"""Scripted baselines: the passive bogie (gimbal off, clutch open: §5, Table 6) and a hand-written
gimbal controller (path following with the yaw joint, roll joint to balance the diagonal loads).
Both act on the normalised 45-value observation, like a learned policy.
"""

from __future__ import annotations

import math

import numpy as np

from .. import sensing

_IDX = sensing.OBSERVATION_INDEX
_SC = sensing.ObservationScales()
_LIM = sensing.ActionLimits()
# Fz of each sensor (FL, FR, RL, RR) in the observation
_FZ = [_IDX["fts"] + 6 * s + 2 for s in range(4)]


class PassiveController:
    """Drive straight at ``speed``; joint rates 0. Use with ``passive=True`` (the environment
    then holds the yaw brake and opens the clutch, so the bogie rolls freely)."""

    def __init__(self, speed: float = 0.2):
        if not 0.0 <= speed <= _LIM.vx_max:
            raise ValueError(f"speed = {speed} must be in [0, {_LIM.vx_max}] m/s")
        self.speed = speed

    def __call__(self, obs, env=None) -> np.ndarray:
        return np.array([2.0 * self.speed / _LIM.vx_max - 1.0, 0.0, 0.0], dtype=np.float32)


class ScriptedGimbalController:
    """Path following and load balancing with the Active Gimbal Suspension.

    Steering: a positive gimbal yaw turns ERNEST left (like front-axle steering), so the desired
    yaw is psi* = -k_heading * heading_deviation - k_lateral * lateral_deviation (clipped), tracked
    by a proportional yaw rate. Balancing: a positive roll rate shifts load onto the FR-RL
    diagonal, so the roll rate is proportional to (Fz_FL + Fz_RR) - (Fz_FR + Fz_RL) from the
    processed force–torque values. Speed drops when the heading is far off.
    """

    def __init__(self, k_heading: float = 1.2, k_lateral: float = 0.6, max_steer_deg: float = 30.0,
                 k_yaw: float = 2.0, k_balance_deg_per_newton: float = 0.02,
                 balance_deadband: float = 40.0, speed: float = 0.2):
        self.k_heading, self.k_lateral = k_heading, k_lateral
        self.max_steer = math.radians(max_steer_deg)
        self.k_yaw = k_yaw
        self.k_balance = math.radians(k_balance_deg_per_newton)
        self.deadband = balance_deadband  # [N]: ignore small imbalances (saves roll-motor energy)
        self.speed = speed

    def __call__(self, obs, env=None) -> np.ndarray:
        o = np.asarray(obs, dtype=np.float64)
        heading = o[_IDX["heading_deviation"]] * _SC.heading
        lateral = o[_IDX["lateral_deviation"]] * _SC.lateral
        psi = o[_IDX["gimbal_yaw"]] * _SC.gimbal_yaw
        fz = o[_FZ] * _SC.force
        psi_star = np.clip(-self.k_heading * heading - self.k_lateral * lateral,
                           -self.max_steer, self.max_steer)
        yaw_rate = np.clip(self.k_yaw * (psi_star - psi), -_LIM.yaw_rate_max, _LIM.yaw_rate_max)
        imbalance = (fz[0] + fz[3]) - (fz[1] + fz[2])
        imbalance = np.sign(imbalance) * max(abs(imbalance) - self.deadband, 0.0)
        roll_rate = np.clip(self.k_balance * imbalance, -_LIM.roll_rate_max, _LIM.roll_rate_max)
        vx = self.speed * float(np.clip(math.cos(heading), 0.3, 1.0))
        return np.array([2.0 * vx / _LIM.vx_max - 1.0, yaw_rate / _LIM.yaw_rate_max,
                         roll_rate / _LIM.roll_rate_max], dtype=np.float32)
