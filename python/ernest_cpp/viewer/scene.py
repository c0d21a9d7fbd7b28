"""The 3D scene in the browser (viser): terrain coloured by elevation, rocks and steps as boxes,
the desired path, the rover's six bodies, the wheel loads as arrows, the travelled track; each a
layer with its own switch, and time series of wheel loads, gimbal angles, actions and power."""

from __future__ import annotations

import math

import numpy as np

from . import geometry as G

CHASSIS_RGB = (225, 70, 25)  # the test finds the rover by this colour
BOGIE_RGB = (40, 110, 225)
WHEEL_RGB = (45, 45, 50)
ROCK_RGB = (120, 118, 112)
PATH_RGB = (30, 200, 255)
TRAIL_RGB = (255, 255, 255)
BACKGROUND = (255, 255, 255)
NO_SHADOW = {"cast_shadow": False, "receive_shadow": False}

LAYERS = ("terrain", "obstacles", "path", "rover", "forces", "track")
WHEELS = ("FL", "FR", "RL", "RR")
WHEEL_COLOURS = ("#e6194b", "#3cb44b", "#4363d8", "#f58231")


def _x_seconds():
    import viser.uplot as U

    return {"x": U.Scale(time=False, auto=True)}


def _series(label, stroke=None, **kw):
    import viser.uplot as U

    return U.Series(label=label, stroke=stroke, width=1.5, **kw) if stroke else U.Series(label=label)


def setup_lights(server) -> None:
    """Plain lights for software WebGL (a headless browser, a remote desktop): no shadows and no
    image-based environment lighting, whose preparation tripled the first frame's time there
    (benchmarks/RESULTS.md, "3D viewer"); a hemisphere light makes up the brightness."""
    server.scene.configure_default_lights(True, cast_shadow=False)
    server.scene.configure_environment_map(None)
    server.scene.add_light_hemisphere("/lights/sky", sky_color=(255, 255, 255),
                                      ground_color=(140, 125, 110), intensity=1.6)


def add_terrain(server, heights, spacing, origin, obstacles, path=None, max_cells: int = 200):
    """The height map coloured by elevation under /terrain, the boxes under /obstacles and, given
    ``path`` (x0, y0, heading), the desired path under /path; returns their handles."""
    import trimesh

    verts, faces, colours = G.terrain_mesh(heights, spacing, origin, max_cells)
    # glTF vertex colours are linear: convert the sRGB ramp so the browser shows it as meant
    linear = (255.0 * (colours / 255.0) ** 2.2).round().astype(np.uint8)
    mesh = trimesh.Trimesh(vertices=verts, faces=faces, vertex_colors=linear, process=False)
    handles = [server.scene.add_mesh_trimesh("/terrain/map", mesh, **NO_SHADOW)]
    for k, o in enumerate(np.asarray(obstacles).reshape(-1, 9)):
        cx, cy, cz, lx, ly, lz, yaw, pitch, roll = (float(v) for v in o)
        handles.append(server.scene.add_box(f"/obstacles/box{k}", color=ROCK_RGB,
                                            dimensions=(lx, ly, lz), position=(cx, cy, cz),
                                            wxyz=G.quat_zyx(yaw, pitch, roll), **NO_SHADOW))
    pts = G.path_points(path, heights, spacing, origin) if path is not None else []
    if len(pts) > 1:
        seg = np.stack([pts[:-1], pts[1:]], axis=1).astype(np.float32)
        handles.append(server.scene.add_line_segments("/path/line", seg, colors=PATH_RGB,
                                                      thickness=3.0, thickness_units="screen"))
    return handles


