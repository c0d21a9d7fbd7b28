# Type stub for ernest_cpp.dynamics (the C++ classes come from ernest_cpp._core.dynamics).
from enum import Enum
from typing import Iterable, Sequence

import numpy as np
import numpy.typing as npt

from .soil import RigidContactParameters, SoilParameters

COMMAND_SIZE: int
STATE_VECTOR_SIZE: int
WHEELS: tuple[str, str, str, str]
STATE_VECTOR_NAMES: tuple[str, ...]
COMMAND_NAMES: tuple[str, ...]

class SimulationDiverged(RuntimeError): ...

class MotorParameters:
    torque_constant: float
    resistance: float
    gear_ratio: float
    efficiency: float
    current_limit: float
    rotor_inertia: float
    def __init__(self) -> None: ...
    def max_output_torque(self) -> float: ...

class MotorElectrical:
    @property
    def current(self) -> float: ...
    @property
    def power(self) -> float: ...

def motor_electrical(m: MotorParameters, output_torque: float, output_speed: float) -> MotorElectrical: ...

class RoverParameters:
    wheelbase: float
    track: float
    wheel_radius: float
    wheel_width: float
    chassis_mass: float
    bogie_mass: float
    wheel_assembly_mass: float
    chassis_com: npt.NDArray[np.float64]
    bogie_com_height: float
    chassis_inertia: npt.NDArray[np.float64]
    bogie_inertia: npt.NDArray[np.float64]
    wheel_spin_inertia: float
    wheel_transverse_inertia: float
    gimbal_height: float
    yaw_limit: float
    roll_limit: float
    stop_stiffness: float
    stop_damping: float
    yaw_brake_torque: float
    clutch_align_speed: float
    clutch_align_gain: float
    clutch_align_tolerance: float
    wheel_motor: MotorParameters
    gimbal_motor: MotorParameters
    fts_height: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    def total_mass(self) -> float: ...
    def wheel_centre(self, i: int) -> npt.NDArray[np.float64]: ...
    def gimbal_point(self) -> npt.NDArray[np.float64]: ...

class HeightMap:
    def __init__(self, heights: npt.ArrayLike, spacing: float, origin_x: float, origin_y: float) -> None: ...
    @staticmethod
    def flat(length: float, width: float, spacing: float, z: float = 0.0, x0: float = -5.0,
             y0: float = -5.0) -> HeightMap: ...
    @staticmethod
    def slope(angle: float, length: float, width: float, spacing: float, x0: float = -5.0,
              y0: float = -5.0) -> HeightMap: ...
    def height(self, x: float, y: float) -> float: ...
    def normal(self, x: float, y: float) -> npt.NDArray[np.float64]: ...
    def height_normal(self, x: float, y: float) -> tuple[float, npt.NDArray[np.float64]]: ...
    @property
    def heights(self) -> npt.NDArray[np.float64]: ...
    @property
    def spacing(self) -> float: ...
    @property
    def origin_x(self) -> float: ...
    @property
    def origin_y(self) -> float: ...

class BoxObstacle:
    centre: npt.NDArray[np.float64]
    size: npt.NDArray[np.float64]
    yaw: float
    pitch: float
    roll: float
    def __init__(self, centre: npt.ArrayLike, size: npt.ArrayLike, yaw: float = 0.0,
                 pitch: float = 0.0, roll: float = 0.0) -> None: ...

class GroundType(Enum):
    Soil = 0
    Rigid = 1

class Stepper(Enum):
    Ode = 0
    Own = 1

class WheelObstacleContact(Enum):
    Ode = 0
    Exact = 1

class ActuatorMode(Enum):
    Velocity = 0
    Torque = 1
    Off = 2

class ClutchState(Enum):
    Disengaged = 0
    Aligning = 1
    Engaged = 2

class SimOptions:
    dt: float
    seed: int
    ground: GroundType
    soil: SoilParameters
    soil_points_per_panel: int
    soil_normal_damping: float
    rigid: RigidContactParameters
    friction: float | None
    rigid_slip: float
    rigid_tyre_stiffness_x: float
    rigid_tyre_stiffness_y: float
    rigid_tyre_damping: float
    guess_active_set: bool
    guess_obstacle_contacts: bool
    sparse_lcp: bool
    stepper: Stepper
    wheel_obstacle_contact: WheelObstacleContact
    resolve_rhs_only: bool
    max_speed: float
    max_angular_speed: float
    slip_force_tolerance: float
    slip_warm_start: bool
    obstacle_substeps: int
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class SolverStats:
    steps: int
    first_guess: int
    later_guess: int
    pivoted: int
    lcp_errors: int
    sparse_solves: int
    dense_solves: int
    slip_solves: int
    slip_driving: int
    obstacle_guessed: int
    obstacle_bounded: int
    obstacle_explicit: int
    obstacle_implicit: int
    own_steps: int
    own_fallbacks: int
    rhs_resolves: int
    cap_resolves: int
    plans_made: int
    plans_grown: int
    obstacles_touched: int
    fast_lcp: bool

