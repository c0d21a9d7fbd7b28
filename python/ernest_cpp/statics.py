"""Statics of rovers on their contacts (C++: ``ernest_cpp._core.statics``).

ERNEST (seed 004): the two-body mass model of §3.2 and its Levenberg–Marquardt identification
(eq 11) from force–torque-sensor loads, a simulated load survey, and the largest roll torque the
clutch can apply before a wheel lifts off (Fig. 25, a linear program solved by GLPK). Helpers in
``ernest_cpp.rover_statics``. Invalid input raises ``ValueError`` naming the field.
"""

from __future__ import annotations

from ._core.statics import (  # noqa: F401  (re-exports)
    MASS_MODEL_PARAMETERS,
    LiftoffLimit,
    LiftoffOptions,
    LiftoffResult,
    LoadEquations,
    LoadPose,
    MassFitOptions,
    MassFitResult,
    MassModel,
    RoverGeometry,
    SurveyOptions,
    fit_mass_model,
    load_equations,
    max_roll_torque,
    pose_from_state,
    predict_loads,
    slope_pose,
    survey_loads,
)

__all__ = [
    "MASS_MODEL_PARAMETERS", "LiftoffLimit", "LiftoffOptions", "LiftoffResult", "LoadEquations",
    "LoadPose", "MassFitOptions", "MassFitResult", "MassModel", "RoverGeometry", "SurveyOptions",
    "fit_mass_model", "load_equations", "max_roll_torque", "pose_from_state", "predict_loads",
    "slope_pose", "survey_loads",
]
