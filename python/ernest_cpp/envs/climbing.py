"""Scripted obstacle gaits for the Active Gimbal Suspension (seed 004 §5.2–5.3), used as
demonstrators: their experience goes into the replay buffer of off-policy training (§4.1 allows
any behaviour policy) and they show what the physics allows on the wheel-high step.

:class:`PhaseGait` is a sequence of timed phases, each a target gimbal yaw and roll and a forward
speed. The joints are driven towards each phase's targets by a proportional rate command clipped
to the §4.2 action limits (the actions a policy could give). The first phase is held until the
leading front (or rear) wheel is within ``trigger`` of the obstacle's face, measured along the path from the
simulator's ground truth (a privileged signal: a demonstrator may see what a policy cannot). After
the last phase the rover drives on at full speed and, once its rear wheels are over, steers back
to its path.

:class:`StepClimbController` is the phase gait whose phases climb a wheel-high step as §5.3 and
Figs 19–20 describe: the front wheels climb one at a time (yaw puts one ahead, roll lifts it and
unloads it while it is driven over the edge), then the roll is driven towards its stop to tip the
chassis so that one rear wheel climbs while the other follows on full drive torque. Its defaults
were tuned by CMA-ES on ``ernest/WheelStep-v0`` (``benchmarks/tune_gait.py step``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import sensing
from .._repr import arguments_repr, keeps_arguments
from .baselines import POLICY_DT, _to_action

_LIM = sensing.ActionLimits()
_WHEEL_RADIUS = 0.17  # seed 004 Table 1: wheel diameter 0.34 m

#: Phases of the step climb: (duration [s], gimbal yaw [deg], gimbal roll [deg], speed [m/s]).
#: Phase 0 (the approach) lasts until the trigger; its duration is unused.
STEP_CLIMB_PHASES: tuple[tuple[float, float, float, float], ...] = (
    (0.00, -41.48, 0.00, 0.200),   # approach, left front wheel ahead
    (5.30, -35.65, 25.42, 0.018),  # lift and unload the left front wheel at the face
    (2.52, -21.32, 21.21, 0.153),  # drive it over the edge
    (2.02, 23.21, -5.01, 0.032),   # swing the right front wheel ahead, roll the other way
    (2.59, 19.87, -11.32, 0.016),  # lift it at the face
    (3.22, 25.06, -12.16, 0.169),  # and drive it up
    (5.86, 19.86, 29.18, 0.168),   # roll to the stop: tips the chassis, one rear wheel climbs
    (7.97, 6.36, -29.36, 0.198),   # the other rear wheel on full drive, roll the other way
)
STEP_CLIMB_TRIGGER = 0.127  # [m] leading front wheel to the face when phase 1 starts


#: Phases of the Bickler-trap crossing (§5.2, Fig. 18), after the rear wheels reach the rocks:
#: the roll tips the chassis so one rear wheel climbs, then the other.
BICKLER_PHASES: tuple[tuple[float, float, float, float], ...] = (
    (0.00, 7.13, 0.00, 0.200),     # drive up: the front wheels roll over the rocks
    (0.54, -43.47, 18.01, 0.155),  # rear wheels at the rocks: yaw hard, roll one way
    (4.16, -28.97, -26.80, 0.186), # roll to the other stop: one rear wheel climbs
    (1.56, -16.10, 28.32, 0.197),  # and back: the other one follows
    (3.02, -2.81, -7.31, 0.198),   # level out and drive on
)
BICKLER_TRIGGER = 0.033  # [m] leading rear wheel to the rocks when phase 1 starts


def _along_path(env, points: np.ndarray) -> np.ndarray:
    """Distance of ``points`` (n x 3, world) along the start heading from the world origin (the
    frame the scenarios place their steps and rocks in)."""
    h = float(env.scenario.start_heading)
    return points[:, 0] * math.cos(h) + points[:, 1] * math.sin(h)


def obstacle_face(env) -> float:
    """Distance along the path of the near face of the course's obstacle: the step's edge
    (``step_distance``) or, for the Bickler trap, the near side of its row of rocks."""
    sc = env.scenario
    if sc.step_height > 0.0:
        return float(sc.step_distance)
    obstacles = np.asarray(sc.obstacles)
    if obstacles.size == 0:
        raise ValueError(f"scenario {sc.name!r} has no step or rocks for an obstacle gait")
    h = float(sc.start_heading)
    centre = obstacles[:, 0] * math.cos(h) + obstacles[:, 1] * math.sin(h)
    return float(np.min(centre - 0.5 * obstacles[:, 3]))


class PhaseGait:
    """Timed gimbal phases after a trigger at the obstacle (see the module docstring).

    ``phases``: (duration [s], yaw [deg], roll [deg], speed [m/s]) each; ``trigger`` [m]: the
    leading front wheel's distance to the face that ends the approach; ``k_joint`` [1/s]: the
    joints' proportional gain (the rate command is ``k_joint`` times the angle error, clipped);
    ``k_heading`` [-], ``k_lateral`` [rad/m], ``max_steer_deg``: after the last phase, once both
    rear wheels are past the face, the yaw target steers back to the path (a positive gimbal yaw
    turns left); before that the gimbal is held centred (steering while a rear wheel climbs
    spoils the climb: measured, the tuned step climb then leaves both rear wheels below);
    ``max_approach`` [s]: the approach ends after this long even without the trigger;
    ``trigger_wheels``: ``front`` (the step: the front wheels climb first) or ``rear`` (the
    Bickler trap: the front wheels roll over the rocks, the rear wheels are the ones to lift).
    """

    __repr__ = arguments_repr

    @keeps_arguments
    def __init__(self, phases, trigger: float, k_joint: float = 1.8, k_heading: float = 0.8,
                 k_lateral: float = 0.3, max_steer_deg: float = 30.0, max_approach: float = 20.0,
                 trigger_wheels: str = "front", dt: float = POLICY_DT):
        phases = [tuple(float(v) for v in p) for p in phases]
        if not phases or any(len(p) != 4 for p in phases):
            raise ValueError("phases must be a non-empty list of (duration, yaw, roll, speed)")
        for i, (d, yaw, roll, v) in enumerate(phases):
            if d < 0.0 or abs(yaw) > 45.0 or abs(roll) > 30.0 or not 0.0 <= v <= _LIM.vx_max:
                raise ValueError(f"phase {i} = {phases[i]}: duration >= 0, |yaw| <= 45 deg, "
                                 f"|roll| <= 30 deg and speed in [0, {_LIM.vx_max}] m/s")
        if trigger < 0.0 or k_joint <= 0.0 or k_heading < 0.0 or k_lateral < 0.0 or \
                not 0.0 <= max_steer_deg <= 45.0 or max_approach <= 0.0:
            raise ValueError("trigger >= 0, k_joint > 0, k_heading >= 0, k_lateral >= 0, "
                             "max_steer_deg in [0, 45] and max_approach > 0")
        self.phases, self.trigger, self.k_joint = phases, trigger, k_joint
        self.k_heading, self.k_lateral = k_heading, k_lateral
        self.max_steer = math.radians(max_steer_deg)
        if trigger_wheels not in ("front", "rear"):
            raise ValueError(f"trigger_wheels = {trigger_wheels!r}; choose front or rear")
        self.trigger_wheels = slice(0, 2) if trigger_wheels == "front" else slice(2, 4)
        self.max_approach, self.dt = max_approach, dt
        self.reset()

    def reset(self) -> None:
        """A new episode: back to the approach."""
        self.phase, self.t, self.t_phase = 0, 0.0, 0.0

    def targets(self, env) -> tuple[float, float, float]:
        """(yaw [rad], roll [rad], speed [m/s]) for the current control period; advances the
        phase clock by one period."""
        if self.phase == 0:
            wheels = np.asarray(env.core.state.wheel_position)
            lead = float(np.max(_along_path(env, wheels[self.trigger_wheels])))
            if lead + _WHEEL_RADIUS > obstacle_face(env) - self.trigger or \
                    self.t >= self.max_approach:
                self.phase, self.t_phase = 1, 0.0  # from the next period on
            self.t += self.dt
            _, yaw, roll, v = self.phases[0]
            return math.radians(yaw), math.radians(roll), v
        else:
            while self.phase < len(self.phases) and self.t_phase >= self.phases[self.phase][0]:
                self.t_phase -= self.phases[self.phase][0]
                self.phase += 1
            self.t_phase += self.dt
        self.t += self.dt
        if self.phase < len(self.phases):
            _, yaw, roll, v = self.phases[self.phase]
            return math.radians(yaw), math.radians(roll), v
        # Drive on; steer back to the path once the rear wheels are past the face (steering
        # while they climb spoils the climb).
        s = env.core.state
        rear = float(np.min(_along_path(env, np.asarray(s.wheel_position)[2:])))
        if rear < obstacle_face(env) + _WHEEL_RADIUS:
            return 0.0, 0.0, _LIM.vx_max
        path = env.scenario.path
        steer = -self.k_heading * path.heading_deviation(s.yaw) - \
            self.k_lateral * path.lateral_deviation(s.position[0], s.position[1])
        return float(np.clip(steer, -self.max_steer, self.max_steer)), 0.0, _LIM.vx_max

    def __call__(self, obs, env) -> np.ndarray:
        if env is None:
            raise ValueError("PhaseGait needs the environment (ground truth at the obstacle)")
        env = getattr(env, "unwrapped", env)
        yaw, roll, v = self.targets(env)
        s = env.core.state
        yaw_rate = np.clip(self.k_joint * (yaw - s.gimbal_yaw), -_LIM.yaw_rate_max,
                           _LIM.yaw_rate_max)
        roll_rate = np.clip(self.k_joint * (roll - s.gimbal_roll), -_LIM.roll_rate_max,
                            _LIM.roll_rate_max)
        return _to_action(v, float(yaw_rate), float(roll_rate))


class BicklerCrossController(PhaseGait):
    """The Bickler-trap crossing of §5.2 as a scripted phase gait: the front wheels roll over the
    rocks, then the roll lifts the rear wheels over one at a time (tuned defaults: all four wheels
    over ``ernest/BicklerTrap-v0`` in 10 of 10 seeds at dt and dt / 4,
    ``benchmarks/tune_gait.py bickler``)."""

    @keeps_arguments
    def __init__(self, phases=BICKLER_PHASES, trigger: float = BICKLER_TRIGGER, **kw):
        kw.setdefault("trigger_wheels", "rear")
        super().__init__(phases, trigger, **kw)


class StepClimbController(PhaseGait):
    """The wheel-high step climb of §5.3 as a scripted phase gait (tuned defaults)."""

    @keeps_arguments
    def __init__(self, phases=STEP_CLIMB_PHASES, trigger: float = STEP_CLIMB_TRIGGER, **kw):
        super().__init__(phases, trigger, **kw)