class Commands:
    wheel_speed: list[float]
    wheel_torque: list[float]
    wheel_mode: ActuatorMode
    yaw_rate: float
    roll_rate: float
    yaw_torque: float
    roll_torque: float
    yaw_mode: ActuatorMode
    roll_mode: ActuatorMode
    gimbal_enabled: bool
    clutch_engage: bool
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class RoverState:
    time: float
    position: npt.NDArray[np.float64]
    quaternion: npt.NDArray[np.float64]
    linear_velocity: npt.NDArray[np.float64]
    angular_velocity: npt.NDArray[np.float64]
    body_linear_velocity: npt.NDArray[np.float64]
    body_angular_velocity: npt.NDArray[np.float64]
    roll: float
    pitch: float
    yaw: float
    gimbal_yaw: float
    gimbal_roll: float
    gimbal_yaw_rate: float
    gimbal_roll_rate: float
    yaw_torque: float
    roll_torque: float
    bogie_frame_angle: float
    clutch: ClutchState
    wheel_speed: npt.NDArray[np.float64]
    wheel_torque: npt.NDArray[np.float64]
    wheel_load: npt.NDArray[np.float64]
    sinkage: npt.NDArray[np.float64]
    slip: npt.NDArray[np.float64]
    contact_vx: npt.NDArray[np.float64]
    contact_vy: npt.NDArray[np.float64]
    motor_current: npt.NDArray[np.float64]
    motor_power: npt.NDArray[np.float64]
    wheel_position: npt.NDArray[np.float64]
    fts: npt.NDArray[np.float64]
    energy: float

class Snapshot:
    @property
    def time(self) -> float: ...
    @property
    def state(self) -> RoverState: ...
    @property
    def commands(self) -> Commands: ...

class RoverSim:
    """One thread at a time per RoverSim: a concurrent call raises RuntimeError (no waiting)."""
    def __init__(self, params: RoverParameters, terrain: HeightMap,
                 obstacles: Sequence[BoxObstacle] = ..., options: SimOptions = ...) -> None: ...
    def reset(self, x: float, y: float, heading: float, psi: float = 0.0, phi: float = 0.0,
              speed: float = 0.0) -> None: ...
    def set_commands(self, commands: Commands) -> None: ...
    @property
    def commands(self) -> Commands: ...
    def step(self) -> None: ...
    def step_n(self, n: int) -> None: ...
    @property
    def state(self) -> RoverState: ...
    def state_vector(self) -> npt.NDArray[np.float64]: ...
    @staticmethod
    def state_vector_names() -> list[str]: ...
    def snapshot(self) -> Snapshot: ...
    def restore(self, snapshot: Snapshot) -> None: ...
    def apply_chassis_force(self, force: npt.ArrayLike) -> None: ...
    def kinetic_energy(self) -> float: ...
    def potential_energy(self) -> float: ...
    @property
    def solver_stats(self) -> SolverStats: ...
    @property
    def friction(self) -> float: ...
    @property
    def parameters(self) -> RoverParameters: ...
    @property
    def options(self) -> SimOptions: ...
    @property
    def terrain(self) -> HeightMap: ...

class BatchStepper:
    def __init__(self, sims: Sequence[RoverSim], threads: int = 1) -> None: ...
    def step(self, commands: npt.ArrayLike | None, n_steps: int = 1) -> npt.NDArray[np.float64]: ...
    @property
    def size(self) -> int: ...
    @property
    def threads(self) -> int: ...
    def sim(self, i: int) -> RoverSim: ...

class WheelSyncResult:
    @property
    def x(self) -> npt.NDArray[np.float64]: ...
    @property
    def wheel_speeds(self) -> npt.NDArray[np.float64]: ...
    @property
    def residual(self) -> float: ...
    @property
    def A(self) -> npt.NDArray[np.float64]: ...
    @property
    def y(self) -> npt.NDArray[np.float64]: ...

def wheel_jacobian(p: RoverParameters, psi: float, phi: float, wheel: int) -> npt.NDArray[np.float64]: ...
def synchronise_wheels(p: RoverParameters, psi: float, phi: float, vx: float, wx: float,
                       wy: float, psi_dot: float, phi_dot: float) -> WheelSyncResult: ...
def driving_soil(name: str) -> SoilParameters: ...
def make_options(ground: str = "soil", soil: str | SoilParameters = "m90", dt: float | None = None,
                 seed: int = 0, friction: float | None = None, guess_active_set: bool = True,
                 sparse_lcp: bool = True) -> SimOptions: ...
def rock_field(n: int = 20, seed: int = 0, length: float = 6.0, width: float = 2.0,
               x0: float = 0.8, size: tuple[float, float] = (0.06, 0.16)) -> list[BoxObstacle]: ...
def make_sim(ground: str = "soil", terrain: HeightMap | None = None,
             obstacles: Iterable[BoxObstacle] = (), params: RoverParameters | None = None,
             options: SimOptions | None = None, **option_kwargs: object) -> RoverSim: ...
def sync_commands(sim: RoverSim, vx: float, yaw_rate: float = 0.0, roll_rate: float = 0.0,
                  gimbal_enabled: bool = True, clutch_engage: bool = False) -> Commands: ...
def command_array(rows: Sequence[Sequence[float]]) -> npt.NDArray[np.float64]: ...
def fast_lcp_active() -> bool: ...
