"""Bekker–Wong wheel–soil model (seed 004 §3.3, eqs 12–32), rigid contact (§3.4) and a
single-wheel rig. The model itself is C++ (``ernest_cpp._core.soil``); this module re-exports
it and adds numpy conveniences.
"""

from __future__ import annotations

import numpy as np

from ._core.soil import (  # noqa: F401  (re-exports)
    DEFAULT_POINTS_PER_PANEL,
    BekkerWongModel,
    ContactState,
    RigidContactParameters,
    RigOptions,
    RigResult,
    SoilParameters,
    WheelGeometry,
    WheelSoilForce,
    rig_state,
    slip_ratio,
    slip_sweep,
    solve_equilibrium,
)

#: Standard gravity and Mars surface gravity [m/s^2].
EARTH_GRAVITY = 9.81
MARS_GRAVITY = 3.721

SWEEP_COLUMNS = ("slip", "model_slip", "sinkage", "drawbar_pull", "normal_force", "torque",
                 "converged")


def soil_preset(name: str, gravity: float = EARTH_GRAVITY) -> SoilParameters:
    """Soil preset by name ('dry_sand', 'm90', 'wet_sand') with the given gravity."""
    p = SoilParameters.preset(name)
    p.gravity = gravity
    p.validate()
    return p


def ernest_wheel() -> WheelGeometry:
    """ERNEST's wheel (seed 004 Table 1): diameter 0.34 m, width 0.13 m."""
    return WheelGeometry(radius=0.17, width=0.13)


def drawbar_curve(soil: SoilParameters | str, load: float, slips=None,
                  wheel: WheelGeometry | None = None, carriage_speed: float = 0.2,
                  points_per_panel: int = DEFAULT_POINTS_PER_PANEL) -> dict[str, np.ndarray]:
    """Equilibrium sinkage, drawbar pull and torque over a slip sweep at a fixed vertical load.

    Returns a dict of numpy arrays keyed by :data:`SWEEP_COLUMNS` (``converged`` as bool).
    """
    if isinstance(soil, str):
        soil = soil_preset(soil)
    slips = np.linspace(-0.9, 0.9, 37) if slips is None else np.asarray(slips, dtype=float)
    if slips.ndim != 1 or slips.size == 0:
        raise ValueError("slips must be a non-empty 1-D array")
    model = BekkerWongModel(soil, wheel or ernest_wheel(), points_per_panel)
    opts = RigOptions()
    opts.carriage_speed = carriage_speed
    table = slip_sweep(model, float(load), slips, opts)
    out = {name: table[:, i] for i, name in enumerate(SWEEP_COLUMNS)}
    out["converged"] = out["converged"].astype(bool)
    return out
