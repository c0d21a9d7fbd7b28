"""ERNEST rover dynamics on ODE (seed 004 §2–3): multibody model with the Active Gimbal Suspension,
roll clutch, Bekker–Wong soft soil and rigid contact, DC motors (eq 40), force–torque sensors,
snapshot/restore, divergence detection, a batched multi-threaded stepper, and the Jacobian wheel
synchroniser of §2.3 (eqs 1–10).

The simulator is C++ (``ernest_cpp._core.dynamics``); this module re-exports it and adds
conveniences for building scenarios.
"""

from __future__ import annotations

import math
import warnings
from typing import Iterable, Sequence

import numpy as np

from . import soil as _soil
from ._core import dynamics as _dyn
from ._core import envs as _envs
from ._core.dynamics import (  # noqa: F401  (re-exports)
    COMMAND_SIZE,
    STATE_VECTOR_SIZE,
    ActuatorMode,
    BatchStepper,
    BoxObstacle,
    ClutchState,
    Commands,
    GroundType,
    HeightMap,
    MotorElectrical,
    MotorParameters,
    RoverParameters,
    RoverSim,
    RoverState,
    SimOptions,
    Stepper,
    SimulationDiverged,
    Snapshot,
    SolverStats,
    WheelObstacleContact,
    WheelSyncResult,
    motor_electrical,
    synchronise_wheels,
    wheel_jacobian,
)

#: Wheel order of every per-wheel array.
WHEELS = ("FL", "FR", "RL", "RR")
#: Names of the STATE_VECTOR_SIZE columns of RoverSim.state_vector() and BatchStepper.step() (the
#: rover's full state, not the policy's observation: sensing.OBSERVATION_SIZE, layout ernest-obs-v2).
STATE_VECTOR_NAMES = tuple(RoverSim.state_vector_names())
#: Columns of BatchStepper commands.
COMMAND_NAMES = ("w_FL", "w_FR", "w_RL", "w_RR", "yaw_rate", "roll_rate", "gimbal_enabled",
                 "clutch_engage")


def driving_soil(name: str) -> _soil.SoilParameters:
    """The soil preset ``name`` with the slip regularisation the environments drive on.

    Table 2 gives eq 12's eps_slip = 100 (m/s)^-2 and eq 16's eps_motion = 5e-5 m/s, chosen for
    integrator speed; under them a rover starting from rest on M90 barely moves (2 cm in 6 s at a
    0.15 m/s command) because the regularisation spans ERNEST's whole speed range. The
    environments use ``EnvOptions().eps_slip`` and ``EnvOptions().eps_motion`` (1e4, 0.01;
    docs/soil.md); this takes them from there, so the two cannot drift apart.
    """
    soil = _soil.soil_preset(name)
    env = _envs.EnvOptions()
    soil.eps_slip = env.eps_slip
    soil.eps_motion = env.eps_motion
    return soil


def make_options(ground: str = "soil", soil: str | _soil.SoilParameters = "m90",
                 dt: float | None = None, seed: int = 0,
                 friction: float | None = None, guess_active_set: bool = True,
                 sparse_lcp: bool = True) -> SimOptions:
    """SimOptions for ``ground`` ('soil' or 'rigid'), a soil preset name or SoilParameters, the
    physics step (default: the study's), the seed, the Coulomb friction (None: drawn), whether
    the solver guesses its active set (False: ODE pivots every step; same solution) and whether
    it solves with the sparse LDL^T (False: ODE's dense solver; same solution).

    A preset name gives the environments' soil (``driving_soil``: Table 2's values with the
    environments' eps_slip and eps_motion, under which the rover drives); pass
    ``soil.soil_preset(name)`` for Table 2's values as printed.
    """
    o = SimOptions()
    if ground not in ("soil", "rigid"):
        raise ValueError(f"ground must be 'soil' or 'rigid', got {ground!r}")
    o.ground = GroundType.Soil if ground == "soil" else GroundType.Rigid
    o.soil = driving_soil(soil) if isinstance(soil, str) else soil
    if dt is not None:
        o.dt = float(dt)
    o.seed = int(seed)
    if friction is not None:
        o.friction = float(friction)
    o.guess_active_set = bool(guess_active_set)
    o.sparse_lcp = bool(sparse_lcp)
    o.validate()
    return o


