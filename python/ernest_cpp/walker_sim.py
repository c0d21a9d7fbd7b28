"""The wheel-on-leg walker in ODE (beyond seed 003: executing FootFall's plans in simulation, §4.1):
chassis and links as ODE bodies, joints as hinges under position control (hinge motors), wheels on
compliant contacts (seed 003 eq 3's spring k_zz through ODE's contact ERP/CFM), flat ground and box
rocks; joint-path execution with the swing wheel's clearance to rocks and ground; and the Moses Lake
scenario (§4.1): a swing planned against the rigid pose hits a rock the sag-compensated plan
(cpp/statics sag model, §5.1.1) clears. The work is done in C++ (``ernest_cpp._core.walker_sim``);
this module re-exports it.
"""

from __future__ import annotations

from ._core.walker_sim import (  # noqa: F401  (re-exports)
    ExecutionOptions,
    ExecutionTrace,
    FootfallCycleOptions,
    FootfallCycleResult,
    FootfallStepRecord,
    GaitExecution,
    Rock,
    RockMapOptions,
    SagScenarioOptions,
    SagScenarioResult,
    SwingPlan,
    WalkerSim,
    WalkerSimDiverged,
    WalkerSimOptions,
    box_rock_field,
    execute_configuration_path,
    execute_gait_cycle,
    execute_joint_path,
    planned_clearance,
    rock_height_map,
    run_footfall_cycle,
    run_sag_scenario,
    swing_path,
    wheel_rock_clearance,
)

__all__ = [
    "ExecutionOptions",
    "ExecutionTrace",
    "FootfallCycleOptions",
    "FootfallCycleResult",
    "FootfallStepRecord",
    "GaitExecution",
    "Rock",
    "RockMapOptions",
    "SagScenarioOptions",
    "SagScenarioResult",
    "SwingPlan",
    "WalkerSim",
    "WalkerSimDiverged",
    "WalkerSimOptions",
    "box_rock_field",
    "execute_configuration_path",
    "execute_gait_cycle",
    "execute_joint_path",
    "planned_clearance",
    "rock_height_map",
    "run_footfall_cycle",
    "run_sag_scenario",
    "swing_path",
    "wheel_rock_clearance",
]
