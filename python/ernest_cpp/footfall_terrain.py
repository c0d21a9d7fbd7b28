"""FootFall's terrain from the perception stack: the planner's digital elevation map from stereo
(stereo → fused map) or, as an option, the simulator's ground truth. A stereo pair on a mast above
the walker's body looks round in ``views`` directions (a pan), each frame is rendered from the
ground-truth scene, matched (StereoBM) and fused into the perception stack's elevation map
(``perception.StereoMapper``); ``footfall.terrain_from_map`` then makes the planner's DEM: heights
raised by k sigma, small holes filled from above, unseen areas (under the body, behind rocks)
obstacle columns the leg can neither cross nor stand on (the policy and its reasons:
``cpp/footfall/terrain_map.hpp``).

The mast is ours (the paper's walker maps with its own cameras; the rover masthead of seed 004
looks 30° down from 1.30 m, too shallow to see the ground next to a 1.75 m-high body)."""

from __future__ import annotations

import math

import numpy as np

from . import footfall as F
from . import perception as P

#: terrain sources of ``ernest footfall --terrain``
SOURCES = ("truth", "stereo")


def mast_options(mast: float = 0.5, pitch_deg: float = 50.0, width: int = 640, height: int = 480,
                 map_length: float = 10.0) -> "P.StereoMapperOptions":
    """Stereo mapper options for a pan camera ``mast`` m above the body origin, tilted
    ``pitch_deg`` down (50°: with the 60° vertical field it sees the ground from ~0.4 m to ~6 m
    out from a 2.25 m viewpoint), over a ``map_length`` square elevation map at 1 cm."""
    o = P.StereoMapperOptions()
    o.camera.width, o.camera.height = width, height
    o.camera.mount_position = np.array([0.0, 0.0, mast])
    o.camera.mount_pitch = math.radians(pitch_deg)
    o.map.length = map_length
    return o


def stereo_map(truth, body, views: int = 8, options: "P.StereoMapperOptions | None" = None,
               boxes=()) -> "P.StereoMapper":
    """Fuses ``views`` stereo frames of the scene (``truth``, a HeightMap, and rigid ``boxes``)
    taken from the body pose (4 × 4) turned by 360°/views each time; returns the mapper (its
    ``map`` is the fused ElevationMap)."""
    if views < 1:
        raise ValueError(f"views must be >= 1, got {views}")
    body = np.asarray(body, dtype=float)
    if body.shape != (4, 4) or not np.all(np.isfinite(body)):
        raise ValueError("body must be a finite 4 x 4 pose")
    mapper = P.StereoMapper(truth, list(boxes), options or mast_options())
    for k in range(views):
        a = 2.0 * math.pi * k / views
        yaw = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
        mapper.capture(body[:3, 3], body[:3, :3] @ yaw)
    return mapper


def stereo_terrain(truth, body, views: int = 8, options: "F.MapTerrainOptions | None" = None,
                   mapper_options: "P.StereoMapperOptions | None" = None) -> "F.MapTerrain":
    """The planner's DEM from stereo over ``truth`` seen from ``body`` (see :func:`stereo_map`)."""
    mapper = stereo_map(truth, body, views, mapper_options)
    return F.terrain_from_map(mapper.map, options or F.MapTerrainOptions())


def planner_terrain(source: str, truth, body, **kwargs):
    """The HeightMap the planner uses: ``"truth"`` (the simulator's) or ``"stereo"`` (perception)."""
    if source == "truth":
        return truth
    if source == "stereo":
        return stereo_terrain(truth, body, **kwargs).terrain
    raise ValueError(f"terrain source must be one of {SOURCES}, got {source!r}")


def plan_step_from_stereo(model, truth, body, q, leg: int, goal_x: float, goal_y: float,
                          step_options: "F.StepOptions | None" = None, views: int = 8,
                          options: "F.MapTerrainOptions | None" = None) -> dict:
    """End to end: stereo over the rock field (``truth``) → fused map → planner DEM → a
    sag-compensated step of ``leg`` to (goal_x, goal_y). Returns ``step`` (StepPlan; "no plan"
    with the reason when the goal is unseen), ``terrain`` (MapTerrain) and ``goal_unknown``."""
    t = stereo_terrain(truth, body, views, options)
    step = F.plan_step(model, t.terrain, body, q, leg, goal_x, goal_y, step_options or F.StepOptions())
    return {"step": step, "terrain": t, "goal_unknown": bool(t.unknown_at(goal_x, goal_y))}