def rock_field(n: int = 20, seed: int = 0, length: float = 6.0, width: float = 2.0,
               x0: float = 0.8, size: tuple[float, float] = (0.06, 0.16)) -> list[BoxObstacle]:
    """n box 'rocks' with random sizes and yaws in [x0, x0 + length] x [-width/2, width/2],
    half buried in flat ground at z = 0 (seeded, reproducible)."""
    rng = np.random.default_rng(seed)
    rocks = []
    for _ in range(int(n)):
        s = rng.uniform(size[0], size[1], 3)
        c = (x0 + rng.uniform(0.0, length), rng.uniform(-width / 2, width / 2), 0.25 * s[2])
        rocks.append(BoxObstacle(np.array(c), s, float(rng.uniform(0, math.pi)), 0.0, 0.0))
    return rocks


def make_sim(ground: str = "soil", terrain: HeightMap | None = None,
             obstacles: Iterable[BoxObstacle] = (), params: RoverParameters | None = None,
             options: SimOptions | None = None, **option_kwargs) -> RoverSim:
    """A RoverSim on ``terrain`` (default: 40 m x 20 m flat ground around the origin)."""
    terrain = terrain or HeightMap.flat(40.0, 20.0, 0.25, 0.0, -10.0, -10.0)
    options = options or make_options(ground, **option_kwargs)
    return RoverSim(params or RoverParameters(), terrain, list(obstacles), options)


def sync_commands(sim: RoverSim, vx: float, yaw_rate: float = 0.0, roll_rate: float = 0.0,
                  gimbal_enabled: bool = True, clutch_engage: bool = False) -> Commands:
    """Commands with wheel speeds from the wheel synchroniser (§2.3) at the current state."""
    s = sim.state
    w = synchronise_wheels(sim.parameters, s.gimbal_yaw, s.gimbal_roll, vx,
                           s.body_angular_velocity[0], s.body_angular_velocity[1], yaw_rate,
                           roll_rate)
    c = Commands()
    c.wheel_speed = list(w.wheel_speeds)
    c.yaw_rate = yaw_rate
    c.roll_rate = roll_rate
    c.gimbal_enabled = gimbal_enabled
    c.clutch_engage = clutch_engage
    return c


_fast_lcp_warned = False


def fast_lcp_active() -> bool:
    """Whether ODE's constraint solves reach ernest's sparse solver in this process.

    The fast path replaces ODE's internal ``dxSolveLCP`` by symbol binding (ARCHITECTURE.md, "The
    solver hook"); with a libode that binds the call internally, names it otherwise or lays out
    its data differently, every solve is ODE's Dantzig solver instead: slower, and friction
    bounded by ODE's approximation (not corrected to Coulomb's law with the final normal force).
    The first time it is found off, this issues one ``RuntimeWarning`` naming why (the C++ core
    also prints one line on stderr). Checked once, on import of this module; per simulator, see
    ``RoverSim.solver_stats.fast_lcp``.
    """
    global _fast_lcp_warned
    active = bool(_dyn.fast_lcp_active())
    if not active and not _fast_lcp_warned:
        _fast_lcp_warned = True
        why = _dyn.fast_lcp_inactive_reason()
        warnings.warn(f"ernest_cpp: the fast constraint solver is off ({why}); every step uses "
                      "ODE's Dantzig solver: slower, friction by ODE's approximation",
                      RuntimeWarning, stacklevel=2)
    return active


def command_array(rows: Sequence[Sequence[float]]) -> np.ndarray:
    """(N, COMMAND_SIZE) float64 array for BatchStepper.step, checked."""
    a = np.ascontiguousarray(rows, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != COMMAND_SIZE:
        raise ValueError(f"commands must have shape (N, {COMMAND_SIZE}), got {a.shape}")
    return a


__all__ = [
    "COMMAND_NAMES", "COMMAND_SIZE", "STATE_VECTOR_NAMES", "STATE_VECTOR_SIZE", "WHEELS",
    "ActuatorMode", "BatchStepper", "BoxObstacle", "ClutchState", "Commands", "GroundType",
    "HeightMap", "MotorElectrical", "MotorParameters", "RoverParameters", "RoverSim", "RoverState",
    "SimOptions", "SimulationDiverged", "Snapshot", "SolverStats", "Stepper", "WheelObstacleContact",
    "WheelSyncResult",
    "command_array",
    "driving_soil", "fast_lcp_active", "make_options", "make_sim", "motor_electrical", "rock_field", "sync_commands",
    "synchronise_wheels", "wheel_jacobian",
]

fast_lcp_active()  # warn on import if the hook is off (once per process)
