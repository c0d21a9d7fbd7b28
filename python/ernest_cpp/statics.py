"""Statics of any set of ground contacts (seed 003, FootFall): stability margins (§3.3), the
zero-interaction force distribution (§5.1.1), the compliance (sag) model (§5.1.1, eqs 1–12) and
its spring-constant calibration (§5.1.3–5.1.4); and for ERNEST (seed 004) the two-body mass model
of §3.2 with its Levenberg–Marquardt identification (eq 11) from force–torque-sensor loads, a
simulated load survey, and the largest roll torque the clutch can apply before a wheel lifts off
(Fig. 25, a linear program solved by GLPK; helpers in ``ernest_cpp.rover_statics``).

The work is done in C++ (``ernest_cpp._core.statics``); this module re-exports it and adds
numpy conveniences. Point sets are ``(3, N)`` arrays (one column per contact), as in C++; a wrong
shape, a NaN or a non-positive spring raises ``ValueError`` naming the argument or field.

Example::

    import numpy as np
    from ernest_cpp import statics as S
    feet = np.array([[2.5 * np.cos(t), 2.5 * np.sin(t), 0.0]
                     for t in np.arange(6) * np.pi / 3]).T          # (3, 6)
    m = S.stability_margins(feet, cg=[0.1, 0.0, 1.75], gravity=S.EARTH_GRAVITY)
    forces, info = S.zero_interaction_forces(feet, [0.1, 0, 1.75], 850.0, S.EARTH_GRAVITY)
    r = S.solve_sag(S.sag_problem(feet, [0.1, 0, 1.75], 850.0, stiffness=1e5))
"""

from __future__ import annotations

import numpy as np

from ._core.statics import (  # noqa: F401  (re-exports)
    MAX_CONTACTS,
    CalibrationOptions,
    CalibrationResult,
    CalibrationStance,
    DistributionInfo,
    PerFootCalibrationResult,
    Polygon,
    ProjectionFrame,
    SagOptions,
    SagProblem,
    SagResult,
    SagStatus,
    StabilityMargins,
    calibrate_per_foot_constants,
    calibrate_spring_constant,
    conservative_support_polygon,
    energy_stability_margin,
    mean_height_error,
    nesm_edge,
    solve_sag,
    stability_margins,
    static_stability_margin,
    support_polygon,
    zero_interaction_forces,
)

from ._core.statics import (  # noqa: F401  (re-exports: ERNEST, seed 004)
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

#: Standard gravity as a world vector (z up) [m/s^2].
EARTH_GRAVITY = np.array([0.0, 0.0, -9.81])


def sag_problem(feet, cg, mass: float, stiffness, lift=None, gravity=None, body_points=None,
                chassis_position=None, chassis_rotation=None,
                spring_frame=None) -> SagProblem:
    """Build a :class:`SagProblem`.

    ``feet`` is (3, N); ``stiffness`` a scalar (every spring), a (3,) array (k_xx, k_yy, k_zz for
    every foot) or a (3, N) array; ``lift`` (N,) Δh per foot (eq 9, ``inf`` = in the air);
    ``body_points`` (3, M) rigid-body points to carry to their sagged position. The problem is
    validated (``ValueError`` naming the field).
    """
    p = SagProblem()
    p.feet = np.asarray(feet, dtype=float)
    n = p.feet.shape[1]
    k = np.asarray(stiffness, dtype=float)
    if k.ndim == 0:
        k = np.full((3, n), float(k))
    elif k.shape == (3,):
        k = np.repeat(k[:, None], n, axis=1)
    p.stiffness = k
    p.cg = np.asarray(cg, dtype=float)
    p.mass = float(mass)
    if lift is not None:
        p.lift = np.asarray(lift, dtype=float)
    if gravity is not None:
        p.gravity = np.asarray(gravity, dtype=float)
    if body_points is not None:
        p.body_points = np.asarray(body_points, dtype=float)
    if chassis_position is not None:
        p.chassis_position = np.asarray(chassis_position, dtype=float)
    if chassis_rotation is not None:
        p.chassis_rotation = np.asarray(chassis_rotation, dtype=float)
    if spring_frame is not None:
        p.spring_frame = np.asarray(spring_frame, dtype=float)
    p.validate()
    return p


def lift_foot(problem: SagProblem, index: int, dh: float) -> SagProblem:
    """Copy of ``problem`` with foot ``index`` raised by ``dh`` along the spring normal above the
    point where it touches (eq 9: the fork moves up by Δh and ``lift[index]`` grows by Δh), as
    FootFall lifts a leg. ``dh = inf`` puts the foot in the air for good."""
    p = SagProblem()
    for name in ("feet", "stiffness", "cg", "mass", "gravity", "spring_frame", "chassis_position",
                 "chassis_rotation", "body_points"):
        setattr(p, name, getattr(problem, name))
    n = problem.feet.shape[1]
    lift = np.array(problem.lift, dtype=float) if len(problem.lift) else np.zeros(n)
    if not 0 <= index < n:
        raise ValueError(f"index = {index} is outside [0, {n - 1}]")
    lift[index] += dh
    if np.isfinite(dh):
        feet = np.array(problem.feet)
        feet[:, index] += dh * np.asarray(problem.spring_frame)[:, 2]
        p.feet = feet
    p.lift = lift
    return p
