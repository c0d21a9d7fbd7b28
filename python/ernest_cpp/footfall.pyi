# Type stub for ernest_cpp.footfall (the C++ classes come from ernest_cpp._core.footfall).
from enum import Enum
from typing import Any

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

class StabilityCriterion(Enum):
    Auto = ...
    SSM = ...
    NESM = ...

class CellStatus(Enum):
    Unreachable = ...
    Unstable = ...
    Stable = ...
    Overloaded = ...

class PlannerType(Enum):
    SBL = ...
    RRTConnect = ...

class PlanStatus(Enum):
    Solved = ...
    NoPlan = ...

class CollisionOptions:
    environment_clearance: float
    own_leg_clearance: float
    clearance_table: Array
    terrain_margin: float
    def __init__(self) -> None: ...
    def validate(self, joints: int) -> None: ...

def default_clearance_table(joints: int) -> Array: ...

class StabilityMapOptions:
    cell: float
    lift_height: float
    min_margin: float
    criterion: StabilityCriterion
    slope_threshold: float
    ik_evaluations: int
    torques: bool
    max_saturation: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class StabilityMap:
    origin_x: float
    origin_y: float
    cell: float
    status: npt.NDArray[np.uint8]
    margin: Array
    nesm: bool
    start_waypoint_reachable: bool
    hip: Array
    reach: float
    ik_solves: int
    saturation: Array
    lift_saturation: float
    def count(self, status: CellStatus) -> int: ...

class CellEvaluation:
    status: CellStatus
    margin: float
    q: Array
    q_above: Array
    cg: Array
    saturation_down: float
    saturation_lifted: float
    saturation: float
    peak_leg: int
    peak_joint: int

class StabilityMapper:
    nesm: bool
    start_above: Array
    start_waypoint_reachable: bool
    def __init__(self, model: Any, terrain: Any, body: Array, q: Array, leg: int,
                 options: StabilityMapOptions = ...) -> None: ...
    def map(self) -> StabilityMap: ...
    def evaluate(self, x: float, y: float, seed: Array) -> CellEvaluation: ...

class LegCollisionChecker:
    def __init__(self, model: Any, terrain: Any, body: Array, q: Array, leg: int,
                 options: CollisionOptions = ...) -> None: ...
    def valid(self, q_leg: Array, include_wheel: bool = True) -> bool: ...
    def motion_valid(self, a: Array, b: Array, epsilon: float, include_wheel: bool = True) -> bool: ...
    def checks(self) -> int: ...

def first_colliding_edge(checker: LegCollisionChecker, path: Array, resolution: float,
                         wheel_free_edges: int = 0) -> int: ...

class PlannerOptions:
    planner: PlannerType
    time_limit: float
    epsilon: float
    range: float | None
    seed: int
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class PlanResult:
    status: PlanStatus
    reason: str
    path: Array
    seconds: float
    length: float
    checks: int
    solved: bool

def path_length(path: Array) -> float: ...

class LegPlanner:
    options: PlannerOptions
    def __init__(self, checker: LegCollisionChecker, options: PlannerOptions = ...) -> None: ...
    def plan(self, start: Array, goal: Array) -> PlanResult: ...
    def simplify_with_ompl(self, path: Array) -> Array: ...

class SmoothingObjective(Enum):
    Length = ...
    PeakTorque = ...

class SmoothingOptions:
    epsilon: float
    min_improvement: float
    max_iterations: int
    max_nodes: int
    objective: SmoothingObjective
    torque_resolution: float
    torque_tolerance: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class SmoothingResult:
    path: Array
    initial_length: float
    length: float
    iterations: int
    edge_checks: int
    seconds: float
    initial_peak_saturation: float
    peak_saturation: float

def smooth_path(checker: LegCollisionChecker, path: Array, options: SmoothingOptions = ...) -> SmoothingResult: ...

class TorquePeak:
    saturation: float
    leg: int
    joint: int

