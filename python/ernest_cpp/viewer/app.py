"""The viewer's two servers: ``Player`` plays a recording back with a time slider, ``LiveViewer``
streams a running environment (``render_mode="human"``) without ever holding up ``step``."""

from __future__ import annotations

import math
import threading
import time

import numpy as np

from .recording import Recording, load_recording
from .scene import BACKGROUND, RoverScene, TimePlots


def _check_port(port) -> int:
    if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= port <= 65535:
        raise ValueError(f"port = {port!r} must be an integer in [0, 65535] (0: any free port)")
    return int(port)


def _server(host: str, port: int):
    try:
        import viser
    except ImportError as exc:  # pragma: no cover - the viewer extra is installed by ./run
        raise ImportError("the 3D viewer needs the viewer extra: pip install 'ernest-cpp[viewer]'"
                          ) from exc
    if not isinstance(host, str) or not host:
        raise ValueError(f"host = {host!r} must be a host name or address")
    if port == 0:  # any free port
        import socket

        with socket.socket() as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
    return viser.ViserServer(host=host, port=port, verbose=False)


#: the fixed camera's vertical field of view
CAMERA_FOV = math.radians(55.0)


def default_camera(rec_or_start, heading: float):
    """(eye, look_at) of the fixed camera: behind and left of the start, looking along the path."""
    p = np.asarray(rec_or_start, dtype=float)
    d = np.array([math.cos(heading), math.sin(heading), 0.0])
    left = np.array([-d[1], d[0], 0.0])
    target = p + 1.0 * d
    eye = p - 3.2 * d + 2.4 * left + np.array([0.0, 0.0, 2.6])
    return eye, target


def follow(server, eye, target) -> None:
    """Move every connected browser's camera to ``eye`` looking at ``target``."""
    for client in server.get_clients().values():
        client.camera.position = tuple(float(v) for v in eye)
        client.camera.look_at = tuple(float(v) for v in target)


def walker_camera(body):
    """(eye, look_at) of the fixed camera on the walker: behind, left and above its body."""
    b = np.asarray(body, dtype=float)
    p = b[:3, 3]
    return p + np.array([-4.5, 3.5, 3.5]), p + np.array([0.3, 0.0, -0.8])