class RoverScene:
    """Builds the scene of one episode on a viser server and poses it frame by frame."""

    def __init__(self, server, geometry: dict, load_scale: float | None = None,
                 max_cells: int = 200):
        self.server = server
        self.max_cells = max_cells  # the terrain mesh's cells per side, at most
        self.geometry = geometry
        self.load_scale = load_scale  # metres of arrow per newton (None: 0.4 m for a quarter weight)
        self.layers: dict = {}
        self.bodies: dict = {}
        self.arrows = None
        self.trail = None
        self.checkboxes: dict = {}
        self._static: list = []
        server.scene.set_up_direction("+z")
        setup_lights(server)
        for name in LAYERS:
            self.layers[name] = server.scene.add_frame(f"/{name}", show_axes=False)
        self._build_rover()

    # --- static parts -------------------------------------------------------------------
    def set_terrain(self, heights, spacing, origin, obstacles, path) -> None:
        for h in self._static:  # a new episode replaces the last one's terrain
            h.remove()
        self._static = add_terrain(self.server, heights, spacing, origin, obstacles, path,
                                   self.max_cells)

    def _build_rover(self) -> None:
        g = self.geometry
        sc = self.server.scene
        gp = np.asarray(g["gimbal_point"], dtype=float)
        wb, tr, r, w = g["wheelbase"], g["track"], g["wheel_radius"], g["wheel_width"]
        self.bodies["chassis"] = sc.add_frame("/rover/chassis", show_axes=False)
        # chassis: the body between the axles, the rear axle beam and the post to the gimbal
        sc.add_box("/rover/chassis/body", color=CHASSIS_RGB, dimensions=(0.8 * wb, 0.55 * tr, 0.16),
                   position=(-0.05 * wb, 0.0, gp[2] + 0.08))
        sc.add_box("/rover/chassis/rear_axle", color=CHASSIS_RGB,
                   dimensions=(0.08, tr - w, 0.06), position=(-0.5 * wb, 0.0, 0.06))
        sc.add_box("/rover/chassis/rear_post", color=CHASSIS_RGB,
                   dimensions=(0.06, 0.06, gp[2]), position=(-0.5 * wb, 0.0, gp[2] / 2 + 0.05))
        self.bodies["bogie"] = sc.add_frame("/rover/bogie", show_axes=False)
        sc.add_box("/rover/bogie/axle", color=BOGIE_RGB, dimensions=(0.08, tr - w, 0.06),
                   position=(0.0, 0.0, -gp[2] + 0.06))
        sc.add_box("/rover/bogie/post", color=BOGIE_RGB, dimensions=(0.07, 0.07, gp[2]),
                   position=(0.0, 0.0, -gp[2] / 2 + 0.03))
        axle_y = G.quat_axis("x", math.pi / 2)  # the cylinder's axis (z) along the body's y
        for name in WHEELS:
            self.bodies[f"wheel_{name}"] = sc.add_frame(f"/rover/wheel_{name}", show_axes=False)
            sc.add_cylinder(f"/rover/wheel_{name}/tyre", radius=r, height=w, color=WHEEL_RGB,
                            wxyz=axle_y, radial_segments=24, **NO_SHADOW)
        zeros = np.zeros((4, 2, 3), np.float32)
        self.arrows = sc.add_arrows("/forces/loads", points=zeros, colors=np.zeros((4, 3), np.uint8),
                                    shaft_radius=0.025, head_radius=0.06, head_length=0.1)
        self.trail = sc.add_line_segments("/track/line", np.zeros((1, 2, 3), np.float32),
                                          colors=TRAIL_RGB, thickness=2.0,
                                          thickness_units="screen")

    def add_layer_switches(self, gui) -> None:
        with gui.add_folder("Layers"):
            for name in LAYERS:
                box = gui.add_checkbox(name, True)
                box.on_update(lambda ev, name=name: self._toggle(name, ev.target.value))
                self.checkboxes[name] = box

    def _toggle(self, name: str, on: bool) -> None:
        self.layers[name].visible = bool(on)

    # --- per frame ------------------------------------------------------------------------
    def show(self, frame: dict, track: np.ndarray | None = None) -> None:
        """Pose the rover and the load arrows for one frame (``Recording.frames`` at an index);
        ``track`` (n, 3) the positions travelled so far."""
        poses = G.rover_bodies(frame, self.geometry)
        with self.server.atomic():
            for name, (p, q) in poses.items():
                h = self.bodies[name]
                h.position = tuple(float(v) for v in p)
                h.wxyz = tuple(float(v) for v in q)
            self.arrows.points, self.arrows.colors = self._load_arrows(frame)
            if track is not None:
                t = np.asarray(track, dtype=np.float32).reshape(-1, 3)
                if len(t) == 1:  # the first frame: nothing travelled yet
                    t = np.concatenate([t, t])
                self.trail.points = np.stack([t[:-1], t[1:]], axis=1)

    def _load_arrows(self, frame: dict):
        """One arrow per wheel standing on its tyre, as long as the wheel's load (0.6 m for a
        quarter of the rover's weight), green (unloaded) through yellow to red (400 N)."""
        wp = np.asarray(frame["wheel_position"], dtype=np.float32)
        load = np.maximum(np.asarray(frame["wheel_load"], dtype=np.float32), 0.0)
        scale = self.load_scale or 0.6 / 184.0  # 184 N: a quarter of the 75 kg rover's weight
        base = wp.copy()
        base[:, 2] += self.geometry["wheel_radius"] + 0.03
        tip = base.copy()
        tip[:, 2] += np.maximum(load * scale, 1e-3)
        u = np.clip(load / 400.0, 0.0, 1.0)
        stops = np.array([[40, 180, 60], [240, 200, 40], [230, 40, 30]], float)
        lo = (u >= 0.5).astype(int)
        f = (np.where(lo == 1, u - 0.5, u) * 2.0)[:, None]
        colours = ((1 - f) * stops[lo] + f * stops[lo + 1]).astype(np.uint8)
        return np.stack([base, tip], axis=1), colours