class StanceTorques:
    leg: int
    def __init__(self, model: Any, body: Array, q: Array, leg: int) -> None: ...
    def down(self, q_leg: Array) -> TorquePeak: ...
    def lifted(self, q_leg: Array) -> TorquePeak: ...
    def lifted_segment(self, a: Array, b: Array, resolution: float = ...) -> TorquePeak: ...
    def lifted_path(self, path: Array, resolution: float = ...) -> TorquePeak: ...

def smooth_path_for_torque(checker: LegCollisionChecker, torques: StanceTorques, path: Array,
                           options: SmoothingOptions = ...) -> SmoothingResult: ...

class SwingSagOptions:
    stiffness: float
    lift_height: float
    sag: Any
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class SwingSag:
    status: Any
    rigid_body: Array
    sagged_body: Array
    hip_displacement: Array
    hip_drop: Array
    forces: Array
    lifted_q: Array

def predict_swing_sag(model: Any, body: Array, q: Array, leg: int, options: SwingSagOptions = ...) -> SwingSag: ...

class StepOptions:
    collision: CollisionOptions
    planner: PlannerOptions
    smoothing: SmoothingOptions
    sag: SwingSagOptions
    map: StabilityMapOptions
    sag_compensation: bool
    def __init__(self) -> None: ...
    def validate(self, joints: int) -> None: ...

class StepPlan:
    status: PlanStatus
    reason: str
    sag: SwingSag
    planning_body: Array
    goal: Array
    goal_margin: float
    goal_saturation: float
    path_saturation: float
    q_start: Array
    q_start_above: Array
    q_goal_above: Array
    q_goal: Array
    plan: PlanResult
    smoothing: SmoothingResult
    path: Array
    solved: bool

def plan_step(model: Any, terrain: Any, body: Array, q: Array, leg: int, goal_x: float, goal_y: float,
              options: StepOptions = ...) -> StepPlan: ...

class RockFieldOptions:
    length: float
    centre_x: float
    centre_y: float
    spacing: float
    rocks: int
    min_height: float
    max_height: float
    min_radius: float
    max_radius: float
    keep_clear: float
    inner_radius: float
    seed: int
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

def rock_field(options: RockFieldOptions, keep_clear: Array) -> Any: ...
def sample_waypoints(mapper: StabilityMapper, map: StabilityMap, checker: LegCollisionChecker,
                     count: int, seed: int) -> Array: ...

class MapTerrainOptions:
    spacing: float
    sigma_factor: float
    max_sigma: float
    fill_radius: float
    unknown_height: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class TerrainCell(Enum):
    Observed = ...
    Filled = ...
    Unknown = ...

class MapTerrain:
    @property
    def terrain(self) -> Any: ...
    @property
    def state(self) -> npt.NDArray[np.uint8]: ...
    @property
    def observed(self) -> int: ...
    @property
    def filled(self) -> int: ...
    @property
    def unknown(self) -> int: ...
    @property
    def filled_cells(self) -> int: ...
    @property
    def top(self) -> float: ...
    def unknown_at(self, x: float, y: float) -> bool: ...

def terrain_from_map(map: Any, options: MapTerrainOptions = ...) -> MapTerrain: ...
def terrain_from_arrays(heights: Array, variances: Array, resolution: float, origin_x: float,
                        origin_y: float, options: MapTerrainOptions = ...) -> MapTerrain: ...

def stability_map(model: Any, terrain: Any, body: Array, q: Array, leg: int,
                  options: StabilityMapOptions | None = None) -> dict[str, Any]: ...
def map_arrays(m: StabilityMap) -> dict[str, Any]: ...
def plot_stability_map(arrays: dict[str, Any], path: Any, terrain: Any = None, feet: Any = None,
                       goal: Any = None, title: str = "") -> None: ...
def wheel_track(model: Any, body: Array, leg: int, path: Array, samples: int = 20) -> Array: ...
def plot_leg_path(model: Any, terrain: Any, step: StepPlan, leg: int, path: Any, title: str = "") -> None: ...
