"""Scripted baselines, each acting on the normalised 45-value observation and returning the
normalised 3-value action at the environment's 2 Hz policy rate, like a learned policy:

- :class:`PassiveController`: the passive bogie of seed 004 §5 / Table 6 (drive straight; use with
  ``passive=True``: gimbal off, clutch open).
- :class:`CrawlingGaitController`: the crawling gait of seed 004 §5.5 (first proposed in its
  ref. [10]): the roll joint shifts the load to one side, whose wheels anchor, while the yaw joint
  swings the bogie and pulls the chassis forward; a yaw bias keeps the rover on its path. This is
  the scripted gimbal baseline of ``ernest evaluate`` and ``ernest slope-demo`` (one gait, defined
  once, in :meth:`CrawlingGaitController.rates`).
- :class:`LoadBalancingController`: path following with the yaw joint and roll-joint balancing of
  the diagonal wheel loads (with a deadband). On the noise-free, mirror-symmetric evaluation
  courses it commands almost nothing, so it behaves like the passive bogie there; it is kept for
  experiments, not compared in ``ernest evaluate``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import sensing
from .._repr import arguments_repr, keeps_arguments

_IDX = sensing.OBSERVATION_INDEX
_SC = sensing.ObservationScales()
_LIM = sensing.ActionLimits()
# Fz of each sensor (FL, FR, RL, RR) in the observation
_FZ = [_IDX["fts"] + 6 * s + 2 for s in range(4)]
#: The environments' policy period [s] (2 Hz, seed 004 §4.2).
POLICY_DT = 0.5


def _to_action(vx: float, yaw_rate: float, roll_rate: float) -> np.ndarray:
    """Physical command -> normalised action in [-1, 1] (the environments' mapping)."""
    a = np.array([2.0 * vx / _LIM.vx_max - 1.0, yaw_rate / _LIM.yaw_rate_max,
                  roll_rate / _LIM.roll_rate_max])
    return np.clip(a, -1.0, 1.0).astype(np.float32)


class PassiveController:
    """Drive straight at ``speed``; joint rates 0. Use with ``passive=True`` (the environment
    then holds the yaw brake and opens the clutch, so the bogie rolls freely)."""

    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, speed: float = 0.2):
        if not 0.0 <= speed <= _LIM.vx_max:
            raise ValueError(f"speed = {speed} must be in [0, {_LIM.vx_max}] m/s")
        self.speed = speed

    def reset(self) -> None:
        """Nothing to reset (stateless); present so every baseline has the same interface."""

    def __call__(self, obs, env=None) -> np.ndarray:
        return _to_action(self.speed, 0.0, 0.0)


