"""The single Gymnasium environment over the C++ episode core (``ernest_cpp._core.envs.RoverEnv``)."""

from __future__ import annotations

import contextlib
import math
import numbers
import pickle
import threading
from typing import Any

import gymnasium as gym
import numpy as np

from .._core import dynamics as _dyn
from .._core import envs as _envs
from .._core.envs import (  # noqa: F401  (re-exports: the C++ episode core, typed in core.pyi)
    EnvOptions,
    RippleSpec,
    RoverEnv,
    Scenario,
    ScenarioOptions,
    VecRoverEnv,
    default_soil,
    generate_scenario,
    ripple_height,
    scenario_names,
)
from .. import sensing
from .. import scenarios as _scenarios



@contextlib.contextmanager
def _one_thread(lock: threading.Lock, what: str):
    """Refuse a second thread instead of waiting, as the C++ objects do: a reset interleaved
    with a step would leave the step's history and info from two episodes."""
    if not lock.acquire(blocking=False):
        raise RuntimeError(f"{what}: the environment is in use by another thread; use one "
                           "environment per thread or serialise the calls with a lock")
    try:
        yield
    finally:
        lock.release()


def _flag(name: str, value) -> bool:
    """A boolean option: True/False (or numpy bool, 0, 1); anything else (e.g. "no", which
    bool() reads as True) raises ValueError naming the option."""
    if isinstance(value, (bool, np.bool_)) or (isinstance(value, numbers.Integral)
                                                 and value in (0, 1)):
        return bool(value)
    raise ValueError(f"{name} = {value!r} must be a bool (True or False)")


def check_seed(seed, name: str, room: int = 0) -> int:
    """seed as an int in [0, 2**64 - 1 - room] (the C++ seeds are uint64), else ValueError."""
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise ValueError(f"{name} = {seed!r} must be an integer in [0, {2**64 - 1 - room}]")
    value = int(seed)
    if not 0 <= value <= 2**64 - 1 - room:
        raise ValueError(f"{name} = {value} is outside the allowed range [0, {2**64 - 1 - room}]")
    return value


_DEFAULTS = _envs.EnvOptions()  # the one set of defaults (C++ EnvOptions)


def _optional_number(name: str, value, lo: float, hi: float, default: str, integer: bool = False):
    """None (the default) or a number in (lo, hi] ([lo, hi] for integers), else ValueError naming
    the parameter: no 0 or negative stands for "default"."""
    if value is None:
        return None
    bad = isinstance(value, bool) or not isinstance(value, numbers.Integral if integer else numbers.Real)
    if not bad:
        v = int(value) if integer else float(value)
        if (lo <= v <= hi) if integer else (lo < v <= hi):  # NaN fails both
            return v
    span = f"[{lo}, {hi}]" if integer else f"({lo:g}, {hi:g}]"
    raise ValueError(f"{name} = {value!r} must be {'an integer' if integer else 'a number'} in "
                     f"{span}, or None for {default}")


