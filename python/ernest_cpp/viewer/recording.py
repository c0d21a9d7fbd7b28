"""Episode recordings for the 3D viewer: what the simulator exposes to Python, one row per
environment step, in one ``.npz`` file (uncompressed: writing stays a small fraction of the
episode's simulation time).

A recording holds the scene once (the terrain height map, the rocks and steps as boxes, the
desired path, the rover's geometry) and per frame the chassis pose, the gimbal yaw and roll
(from which the bogie and its wheels are posed), the wheel centres, the wheel loads, the action,
the actuators' electrical power and the energy used.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np

FORMAT = "ernest-recording"
VERSION = 1

#: per-frame arrays: name -> (shape after the frame axis, unit)
FRAME_FIELDS = {
    "time": ((), "s"),
    "position": ((3,), "m"),  # chassis frame origin (rear axle centre), world
    "quaternion": ((4,), "-"),  # chassis orientation (w, x, y, z)
    "gimbal": ((2,), "rad"),  # gimbal yaw, gimbal roll (bogie relative to chassis)
    "wheel_position": ((4, 3), "m"),  # wheel centres FL, FR, RL, RR
    "wheel_load": ((4,), "N"),
    "action": ((3,), "-"),  # the policy's action in [-1, 1] (V_x, yaw rate, roll rate)
    "power": ((6,), "W"),  # electrical power of the six actuators (four wheels, yaw, roll)
    "energy": ((), "J"),
}

#: the walker's per-frame arrays (``viewer.walker``): None is a size fixed by the model
WALKER_FIELDS = {
    "time": ((), "s"),
    "links": ((None, 2, 3), "m"),  # each link capsule's end points
    "body": ((4, 4), "m"),  # body pose (homogeneous)
    "feet": ((None, 3), "m"),  # each leg's wheel contact point
    "stance": ((None,), "-"),  # 1 where the foot bears load (on the ground)
    "step": ((), "-"),  # the gait step the frame belongs to (index into the planned steps)
}

KINDS = {"rover": FRAME_FIELDS, "walker": WALKER_FIELDS}


@dataclass
class Recording:
    """One recorded episode (``load_recording`` reads it, ``EpisodeRecorder`` writes it)."""

    meta: dict
    heights: np.ndarray  # (nx, ny) [m], x-major as Scenario.heights
    spacing: float
    origin: tuple[float, float]
    obstacles: np.ndarray  # (n, 9): cx, cy, cz, lx, ly, lz, yaw, pitch, roll
    path: tuple[float, float, float]  # x0, y0, heading of the desired path line
    frames: dict[str, np.ndarray] = field(default_factory=dict)
    static: dict[str, np.ndarray] = field(default_factory=dict)  # kind-specific scene arrays

    @property
    def kind(self) -> str:
        return str(self.meta.get("kind", "rover"))

    def __len__(self) -> int:
        return int(self.frames["time"].shape[0])

    @property
    def duration(self) -> float:
        t = self.frames["time"]
        return float(t[-1] - t[0]) if len(t) else 0.0

    def frame_at(self, time: float) -> int:
        """Index of the last frame at or before ``time`` [s] (to 1 µs: the time slider's values
        are rounded; clamped to the episode)."""
        t = self.frames["time"]
        return int(np.clip(np.searchsorted(t, time + 1e-6, side="right") - 1, 0, len(t) - 1))


def _unwrap_ernest(env):
    u = getattr(env, "unwrapped", env)
    core = type(getattr(u, "core", None))
    if not hasattr(core, "state") or not hasattr(core, "scenario"):  # the class: no reset needed
        raise ValueError(f"env = {env!r} is not an ernest environment (ernest_cpp.envs.ErnestEnv, "
                         "e.g. gym.make('ernest/RockField-v0'))")
    return u


class EpisodeRecorder:
    """Collects the frames of one episode of an ernest environment (any of ``ernest/...``).

    Call ``start()`` after ``reset()`` and ``capture()`` after each ``step()``, then
    ``save(path)``; ``RecordEpisode`` does this as a Gymnasium wrapper.
    """

    def __init__(self, env):
        self.env = _unwrap_ernest(env)
        self._rows: list[tuple] = []
        self._scene: dict | None = None

    def start(self) -> None:
        u = self.env
        sc = u.core.scenario
        p = u.params
        self._scene = {
            "heights": np.asarray(sc.heights, dtype=np.float32),
            "spacing": float(sc.spacing), "origin": tuple(float(v) for v in sc.origin),
            "obstacles": np.asarray(sc.obstacles, dtype=np.float32).reshape(-1, 9),
            "path": (float(sc.path.x0), float(sc.path.y0), float(sc.path.heading)),
            "meta": {"kind": "rover", "scenario": sc.name,
                     "env_id": getattr(getattr(u, "spec", None), "id", None),
                     "episode_seed": int(u.core.episode_seed),
                     "policy_dt": float(u.options.policy_dt),
                     "geometry": {"wheelbase": p.wheelbase, "track": p.track,
                                  "wheel_radius": p.wheel_radius, "wheel_width": p.wheel_width,
                                  "gimbal_point": [float(v) for v in p.gimbal_point()],
                                  "chassis_com": [float(v) for v in p.chassis_com]}},
        }
        self._rows = []
        self.capture()

    def capture(self) -> None:
        if self._scene is None:
            raise RuntimeError("EpisodeRecorder.capture: call start() after reset() first")
        s = self.env.core.state
        self._rows.append((s.time, s.position, s.quaternion, (s.gimbal_yaw, s.gimbal_roll),
                           s.wheel_position, s.wheel_load, self.env.core.current_action,
                           s.motor_power, s.energy))

    def __len__(self) -> int:
        return len(self._rows)

    def recording(self) -> Recording:
        if self._scene is None:
            raise RuntimeError("EpisodeRecorder: nothing recorded (call start() after reset())")
        cols = list(zip(*self._rows))
        frames = {name: np.asarray(col, dtype=np.float64 if name == "time" else np.float32)
                  for name, col in zip(FRAME_FIELDS, cols)}
        sc = self._scene
        return Recording(meta=dict(sc["meta"]), heights=sc["heights"], spacing=sc["spacing"],
                         origin=sc["origin"], obstacles=sc["obstacles"], path=sc["path"],
                         frames=frames)

    def save(self, path: str) -> str:
        return save_recording(self.recording(), path)


def save_recording(rec: Recording, path: str) -> str:
    """Write ``rec`` to ``path`` (an ``.npz`` file; written whole, then renamed into place)."""
    if not isinstance(path, (str, os.PathLike)) or not str(path):
        raise ValueError(f"path = {path!r} must be a file name")
    path = os.fspath(path)
    folder = os.path.dirname(path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    meta = dict(rec.meta, format=FORMAT, version=VERSION, spacing=rec.spacing,
                origin=list(rec.origin), path=list(rec.path),
                units={k: u for k, (_, u) in KINDS[rec.kind].items()})
    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        np.savez(fh, meta=np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8),
                 heights=rec.heights.astype(np.float32), obstacles=rec.obstacles.astype(np.float32),
                 **{f"frame_{k}": v for k, v in rec.frames.items()},
                 **{f"static_{k}": v for k, v in rec.static.items()})
    os.replace(tmp, path)
    return path


def load_recording(path) -> Recording:
    """Read a recording written by ``EpisodeRecorder.save`` / ``ernest evaluate --record``.

    A missing file raises FileNotFoundError naming it; a file that is not a complete recording
    of this format raises ValueError naming the file and what is wrong.
    """
    if not isinstance(path, (str, os.PathLike)) or not str(path):
        raise ValueError(f"recording = {path!r} must be a file name")
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(2, "no such recording", path)
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a folder, not a recording (.npz file)")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError, KeyError) as exc:
        raise ValueError(f"{path}: not a readable ernest recording ({type(exc).__name__}: "
                         f"{exc})") from None
    try:
        meta = json.loads(bytes(data["meta"].astype(np.uint8)).decode())
    except (KeyError, ValueError, UnicodeDecodeError):
        raise ValueError(f"{path}: not an ernest recording (no readable 'meta' entry)") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ValueError(f"{path}: not an ernest recording (format {meta.get('format')!r} "
                         f"if a dict, expected {FORMAT!r})" if isinstance(meta, dict) else
                         f"{path}: not an ernest recording (meta is not a JSON object)")
    if meta.get("version") != VERSION:
        raise ValueError(f"{path}: recording version {meta.get('version')!r}; this viewer reads "
                         f"version {VERSION}")
    kind = meta.get("kind", "rover")
    if kind not in KINDS:
        raise ValueError(f"{path}: recording of kind {kind!r}; this viewer shows {', '.join(KINDS)}")
    frames = {}
    n = None
    for name, (shape, _) in KINDS[kind].items():
        arr = data.get(f"frame_{name}")
        if arr is None:
            raise ValueError(f"{path}: recording has no '{name}' frames (file incomplete)")
        if arr.ndim != len(shape) + 1 or any(want is not None and got != want
                                             for got, want in zip(arr.shape[1:], shape)) \
                or (n is not None and arr.shape[0] != n):
            raise ValueError(f"{path}: '{name}' frames have shape {arr.shape}, expected "
                             f"({n if n is not None else 'n'}, "
                             f"{', '.join('m' if v is None else str(v) for v in shape)})")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{path}: '{name}' frames hold non-finite values")
        n = arr.shape[0]
        frames[name] = arr
    if not n:
        raise ValueError(f"{path}: recording has no frames")
    heights = data.get("heights")
    if heights is None or heights.ndim != 2 or min(heights.shape) < 2:
        raise ValueError(f"{path}: recording has no height map (2-D 'heights' array)")
    obstacles = data.get("obstacles")
    if obstacles is None or obstacles.ndim != 2 or obstacles.shape[1] != 9:
        raise ValueError(f"{path}: 'obstacles' must be an (n, 9) array")
    try:
        spacing = float(meta["spacing"])
        origin = (float(meta["origin"][0]), float(meta["origin"][1]))
        line = tuple(float(v) for v in meta["path"][:3])
    except (KeyError, TypeError, ValueError, IndexError):
        raise ValueError(f"{path}: recording metadata lacks spacing, origin or path") from None
    if not spacing > 0:
        raise ValueError(f"{path}: height map spacing {spacing} must be > 0")
    static = {k[len("static_"):]: v for k, v in data.items() if k.startswith("static_")}
    return Recording(meta=meta, heights=heights, spacing=spacing, origin=origin,
                     obstacles=obstacles, path=line, frames=frames, static=static)


class RecordEpisode(gym.Wrapper):
    """Gymnasium wrapper that records each episode of an ernest environment for the viewer.

    ``path`` is the file to write; with ``{episode}`` in it each episode gets its own file
    (``path.format(episode=k)``), else each episode overwrites the last. The file is written when
    the episode ends (terminated or truncated) and by ``close()`` for an unfinished one.
    """

    def __init__(self, env, path: str):
        super().__init__(env)
        if not isinstance(path, (str, os.PathLike)) or not str(path):
            raise ValueError(f"path = {path!r} must be a file name")
        self.path = os.fspath(path)
        self.recorder = EpisodeRecorder(env)
        self.episode = -1
        self.written: list[str] = []
        self._open = False

    def _target(self) -> str:
        return self.path.format(episode=self.episode) if "{episode}" in self.path else self.path

    def reset(self, **kwargs):
        if self._open:
            self._write()
        out = self.env.reset(**kwargs)
        self.episode += 1
        self.recorder.start()
        self._open = True
        return out

    def step(self, action):
        out = self.env.step(action)
        self.recorder.capture()
        if out[2] or out[3]:
            self._write()
        return out

    def _write(self) -> None:
        self.written.append(self.recorder.save(self._target()))
        self._open = False

    def close(self):
        if self._open and len(self.recorder) > 1:
            self._write()
        return super().close()


def record_episode(env, policy, path: str, seed: int = 0, max_steps: int = 100_000) -> Recording:
    """Run one episode of ``policy(obs, env) -> action`` on ``env`` and write its recording."""
    if not callable(policy):
        raise ValueError(f"policy = {policy!r} must be callable as policy(obs, env)")
    if hasattr(policy, "reset"):
        policy.reset()
    rec = EpisodeRecorder(env)
    obs, _ = env.reset(seed=seed)
    rec.start()
    for _ in range(int(max_steps)):
        obs, _, term, trunc, _ = env.step(policy(obs, env))
        rec.capture()
        if term or trunc:
            break
    rec.save(path)
    return rec.recording()
