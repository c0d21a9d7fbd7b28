# Type stub for ernest_cpp.statics (the C++ classes come from ernest_cpp._core.statics).
import numpy as np
import numpy.typing as npt

from .dynamics import RoverParameters, RoverState

MASS_MODEL_PARAMETERS: list[str]

class MassModel:
    chassis_mass: float
    bogie_mass: float
    chassis_com: npt.NDArray[np.float64]
    bogie_com_height: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    def vector(self) -> npt.NDArray[np.float64]: ...
    @staticmethod
    def from_vector(v: npt.ArrayLike) -> MassModel: ...
    @staticmethod
    def from_parameters(p: RoverParameters) -> MassModel: ...

class RoverGeometry:
    wheelbase: float
    track: float
    wheel_radius: float
    tube_radius: float
    gimbal_height: float
    gravity: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...
    @staticmethod
    def from_parameters(p: RoverParameters, gravity: float = 9.81) -> RoverGeometry: ...

class LoadPose:
    chassis_quaternion: npt.NDArray[np.float64]
    psi: float
    phi: float
    roll_torque: float
    ground_normal: npt.NDArray[np.float64]
    loads: npt.NDArray[np.float64]
    horizontal_forces: npt.NDArray[np.float64]
    def __init__(self) -> None: ...
    def validate(self, index: int | None = None) -> None: ...

class LoadEquations:
    @property
    def A(self) -> npt.NDArray[np.float64]: ...
    @property
    def b(self) -> npt.NDArray[np.float64]: ...
    @property
    def t(self) -> npt.NDArray[np.float64]: ...
    @property
    def contact(self) -> list[npt.NDArray[np.float64]]: ...

def load_equations(model: MassModel, geometry: RoverGeometry, pose: LoadPose) -> LoadEquations: ...
def predict_loads(model: MassModel, geometry: RoverGeometry, pose: LoadPose) -> npt.NDArray[np.float64]: ...

class MassFitOptions:
    max_evaluations: int
    tolerance: float
    fixed: list[bool]
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class MassFitResult:
    @property
    def model(self) -> MassModel: ...
    @property
    def std_error(self) -> npt.NDArray[np.float64]: ...
    @property
    def covariance(self) -> npt.NDArray[np.float64]: ...
    @property
    def r_squared(self) -> float: ...
    @property
    def rmse(self) -> float: ...
    @property
    def residual_sigma(self) -> float: ...
    @property
    def evaluations(self) -> int: ...
    @property
    def rank(self) -> int: ...
    @property
    def identifiable(self) -> list[bool]: ...
    @property
    def converged(self) -> bool: ...
    @property
    def status(self) -> str: ...

def fit_mass_model(poses: list[LoadPose], geometry: RoverGeometry, initial: MassModel = ...,
                   options: MassFitOptions = ...) -> MassFitResult: ...

class SurveyOptions:
    yaws_deg: list[float]
    slopes_deg: list[float]
    headings_deg: list[float]
    block_height: float
    settle_time: float
    average_time: float
    friction: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

def survey_loads(params: RoverParameters, options: SurveyOptions = ...) -> list[LoadPose]: ...
def pose_from_state(params: RoverParameters, state: RoverState, gravity: float,
                    ground_normal: npt.ArrayLike = ...) -> LoadPose: ...

class LiftoffOptions:
    min_load: float
    torque_limit: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class LiftoffLimit:
    @property
    def torque(self) -> float: ...
    @property
    def loads(self) -> npt.NDArray[np.float64]: ...
    @property
    def lifted_wheel(self) -> int: ...
    @property
    def torque_limited(self) -> bool: ...

class LiftoffResult:
    @property
    def feasible(self) -> bool: ...
    @property
    def loads_at_zero(self) -> npt.NDArray[np.float64]: ...
    @property
    def positive(self) -> LiftoffLimit: ...
    @property
    def negative(self) -> LiftoffLimit: ...

def max_roll_torque(model: MassModel, geometry: RoverGeometry, pose: LoadPose,
                    options: LiftoffOptions = ...) -> LiftoffResult: ...
def slope_pose(slope: float, heading: float, psi: float) -> LoadPose: ...

# Point sets are (3, N) float arrays.
from enum import Enum
from typing import Sequence

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
Array = npt.NDArray[np.float64]

MAX_CONTACTS: int
EARTH_GRAVITY: Array