def make_options(scenario: str = "rockfield", soil: str | None = None, passive: bool = False,
                 physics_dt: float | None = None, slip_force_tolerance: float | None = None,
                 obstacle_substeps: int | None = None, episode_length: float | None = None,
                 rigid_ground: bool = False, eps_slip: float | None = _DEFAULTS.eps_slip,
                 eps_motion: float | None = _DEFAULTS.eps_motion,
                 fts_noise_force: float = 0.0, fts_noise_torque: float = 0.0,
                 start_speed: float = 0.0, randomisation: dict | None = None,
                 terrain_source: str = "truth", stereo=None,
                 reward: dict | None = None) -> _envs.EnvOptions:
    """EnvOptions from keyword arguments (the Gymnasium kwargs), validated.

    ``soil``: a preset name ('dry_sand', 'm90', 'wet_sand'); None (the default) is the scenario's
    own, ``default_soil(scenario)``: dry sand for the Bickler trap, M90 elsewhere (the same as
    ``ernest_runtime --scenario`` without ``--soil``).

    ``physics_dt`` [s], ``slip_force_tolerance``, ``obstacle_substeps`` and ``episode_length`` [s]
    default to None: the simulator's step and settings, the scenario's episode length (30 s for
    the step, 60 s otherwise). ``eps_slip`` and ``eps_motion`` default to the environments' values
    (``EnvOptions``; docs/soil.md), None keeps the soil preset's (Table 2). A value given must be
    a real one: 0, negatives and NaN are refused (ValueError naming the parameter and range).

    ``randomisation`` sets ScenarioOptions fields: ``range_scale`` (0..1, multiplies Table 3's
    maximum bounds: tilt, yaw/lateral/heading offsets, orientations), ``step_height_range``,
    ``slope_angle_range_deg``, ``ripple_amplitude_range`` ((min, max) pairs), ``max_rock_density``,
    ``p_instance``, ``noise_unit``, ``grid_spacing``, ``clear_radius``, ``eval_slope_deg``,
    ``eval_slope_spread_deg`` (SlopeEval's angle drawn per seed within ± this).

    ``terrain_source``: ``"truth"`` (default: elevation samples from the simulator's terrain) or
    ``"stereo"`` (from the elevation map fused from simulated stereo, seed 004 §2.4); ``stereo``
    is an optional ``perception.StereoMapperOptions`` (camera, matcher, map, fusion rate).

    ``reward`` sets eq 38's weights (``sensing.RewardWeights``): ``w_s``, ``w_delta``, ``w_tau``
    (defaults 2, 0.1, 1e-4: the paper's; it calls them tunable).
    """
    check_scenario(scenario)
    if soil is None:
        soil = default_soil(scenario)
    for name, value in (("soil", soil), ("terrain_source", terrain_source)):
        if not isinstance(value, str):
            raise TypeError(f"{name} = {value!r} must be a str")
    o = _envs.EnvOptions()
    sc = _envs.ScenarioOptions()
    sc.kind = scenario
    for key, value in (randomisation or {}).items():
        if key == "kind" or not hasattr(sc, key):
            raise ValueError(f"randomisation has no field {key!r}")
        setattr(sc, key, tuple(float(v) for v in value) if isinstance(value, (list, tuple))
                else None if value is None else float(value))
    o.scenario = sc
    o.soil = soil
    o.passive = _flag("passive", passive)
    o.physics_dt = _optional_number("physics_dt", physics_dt, 0.0, 0.05, "the simulator's step")
    o.slip_force_tolerance = _optional_number("slip_force_tolerance", slip_force_tolerance, 0.0,
                                              1e9, "the simulator's")
    o.obstacle_substeps = _optional_number("obstacle_substeps", obstacle_substeps, 1, 64,
                                           "the simulator's", integer=True)
    o.episode_duration = _optional_number("episode_length", episode_length, 0.0, 3600.0,
                                          "the scenario's")
    o.rigid_ground = _flag("rigid_ground", rigid_ground)
    o.eps_slip = _optional_number("eps_slip", eps_slip, 0.0, 1e8, "the soil preset's")
    o.eps_motion = _optional_number("eps_motion", eps_motion, 0.0, 1.0, "the soil preset's")
    o.fts_noise_force = float(fts_noise_force)
    o.fts_noise_torque = float(fts_noise_torque)
    o.start_speed = float(start_speed)
    o.terrain_source = str(terrain_source)
    if stereo is not None:
        o.stereo = stereo
    for key, value in (reward or {}).items():
        if key not in ("w_s", "w_delta", "w_tau"):
            raise ValueError(f"reward has no weight {key!r}; allowed: w_s, w_delta, w_tau")
        setattr(o.weights, key, float(value))
    o.validate()
    return o


def check_scenario(scenario) -> None:
    """ValueError unless ``scenario`` is one of the short names of ``ernest_cpp.scenarios``
    (the only names: no aliases), listing them."""
    if not isinstance(scenario, str) or scenario not in _scenarios.SCENARIOS:
        raise ValueError(f"scenario = {scenario!r}; allowed: {', '.join(_scenarios.SCENARIOS)}")


