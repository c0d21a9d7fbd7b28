"""The ATHLETE walker in the 3D view: a FootFall gait cycle executed in ODE
(``walker_sim.run_footfall_cycle``) as a recording, and its scene: the six legs posed from
``WalkerModel`` (each link capsule per frame), the body, the support polygon of the feet on the
ground, the current step's stability map cells (stable green, unstable red) and its planned leg
path, the rocks as boxes over the planner's height map."""

from __future__ import annotations

import numpy as np

from .recording import Recording

STANCE_HEIGHT = 0.03  #: a foot within this of the ground bears load [m]
LEG_RGB = (200, 60, 40)
BODY_RGB = (40, 40, 45)
SUPPORT_RGB = (250, 200, 0)
PATH_RGB = (30, 110, 255)
STABLE_RGB = (40, 170, 60)
UNSTABLE_RGB = (215, 40, 40)


def _ground(terrain, xy: np.ndarray) -> np.ndarray:
    return np.array([terrain.height(float(x), float(y)) for x, y in xy])


def cycle_recording(model, result, rocks, terrain, seed: int | None = None) -> Recording:
    """The recording of an executed gait cycle (``footfall_cycle.run``'s result, its rocks and the
    planner's HeightMap). Needs frames: ``FootfallCycleOptions.execution.frame_interval`` set."""
    t = np.asarray(result.frame_time, dtype=np.float64)
    if t.size == 0:
        raise ValueError("result has no frames: set execution.frame_interval for a recording")
    n = t.size
    bodies = [np.asarray(b) for b in result.frame_body]
    qs = [np.asarray(q) for q in result.frame_q]
    links = np.empty((n, len(model.capsules(bodies[0], qs[0])), 2, 3), np.float32)
    feet = np.empty((n, model.legs, 3), np.float32)
    radius = None
    for k in range(n):
        caps = model.capsules(bodies[k], qs[k])
        links[k] = [[c.p0, c.p1] for c in caps]
        if radius is None:
            radius = np.array([c.radius for c in caps], np.float32)
        feet[k] = np.asarray(model.contact_points(bodies[k], qs[k])).T
    ground = _ground(terrain, feet.reshape(-1, 3)[:, :2]).reshape(n, model.legs)
    stance = (feet[:, :, 2] - ground < STANCE_HEIGHT).astype(np.uint8)
    # the step a frame belongs to: the last one whose leg has been off the ground so far
    legs = [s.leg for s in result.steps]
    step = np.full(n, 0, np.int32)
    current, nxt = 0, 0
    for k in range(n):
        lifted = np.flatnonzero(stance[k] == 0)
        if nxt < len(legs) and legs[nxt] in lifted:
            current, nxt = nxt, nxt + 1
        step[k] = current
    cells, paths = [], []
    from .. import footfall as F

    for i, s in enumerate(result.steps):
        a = F.map_arrays(s.map)
        ix, iy = np.nonzero(a["status"] > 0)
        cells.append(np.stack([np.full(ix.size, i), a["x"][ix], a["y"][iy], a["status"][ix, iy]], 1))
        if s.plan.solved:
            w = np.asarray(s.planned_wheel).T
            paths.append(np.column_stack([np.full(len(w), i), w]))
    hips = np.array([np.asarray(model.hip_mount(k))[:3, 3] for k in range(model.legs)], np.float32)
    obstacles = np.array([[*np.asarray(r.centre), *(2 * np.asarray(r.half_extents)), r.yaw, 0.0, 0.0]
                          for r in rocks], np.float32).reshape(-1, 9)
    return Recording(
        meta={"kind": "walker", "scenario": "footfall cycle", "episode_seed": seed,
              "completed": bool(result.completed), "legs": [int(v) for v in legs]},
        heights=np.asarray(terrain.heights, np.float32), spacing=float(terrain.spacing),
        origin=(float(terrain.origin_x), float(terrain.origin_y)), obstacles=obstacles,
        path=(0.0, 0.0, 0.0),
        frames={"time": t, "links": links, "body": np.asarray(bodies, np.float32), "feet": feet,
                "stance": stance, "step": step},
        static={"link_radius": radius, "hips": hips,
                "cells": np.concatenate(cells).astype(np.float32) if cells else np.zeros((0, 4), np.float32),
                "paths": np.concatenate(paths).astype(np.float32) if paths else np.zeros((0, 4), np.float32)})


def _segments(points: np.ndarray) -> np.ndarray:
    p = np.asarray(points, np.float32).reshape(-1, 3)
    if len(p) < 2:
        p = np.concatenate([p, p]) if len(p) else np.zeros((2, 3), np.float32)
    return np.stack([p[:-1], p[1:]], axis=1)


def convex_hull(xy: np.ndarray) -> np.ndarray:
    """Indices of the convex hull of 2-D points, counter-clockwise (monotone chain)."""
    pts = sorted(range(len(xy)), key=lambda i: (xy[i][0], xy[i][1]))
    if len(pts) < 3:
        return np.asarray(pts, int)

    def cross(o, a, b):
        return (xy[a][0] - xy[o][0]) * (xy[b][1] - xy[o][1]) - (xy[a][1] - xy[o][1]) * (xy[b][0] - xy[o][0])

    lower, upper = [], []
    for i in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], i) <= 0:
            lower.pop()
        lower.append(i)
    for i in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], i) <= 0:
            upper.pop()
        upper.append(i)
    return np.asarray(lower[:-1] + upper[:-1], int)