class CrawlingGaitController:
    """The crawling gait of seed 004 §5.5 as a scripted controller.

    Desired gimbal angles (t from the start of the episode, w = 2 pi / ``period``)::

        psi*(t) = A sin(w t) + psi_bias          A = yaw_amplitude_deg
        phi*(t) = -B cos(w t)  for t >= align    B = roll_amplitude_deg
                = 0            before            (clutch alignment: bogie level first;
                                                  default align_time 1 s: 1.5 s, a quarter
                                                  period, climbed 5 pp less on dry M90)

    While the bogie swings one way the roll presses the wheel on the side it swings away from,
    which anchors while the other advances, and the chassis is pulled forward. Commanded rates over
    each control period [t, t + dt] are the mean rates of that trajectory (its finite difference,
    so a zero-order hold at 2 Hz reaches psi*, phi* at every sample) plus ``k_track`` times the
    measured tracking error of each joint (0 turns it into a purely open-loop gait), clipped to the
    §4.2 action limits. Forward speed is ``speed`` throughout (no-slip travel = speed * t).

    Path following: ``psi_bias = -k_heading * heading deviation - k_lateral * lateral
    deviation``, clipped to ``max_bias_deg`` (a positive gimbal yaw turns ERNEST left). The bias
    enters through the tracking term (the mean rate of a constant bias is zero), so it needs
    ``k_track`` > 0 and the measured yaw.

    Clock: the controller counts its calls; call ``k`` is at t = k * ``dt`` (the environment's
    0.5 s policy period). ``reset()`` restarts the clock; a new episode is also detected by
    itself: the environment's observation carries the current action, which after ``reset`` is the
    standing-still action (Vx = 0, rates 0) that this controller never commands (Vx > 0), so
    seeing it after the first call restarts the gait.

    Defaults (chosen on ``ernest/SlopeEval-v0``, which starts on the slope, dry M90 and wet
    sand, after the implicit-slip fix of the simulator; grid over period 4/6/8 s, yaw 15/20/30
    deg, roll 0/3/6/10 deg, speed 0.1/0.2 m/s, open loop): period 6 s, yaw 20 deg, roll 6 deg,
    full speed 0.2 m/s (the passive bogie's, so travel reductions compare). Dry M90: 80 %
    travel reduction (passive bogie: 103 %, it slides back), wet sand 58 %; within 0.5 pp and
    1 % of cost of transport of a run at a quarter of the physics step. Roll 0 loses most of the
    gain; (6 s, 30 deg, 10 deg) climbs slightly further on dry M90 (79 %) but moves by 3 pp with
    the step. Feedback (``k_track``, path following) is off by default. ``ernest evaluate``,
    ``ernest reproduce`` and ``ernest slope-demo`` use these defaults.
    """

    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, period: float = 6.0, yaw_amplitude_deg: float = 20.0,
                 roll_amplitude_deg: float = 6.0, speed: float = 0.2, align_time: float = 1.0,
                 k_track: float = 0.0, k_heading: float = 0.0, k_lateral: float = 0.0,
                 max_bias_deg: float = 15.0, dt: float = POLICY_DT):
        if period <= 0.0 or dt <= 0.0:
            raise ValueError("period and dt must be > 0")
        if not 0.0 < speed <= _LIM.vx_max:
            raise ValueError(f"speed = {speed} must be in (0, {_LIM.vx_max}] m/s")
        if not 0.0 <= yaw_amplitude_deg <= 45.0 or not 0.0 <= roll_amplitude_deg <= 30.0:
            raise ValueError("amplitudes must be within the joint ranges (yaw 45 deg, roll 30 deg)")
        if align_time < 0.0 or k_track < 0.0 or k_heading < 0.0 or k_lateral < 0.0:
            raise ValueError("align_time and the gains must be >= 0")
        self.period, self.speed, self.align_time, self.dt = period, speed, align_time, dt
        self.yaw_amplitude = math.radians(yaw_amplitude_deg)
        self.roll_amplitude = math.radians(roll_amplitude_deg)
        self.k_track, self.k_heading, self.k_lateral = k_track, k_heading, k_lateral
        self.max_bias = math.radians(max_bias_deg)
        self.calls = 0

    def reset(self) -> None:
        """Restart the gait clock (a new episode)."""
        self.calls = 0

    # -- the gait, defined once ------------------------------------------------------------
    def angles(self, t: float, psi_bias: float = 0.0) -> tuple[float, float]:
        """Desired (gimbal yaw, gimbal roll) [rad] at time ``t`` [s]."""
        w = 2.0 * math.pi / self.period
        psi = self.yaw_amplitude * math.sin(w * t) + psi_bias
        phi = -self.roll_amplitude * math.cos(w * t) if t >= self.align_time else 0.0
        return psi, phi

    def rates(self, t: float, dt: float, yaw: float | None = None, roll: float | None = None,
              heading: float = 0.0, lateral: float = 0.0) -> tuple[float, float, float]:
        """Physical command (Vx [m/s], yaw rate, roll rate [rad/s]) held over [t, t + dt].

        ``yaw``/``roll``: measured joint angles (for ``k_track``; None = open loop);
        ``heading``/``lateral``: path deviations [rad, m] (for the yaw bias)."""
        bias = float(np.clip(-self.k_heading * heading - self.k_lateral * lateral,
                             -self.max_bias, self.max_bias))
        p0, r0 = self.angles(t, bias)
        p1, r1 = self.angles(t + dt, bias)
        yaw_rate, roll_rate = (p1 - p0) / dt, (r1 - r0) / dt
        if t < self.align_time and roll is not None:  # clutch alignment: bring the bogie level
            roll_rate += -roll / max(dt, 0.5)
        if self.k_track > 0.0:
            if yaw is not None:
                yaw_rate += self.k_track * (p0 - yaw)
            if roll is not None and t >= self.align_time:
                roll_rate += self.k_track * (r0 - roll)
        return (self.speed, float(np.clip(yaw_rate, -_LIM.yaw_rate_max, _LIM.yaw_rate_max)),
                float(np.clip(roll_rate, -_LIM.roll_rate_max, _LIM.roll_rate_max)))

    # -- the policy interface ---------------------------------------------------------------
    def __call__(self, obs, env=None) -> np.ndarray:
        o = np.asarray(obs, dtype=np.float64)
        a_prev = o[_IDX["action"]:_IDX["action"] + 3]
        if self.calls > 0 and a_prev[0] <= -1.0 + 1e-6 and np.all(np.abs(a_prev[1:]) < 1e-6):
            self.reset()  # the standing-still action of a freshly reset environment
        t = self.calls * self.dt
        self.calls += 1
        vx, yaw_rate, roll_rate = self.rates(
            t, self.dt, yaw=o[_IDX["gimbal_yaw"]] * _SC.gimbal_yaw,
            roll=o[_IDX["gimbal_roll"]] * _SC.gimbal_roll,
            heading=o[_IDX["heading_deviation"]] * _SC.heading,
            lateral=o[_IDX["lateral_deviation"]] * _SC.lateral)
        return _to_action(vx, yaw_rate, roll_rate)


class LoadBalancingController:
    """Path following and load balancing with the Active Gimbal Suspension.

    Steering: a positive gimbal yaw turns ERNEST left (like front-axle steering), so the desired
    yaw is psi* = -k_heading * heading_deviation - k_lateral * lateral_deviation (clipped), tracked
    by a proportional yaw rate. Balancing: a positive roll rate shifts load onto the FR-RL
    diagonal, so the roll rate is proportional to (Fz_FL + Fz_RR) - (Fz_FR + Fz_RL) from the
    processed force–torque values, outside a deadband. Speed drops when the heading is far off.
    """

    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, k_heading: float = 1.2, k_lateral: float = 0.6, max_steer_deg: float = 30.0,
                 k_yaw: float = 2.0, k_balance_deg_per_newton: float = 0.02,
                 balance_deadband: float = 40.0, speed: float = 0.2):
        self.k_heading, self.k_lateral = k_heading, k_lateral
        self.max_steer = math.radians(max_steer_deg)
        self.k_yaw = k_yaw
        self.k_balance = math.radians(k_balance_deg_per_newton)
        self.deadband = balance_deadband  # [N]: ignore small imbalances (saves roll-motor energy)
        self.speed = speed

    def reset(self) -> None:
        """Nothing to reset (stateless)."""

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
        return _to_action(vx, float(yaw_rate), float(roll_rate))