class ProjectionFrame:
    up: Array
    e1: Array
    e2: Array
    def __init__(self) -> None: ...
    @staticmethod
    def from_gravity(gravity: ArrayLike) -> ProjectionFrame: ...
    def project(self, p: ArrayLike) -> Array: ...

class Polygon:
    @property
    def size(self) -> int: ...
    @property
    def vertices(self) -> Array: ...
    @property
    def edge_contacts(self) -> list[tuple[int, int]]: ...
    def area(self) -> float: ...
    def signed_distance(self, q: ArrayLike) -> float: ...

class StabilityMargins:
    @property
    def support_vertices(self) -> int: ...
    @property
    def cps_vertices(self) -> int: ...
    @property
    def ssm(self) -> float: ...
    @property
    def nesm(self) -> float: ...
    @property
    def ssm_cps(self) -> float: ...
    @property
    def nesm_cps(self) -> float: ...

def support_polygon(contacts: ArrayLike, frame: ProjectionFrame) -> Polygon: ...
def conservative_support_polygon(contacts: ArrayLike, frame: ProjectionFrame) -> Polygon: ...
def nesm_edge(a: ArrayLike, b: ArrayLike, cg: ArrayLike, up: ArrayLike, inside: bool) -> float: ...
def static_stability_margin(polygon: Polygon, cg: ArrayLike, frame: ProjectionFrame) -> float: ...
def energy_stability_margin(polygon: Polygon, contacts: ArrayLike, cg: ArrayLike,
                            frame: ProjectionFrame) -> float: ...
def stability_margins(contacts: ArrayLike, cg: ArrayLike, gravity: ArrayLike) -> StabilityMargins: ...

class DistributionInfo:
    @property
    def rank(self) -> int: ...
    @property
    def residual(self) -> float: ...

def zero_interaction_forces(contacts: ArrayLike, cg: ArrayLike, mass: float,
                            gravity: ArrayLike) -> tuple[Array, DistributionInfo]: ...

class SagProblem:
    feet: Array
    stiffness: Array
    lift: Array
    cg: Array
    mass: float
    gravity: Array
    spring_frame: Array
    chassis_position: Array
    chassis_rotation: Array
    body_points: Array
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class SagOptions:
    max_evaluations: int
    tolerance: float
    equilibrium_tolerance: float
    contact_tolerance: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class SagStatus(Enum):
    Converged = ...
    Unstable = ...
    NotConverged = ...

class SagResult:
    status: SagStatus
    forces: Array
    deflections: Array
    compression: Array
    cg: Array
    rotation: Array
    translation: Array
    chassis_position: Array
    chassis_rotation: Array
    body_points: Array
    loaded: int
    equilibrium_residual: float
    rigidity_residual: float
    evaluations: int

def solve_sag(problem: SagProblem, options: SagOptions = ...) -> SagResult: ...

class CalibrationStance:
    problem: SagProblem
    measured_heights: Array
    def __init__(self, problem: SagProblem = ..., measured_heights: ArrayLike = ...) -> None: ...

class CalibrationOptions:
    k_min: float
    k_max: float
    grid_points: int
    refine: bool
    brent_bits: int
    sag: SagOptions
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class CalibrationResult:
    k_grid: float
    error_grid: float
    k: float
    mean_error: float
    max_error: float
    grid_k: Array
    grid_error: Array
    sag_solves: int

class PerFootCalibrationResult:
    k: Array
    mean_error: float
    max_error: float
    sag_solves: int
    lm_status: int

def calibrate_per_foot_constants(stances: Sequence[CalibrationStance], k_initial: float,
                                 options: SagOptions = ...) -> PerFootCalibrationResult: ...
def mean_height_error(stances: Sequence[CalibrationStance], k: float,
                      options: SagOptions = ...) -> float: ...
def calibrate_spring_constant(stances: Sequence[CalibrationStance],
                              options: CalibrationOptions = ...) -> CalibrationResult: ...
def sag_problem(feet: ArrayLike, cg: ArrayLike, mass: float, stiffness: ArrayLike,
                lift: ArrayLike | None = ..., gravity: ArrayLike | None = ...,
                body_points: ArrayLike | None = ..., chassis_position: ArrayLike | None = ...,
                chassis_rotation: ArrayLike | None = ...,
                spring_frame: ArrayLike | None = ...) -> SagProblem: ...
def lift_foot(problem: SagProblem, index: int, dh: float) -> SagProblem: ...
