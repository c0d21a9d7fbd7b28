# Type stub for ernest_cpp.statics (the C++ classes come from ernest_cpp._core.statics).
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
