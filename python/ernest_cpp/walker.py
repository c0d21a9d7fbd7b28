"""ATHLETE-class wheel-on-leg walker (seed 003 §2.3, §5.3): the SDM-B and T12 models with their
documented parameters, forward kinematics, multi-start inverse kinematics inside the joint limits,
contact Jacobians, static joint torques ``tau = J^T f + g(q)`` and margins to saturation
(Figs 15–16), per-link collision capsules and an FCL self-collision check, the weight distribution with legs lifted (Fig. 16),
the sway gait (Figs 14–15) and FootFall's skeleton gait (§5.3.1: reverse wave,
step lengths by successive IK). The work is done in C++ (``ernest_cpp._core.walker``);
this module re-exports it.

Poses are 4 × 4 homogeneous matrices (body frame for the legs, world for the body); a whole-robot
configuration is an array of shape ``(joints_per_leg, legs)``.
"""

from __future__ import annotations

from ._core.walker import (  # noqa: F401  (re-exports)
    CHASSIS,
    Capsule,
    CollisionPair,
    GaitEvent,
    GaitEventKind,
    GaitPhase,
    GaitPlan,
    GaitPlannerOptions,
    IkOptions,
    IkResult,
    IkStatus,
    JointSpec,
    LegIk,
    LinkCapsule,
    StanceLoads,
    SwayGaitOptions,
    SwayGaitResult,
    WalkerModel,
    WalkerParameters,
    evaluate_gait_phase,
    lift_legs,
    optimise_sway_gait,
    plan_gait,
    reverse_wave_sequence,
    sdm_b_parameters,
    self_collisions,
    stance_loads,
    t12_parameters,
    upright_foot_pose,
)

__all__ = [
    "CHASSIS",
    "Capsule",
    "CollisionPair",
    "GaitEvent",
    "GaitEventKind",
    "GaitPhase",
    "GaitPlan",
    "GaitPlannerOptions",
    "IkOptions",
    "IkResult",
    "IkStatus",
    "JointSpec",
    "LegIk",
    "LinkCapsule",
    "StanceLoads",
    "SwayGaitOptions",
    "SwayGaitResult",
    "WalkerModel",
    "WalkerParameters",
    "evaluate_gait_phase",
    "lift_legs",
    "optimise_sway_gait",
    "plan_gait",
    "reverse_wave_sequence",
    "sdm_b_parameters",
    "self_collisions",
    "stance_loads",
    "t12_parameters",
    "upright_foot_pose",
]