def observation_layout(options: _envs.EnvOptions):
    """The layout the training and export code use (``ernest_cpp.rl.layout``): the observation is
    already normalised by the C++ table ``options.scales`` (offset 0), so physical values are
    ``obs * scale``; the exported policy takes physical values and applies the same table."""
    from ..rl import layout as L  # numpy only; does not load torch

    return L.ernest_layout(options.scales)


#: ``reset(options=...)`` keys the environments honour: none (an episode is set by the gym.make
#: kwargs and the seed). Any other key is refused rather than silently ignored.
RESET_OPTIONS: tuple[str, ...] = ()


def check_reset_options(options: dict | None) -> None:
    if options is None:
        return
    if not isinstance(options, dict):
        raise ValueError(f"reset options must be a dict or None, got {type(options).__name__}")
    unknown = sorted(str(k) for k in options if k not in RESET_OPTIONS)
    if unknown:
        raise ValueError(f"reset(options=...): unknown key(s) {', '.join(unknown)}; the ERNEST "
                         f"environments take no reset options (configure an episode with the "
                         f"gym.make keyword arguments and the seed)")


class ErnestEnv(gym.Env):
    """ERNEST on one of the seed 004 scenarios (§4.5) or evaluation courses (§5).

    Observation: 45 float32 values in the order of §4.2 (see ``sensing.observation_names()``),
    each divided by its maximum expected value. Action: 3 values in [-1, 1] -> V_x in
    [0, 0.2] m/s, yaw rate +-20 deg/s, roll rate +-10 deg/s, applied for 0.5 s (2 Hz). Reward:
    eq 38 with its terms in ``info``. Episodes end at the end of the map (terminated) or at the
    time limit (truncated); a diverged simulation ends the episode with ``info["diverged"]``.

    Copies (``pickle``, ``copy.deepcopy``) carry the configuration (options, rover parameters,
    render mode), not the C++ episode in progress: a copy starts unreset, call ``reset()``.

    ``params`` and ``options`` may be changed in place after creation: the change is validated
    and applied at the next ``reset()`` (the episode in progress keeps its configuration).
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 2}

    def __init__(self, scenario: str = "rockfield", render_mode: str | None = None,
                 params: Any = None, _options: Any = None, **kwargs):
        if render_mode not in (None, "rgb_array", "human"):
            raise ValueError(f"render_mode = {render_mode!r}; allowed: None, 'rgb_array', 'human'")
        check_scenario(scenario)
        self.render_mode = render_mode
        self.scenario_name = scenario
        if _options is not None:  # an unpickled copy: the original's validated options
            _options.validate()
            self.options = _options
        else:
            self.options = make_options(scenario, **kwargs)
        self.params = params if params is not None else _dyn.RoverParameters()
        self.core = _envs.RoverEnv(self.params, self.options)
        self._built_from = self._configuration()
        clip = sensing.OBSERVATION_CLIP
        self.observation_space = gym.spaces.Box(-clip, clip, (sensing.OBSERVATION_SIZE,), np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (sensing.ACTION_SIZE,), np.float32)
        self.observation_layout = observation_layout(self.options)
        self._started = False
        self.history: list[dict] = []  # per-step ground truth for plots (cleared at reset)
        self._busy = threading.Lock()  # step/reset/render: one thread at a time

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        check_reset_options(options)
        with _one_thread(self._busy, "ErnestEnv.reset"):
            return self._reset(seed)

    def _configuration(self) -> bytes:
        return pickle.dumps((self.params, self.options))

    def _apply_changes(self) -> None:
        """Rebuild the C++ core if params or options were changed since it was built."""
        now = self._configuration()
        if now == self._built_from:
            return
        self.options.validate()
        self.params.validate()
        self.core = _envs.RoverEnv(self.params, self.options)
        self.observation_layout = observation_layout(self.options)
        self._built_from = now
        self._started = False

    def _reset(self, seed):
        if seed is not None:
            seed = check_seed(seed, "seed")
        self._apply_changes()
        super().reset(seed=seed)
        if seed is not None:
            obs = self.core.reset(int(seed))
        elif not self._started:
            obs = self.core.reset(int(self.np_random.integers(0, 2**63 - 1)))
        else:
            obs = self.core.reset_next()
        self._started = True
        self.history = [self._snapshot(None)]
        if self.render_mode == "human":
            self._live_view()
        return obs.astype(np.float32), {"episode_seed": self.core.episode_seed,
                                        "scenario": self.core.scenario.name}

    def __repr__(self) -> str:
        """``ErnestEnv('bickler', soil='dry_sand', passive=True)``: the scenario, its soil and
        the environment's settings that differ from the defaults (``make_options``)."""
        o, d = self.options, _DEFAULTS
        parts = [repr(self.scenario_name), f"soil={o.soil!r}"]
        for name, value, default in (
                ("passive", o.passive, d.passive), ("rigid_ground", o.rigid_ground, d.rigid_ground),
                ("physics_dt", o.physics_dt, d.physics_dt),
                ("episode_length", o.episode_duration, d.episode_duration),
                ("terrain_source", o.terrain_source, d.terrain_source),
                ("render_mode", self.render_mode, None)):
            if value != default:
                parts.append(f"{name}={value!r}")
        return f"ErnestEnv({', '.join(parts)})"

    def __getstate__(self):
        return {"scenario_name": self.scenario_name, "render_mode": self.render_mode,
                "options": self.options, "params": self.params}

    def __setstate__(self, state):
        self.__init__(state["scenario_name"], state["render_mode"], state["params"],
                      _options=state["options"])

    def step(self, action):
        with _one_thread(self._busy, "ErnestEnv.step"):
            return self._step(action)

    def _step(self, action):
        if not self._started:
            raise RuntimeError("ErnestEnv.step: call reset() first")
        a = as_actions(action, "action").reshape(-1)
        if a.shape != (sensing.ACTION_SIZE,):
            raise ValueError(f"action must have 3 values, got shape {np.shape(action)}")
        if not np.all(np.isfinite(a)):
            raise ValueError("action must be finite")
        obs, reward, terminated, truncated, info = self.core.step(a)
        self.history.append(self._snapshot(info))
        if self.render_mode == "human":
            self._live_view()
        if terminated or truncated:
            info["episode_metrics"] = self.core.metrics
        return obs.astype(np.float32), float(reward), bool(terminated), bool(truncated), info

    def _snapshot(self, info):
        s = self.core.state
        return {"time": s.time, "position": np.array(s.position), "yaw": s.yaw,
                "roll": s.roll, "pitch": s.pitch, "gimbal_yaw": s.gimbal_yaw,
                "gimbal_roll": s.gimbal_roll, "roll_torque": s.roll_torque,
                "wheel_load": np.array(s.wheel_load), "energy": s.energy,
                "action": np.array(self.core.current_action)}

    def _live_view(self) -> None:
        """render_mode "human": the state goes to the browser's live 3D view (ernest_cpp.viewer;
        port ERNEST_VIEWER_PORT, default 8080); a slow or closed browser never delays the step."""
        if getattr(self, "_viewer", None) is None:
            from ..viewer.app import LiveViewer

            self._viewer = LiveViewer.from_environment()
        self._viewer.push(self)

    def close(self):
        viewer = getattr(self, "_viewer", None)
        if viewer is not None:
            viewer.close()
            self._viewer = None
        super().close()

    def render(self):
        if self.render_mode == "human":  # each step already sent the state (Gymnasium's rule)
            return None
        if self.render_mode != "rgb_array":
            return None
        from .render import render_frame

        with _one_thread(self._busy, "ErnestEnv.render"):
            return render_frame(self)

    # convenient accessors
    @property
    def scenario(self):
        return self.core.scenario

    @property
    def metrics(self) -> dict:
        return self.core.metrics

    def heading_and_lateral(self) -> tuple[float, float]:
        s = self.core.state
        p = self.core.scenario.path
        return p.heading_deviation(s.yaw), p.lateral_deviation(s.position[0], s.position[1])


def as_actions(action, name: str) -> np.ndarray:
    """action as a float64 array, else ValueError naming it (e.g. a string)."""
    try:
        return np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numbers in [-1, 1], got {action!r}") from None


def deg(x: float) -> float:
    return math.degrees(x)