class TimePlots:
    """Wheel loads, gimbal yaw and roll, actions and total power against time, drawn up to the
    current frame (so the plots follow the time slider)."""

    def __init__(self, gui, frames: dict):
        self.frames = frames
        with gui.add_folder("Time series", expand_by_default=True):
            self.loads = gui.add_uplot(data=self._data(1)[0], title="wheel load [N]",
                                       series=(_series("t [s]"), *[_series(w, c) for w, c in
                                                                   zip(WHEELS, WHEEL_COLOURS)]),
                                       aspect=2.0, scales=_x_seconds())
            self.gimbal = gui.add_uplot(data=self._data(1)[1], title="gimbal [deg]",
                                        series=(_series("t [s]"), _series("yaw", "#4363d8"),
                                                _series("roll", "#e6194b")), aspect=2.0, scales=_x_seconds())
            self.actions = gui.add_uplot(data=self._data(1)[2], title="action [-]",
                                         series=(_series("t [s]"), _series("V_x", "#3cb44b"),
                                                 _series("yaw rate", "#4363d8"),
                                                 _series("roll rate", "#e6194b")), aspect=2.0, scales=_x_seconds())
            self.power = gui.add_uplot(data=self._data(1)[3], title="power [W]",
                                       series=(_series("t [s]"), _series("total", "#911eb4")),
                                       aspect=2.0, scales=_x_seconds())

    def _data(self, n: int):
        f = self.frames
        t = np.asarray(f["time"][:n], dtype=np.float64)
        loads = (t, *[np.asarray(f["wheel_load"][:n, i], np.float64) for i in range(4)])
        gim = (t, *[np.degrees(np.asarray(f["gimbal"][:n, i], np.float64)) for i in range(2)])
        act = (t, *[np.asarray(f["action"][:n, i], np.float64) for i in range(3)])
        pw = (t, np.asarray(f["power"][:n], np.float64).sum(axis=1))
        return loads, gim, act, pw

    def show(self, n: int) -> None:
        loads, gim, act, pw = self._data(max(1, n))
        self.loads.data, self.gimbal.data, self.actions.data, self.power.data = loads, gim, act, pw