class WalkerScene:
    """The walker's layers on a viser server, posed frame by frame (``show``)."""

    LAYERS = ("terrain", "obstacles", "walker", "support", "stability map", "leg path", "track")

    def __init__(self, server, rec: Recording):
        from .scene import add_terrain, setup_lights

        self.server = server
        self.rec = rec
        sc = server.scene
        sc.set_up_direction("+z")
        setup_lights(server)
        self.layers = {name: sc.add_frame("/" + name.replace(" ", "_"), show_axes=False)
                       for name in self.LAYERS}
        add_terrain(server, rec.heights, rec.spacing, rec.origin, rec.obstacles)
        r = float(np.mean(rec.static["link_radius"])) if rec.static["link_radius"].size else 0.05
        n_links = rec.frames["links"].shape[1]
        self.links = sc.add_line_segments("/walker/links", np.zeros((n_links, 2, 3), np.float32),
                                          colors=LEG_RGB, thickness=2 * r, thickness_units="world")
        self.body = sc.add_line_segments("/walker/body", np.zeros((6, 2, 3), np.float32),
                                         colors=BODY_RGB, thickness=0.12, thickness_units="world")
        self.feet = sc.add_point_cloud("/walker/feet", np.zeros((6, 3), np.float32),
                                       colors=(20, 20, 20), point_size=0.12, point_shape="circle")
        self.support = sc.add_line_segments("/support/polygon", np.zeros((1, 2, 3), np.float32),
                                            colors=SUPPORT_RGB, thickness=4.0,
                                            thickness_units="screen")
        self.cells = sc.add_point_cloud("/stability_map/cells", np.zeros((1, 3), np.float32),
                                        colors=STABLE_RGB, point_size=0.025, point_shape="square")
        self.leg_path = sc.add_line_segments("/leg_path/planned", np.zeros((1, 2, 3), np.float32),
                                             colors=PATH_RGB, thickness=3.0,
                                             thickness_units="screen")
        self.trail = sc.add_line_segments("/track/body", np.zeros((1, 2, 3), np.float32),
                                          colors=(255, 255, 255), thickness=2.0,
                                          thickness_units="screen")
        self.checkboxes: dict = {}
        self._step = None

    def add_layer_switches(self, gui) -> None:
        with gui.add_folder("Layers"):
            for name in self.LAYERS:
                box = gui.add_checkbox(name, True)
                box.on_update(lambda ev, name=name: setattr(self.layers[name], "visible",
                                                            bool(ev.target.value)))
                self.checkboxes[name] = box

    def _show_step(self, i: int) -> None:
        cells = self.rec.static["cells"]
        c = cells[cells[:, 0] == i]
        if len(c):
            xy = c[:, 1:3]
            z = np.array([self._height(x, y) for x, y in xy], np.float32) + 0.01
            self.cells.points = np.column_stack([xy, z]).astype(np.float32)
            self.cells.colors = np.where((c[:, 3] == 2)[:, None], STABLE_RGB, UNSTABLE_RGB).astype(np.uint8)
        paths = self.rec.static["paths"]
        self.leg_path.points = _segments(paths[paths[:, 0] == i][:, 1:4])
        self._step = i

    def _height(self, x: float, y: float) -> float:
        h = self.rec.heights
        i = int(np.clip(round((x - self.rec.origin[0]) / self.rec.spacing), 0, h.shape[0] - 1))
        j = int(np.clip(round((y - self.rec.origin[1]) / self.rec.spacing), 0, h.shape[1] - 1))
        return float(h[i, j])

    def show(self, frame: dict, track: np.ndarray | None = None) -> None:
        body = np.asarray(frame["body"], np.float64)
        hips = self.rec.static["hips"] @ body[:3, :3].T + body[:3, 3]
        loop = np.concatenate([hips, hips[:1]])
        feet = np.asarray(frame["feet"], np.float32)
        on = np.flatnonzero(np.asarray(frame["stance"]) > 0)
        with self.server.atomic():
            self.links.points = np.asarray(frame["links"], np.float32)
            self.body.points = _segments(loop)
            self.feet.points = feet
            if len(on) >= 3:
                hull = on[convex_hull(feet[on, :2])]
                ring = feet[np.concatenate([hull, hull[:1]])].copy()
                ring[:, 2] += 0.02
                self.support.points = _segments(ring)
            step = int(frame["step"])
            if step != self._step:
                self._show_step(step)
            if track is not None:
                self.trail.points = _segments(np.asarray(track, np.float32))


class WalkerPlots:
    """Body advance and height, and the number of feet on the ground, up to the current frame."""

    def __init__(self, gui, frames: dict):
        from .scene import _series, _x_seconds

        self.frames = frames
        with gui.add_folder("Time series", expand_by_default=True):
            self.body = gui.add_uplot(data=self._data(1)[0], title="body [m]",
                                      series=(_series("t [s]"), _series("x", "#4363d8"),
                                              _series("z", "#e6194b")), aspect=2.0,
                                      scales=_x_seconds())
            self.stance = gui.add_uplot(data=self._data(1)[1], title="feet on the ground",
                                        series=(_series("t [s]"), _series("feet", "#3cb44b")),
                                        aspect=2.0, scales=_x_seconds())

    def _data(self, n: int):
        f = self.frames
        t = np.asarray(f["time"][:n], np.float64)
        b = np.asarray(f["body"][:n], np.float64)
        return ((t, b[:, 0, 3], b[:, 2, 3]),
                (t, np.asarray(f["stance"][:n], np.float64).sum(axis=1)))

    def show(self, n: int) -> None:
        self.body.data, self.stance.data = self._data(max(1, n))