class Player:
    """Serves one recording: the scene, a time slider (with play), layer switches and time series.

    ``Player(path_or_recording, port=8080)``; ``url`` is the address to open; ``set_time(t)``
    moves the slider from Python; ``close()`` stops the server.
    """

    def __init__(self, recording, port: int = 8080, host: str = "127.0.0.1"):
        t0 = time.perf_counter()
        rec = recording if isinstance(recording, Recording) else load_recording(recording)
        self.recording = rec
        port = _check_port(port)
        self.server = _server(host, port)
        self.url = f"http://{'localhost' if host in ('0.0.0.0', '127.0.0.1') else host}:" \
                   f"{self.server.get_port()}"
        f = rec.frames
        if rec.kind == "walker":
            from .walker import WalkerScene

            self.scene = WalkerScene(self.server, rec)
            self._track = f["body"][:, :3, 3]
            eye, target = walker_camera(f["body"][0])
        else:
            geometry = rec.meta.get("geometry") or {}
            for key in ("wheelbase", "track", "wheel_radius", "wheel_width", "gimbal_point"):
                if key not in geometry:
                    raise ValueError(f"recording: metadata lacks the rover geometry ({key!r})")
            self.scene = RoverScene(self.server, geometry)
            self.scene.set_terrain(rec.heights, rec.spacing, rec.origin, rec.obstacles, rec.path)
            self._track = f["position"]
            eye, target = default_camera(f["position"][0], rec.path[2])
        cam = self.server.initial_camera
        cam.position, cam.look_at, cam.up = tuple(eye), tuple(target), (0.0, 0.0, 1.0)
        cam.fov = CAMERA_FOV
        self.camera = (eye, target, CAMERA_FOV)
        gui = self.server.gui
        t = f["time"]
        dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
        self._lock = threading.Lock()
        with gui.add_folder("Time"):
            self.slider = gui.add_slider("time [s]", round(float(t[0]), 6),
                                         round(float(max(t[-1], t[0] + dt)), 6), round(dt, 6),
                                         round(float(t[0]), 6))
            self.play = gui.add_checkbox("play", False)
            self.follow = gui.add_checkbox("follow", False, hint="the camera follows the rover")
            self.speed = gui.add_slider("speed [x]", 0.25, 8.0, 0.25, 1.0)
            self.info = gui.add_markdown(self._caption(0))
        self.scene.add_layer_switches(gui)
        if rec.kind == "walker":
            from .walker import WalkerPlots

            self.plots = WalkerPlots(gui, f)
        else:
            self.plots = TimePlots(gui, f)
        self.frame = -1
        self.slider.on_update(lambda _ev: self._show(self.recording.frame_at(self.slider.value)))
        self._show(0)
        self._stop = threading.Event()
        self._player = threading.Thread(target=self._play_loop, name="ernest-viewer-play",
                                        daemon=True)
        self._player.start()
        self.startup_s = time.perf_counter() - t0

    def _caption(self, i: int) -> str:
        m = self.recording.meta
        t = self.recording.frames["time"]
        return (f"**{m.get('scenario', '?')}** seed {m.get('episode_seed', '?')}  \n"
                f"frame {i + 1}/{len(t)}, t = {t[i]:.1f} s")

    def _show(self, i: int) -> None:
        with self._lock:
            if i == self.frame:
                return
            f = self.recording.frames
            frame = {k: v[i] for k, v in f.items()}
            self.scene.show(frame, self._track[: i + 1])
            if self.follow.value:
                follow(self.server, *self._camera_at(frame))
            self.plots.show(i + 1)
            self.info.content = self._caption(i)
            self.frame = i

    def _camera_at(self, frame: dict):
        if self.recording.kind == "walker":
            return walker_camera(frame["body"])
        return default_camera(frame["position"], self.recording.path[2])

    def set_time(self, t: float) -> int:
        """Move the slider to ``t`` [s] (clamped); returns the frame shown."""
        if not isinstance(t, (int, float, np.floating)) or not math.isfinite(t):
            raise ValueError(f"t = {t!r} must be a finite time in seconds")
        tt = self.recording.frames["time"]
        self.slider.value = round(float(np.clip(t, tt[0], tt[-1])), 6)
        i = self.recording.frame_at(self.slider.value)
        self._show(i)
        return i

    def _play_loop(self) -> None:
        last = time.perf_counter()
        while not self._stop.wait(0.05):
            now = time.perf_counter()
            if self.play.value:
                tt = self.recording.frames["time"]
                t = self.slider.value + (now - last) * self.speed.value
                if t > tt[-1]:
                    t = tt[0]
                self.slider.value = round(float(t), 6)
                self._show(self.recording.frame_at(t))
            last = now

    def clients(self) -> int:
        return len(self.server.get_clients())

    def close(self) -> None:
        self._stop.set()
        self.server.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class LiveViewer:
    """Streams an ernest environment to the browser while it runs (``render_mode="human"``).

    ``push(env)`` takes a snapshot of the state (a few microseconds) into a one-frame mailbox; a
    background thread sends the newest snapshot at most ``max_fps`` times a second, so a slow or
    closed browser drops frames instead of delaying ``step``.
    """

    def __init__(self, port: int = 8080, host: str = "127.0.0.1", max_fps: float = 30.0,
                 history: int = 2000):
        if not isinstance(max_fps, (int, float)) or not 0 < max_fps <= 240:
            raise ValueError(f"max_fps = {max_fps!r} must be a number in (0, 240]")
        self.server = _server(host, _check_port(port))
        self.url = f"http://localhost:{self.server.get_port()}"
        self.max_fps = float(max_fps)
        self.history = int(history)
        self._mailbox = None
        self._scene_key = None
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._cond = threading.Lock()
        self.sent = 0
        self.pushed = 0
        self._rows: list = []
        self.scene = None
        self.plots = None
        self._thread = threading.Thread(target=self._loop, name="ernest-viewer-live", daemon=True)
        self._thread.start()
        print(f"ernest viewer: live view at {self.url}", flush=True)

    @classmethod
    def from_environment(cls) -> "LiveViewer":
        """A live viewer on port ERNEST_VIEWER_PORT (default 8080; 0: any free port; a taken
        port moves on to the next free one)."""
        import os

        text = os.environ.get("ERNEST_VIEWER_PORT", "8080")
        try:
            port = int(text)
        except ValueError:
            raise ValueError(f"ERNEST_VIEWER_PORT = {text!r} must be an integer port in "
                             "[0, 65535]") from None
        if not 0 <= port <= 65535:
            raise ValueError(f"ERNEST_VIEWER_PORT = {port} must be in [0, 65535] (0: any free)")
        return cls(port=port)

    def push(self, env) -> None:
        """Queue the environment's current state (replacing any frame not yet sent)."""
        u = getattr(env, "unwrapped", env)
        s = u.core.state
        row = {"time": s.time, "position": s.position, "quaternion": s.quaternion,
               "gimbal": np.array([s.gimbal_yaw, s.gimbal_roll]),
               "wheel_position": s.wheel_position, "wheel_load": s.wheel_load,
               "action": u.core.current_action, "power": s.motor_power, "energy": s.energy}
        key = (u.core.episode_seed, u.core.scenario.name)
        static = None
        if key != self._scene_key:  # a new episode: its terrain goes along once
            from .recording import EpisodeRecorder

            rec = EpisodeRecorder(u)
            rec.start()
            static = rec.recording()
            self._scene_key = key
        with self._cond:
            if static is None and self._mailbox is not None and self._mailbox[0] is not None:
                static = self._mailbox[0]  # keep an unsent new scene
            self._mailbox = (static, row)
        self.pushed += 1
        self._wake.set()

    def _loop(self) -> None:
        period = 1.0 / self.max_fps
        while not self._stop.is_set():
            self._wake.wait(0.5)
            self._wake.clear()
            with self._cond:
                item, self._mailbox = self._mailbox, None
            if item is None:
                continue
            t0 = time.perf_counter()
            try:
                self._send(*item)
            except Exception as exc:  # never let a viewer fault reach the simulation
                print(f"ernest viewer: frame dropped ({type(exc).__name__}: {exc})", flush=True)
            self.sent += 1
            rest = period - (time.perf_counter() - t0)
            if rest > 0:
                self._stop.wait(rest)

    def _send(self, static, row) -> None:
        if static is not None:
            if self.scene is None:
                self.scene = RoverScene(self.server, static.meta["geometry"])
                self.follow = self.server.gui.add_checkbox(
                    "follow", True, hint="the camera follows the rover")
                self.scene.add_layer_switches(self.server.gui)
            self._heading = static.path[2]
            self.scene.set_terrain(static.heights, static.spacing, static.origin,
                                   static.obstacles, static.path)
            eye, target = default_camera(row["position"], static.path[2])
            cam = self.server.initial_camera
            cam.position, cam.look_at, cam.up = tuple(eye), tuple(target), (0.0, 0.0, 1.0)
            cam.fov = CAMERA_FOV
            self._rows = []
        self._rows.append(row)
        del self._rows[:-self.history]
        frames = {k: np.asarray([r[k] for r in self._rows]) for k in row}
        if self.plots is None:
            self.plots = TimePlots(self.server.gui, frames)
        self.plots.frames = frames
        self.plots.show(len(self._rows))
        self.scene.show(row, frames["position"])
        if self.follow.value:
            follow(self.server, *default_camera(row["position"], self._heading))

    def close(self) -> None:
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=2.0)
        self.server.stop()


__all__ = ["Player", "LiveViewer", "BACKGROUND"]
