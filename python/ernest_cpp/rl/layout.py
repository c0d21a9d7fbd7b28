"""Observation/action layout of the ERNEST policy (seed 004 §4.2, Table 5) and the force–torque noise
injection specification.

The policy sees a 45-vector (Table 5, n_s = 45), in this order (§4.2, Fig. 10):

====  =======================  ======================================================
idx   name                     meaning
====  =======================  ======================================================
0     heading_deviation        yaw of the chassis relative to the path direction [rad]
1     lateral_deviation        signed distance from the path, eq 37 [m]
2-3   roll, pitch              chassis inclination w.r.t. gravity [rad]
4-5   gimbal_yaw, gimbal_roll  Active Gimbal Suspension joint positions [rad]
6-29  fts_{FL..RR}_{Fx..Tz}    4 sensors × (Fx, Fy, Fz, Tx, Ty, Tz), processed [N, N·m]
30-41 elev_{FL..RR}_{0..2}     12 terrain elevations relative to the chassis [m]
42-44 action_vx, _yaw, _roll   the currently applied action (normalised, [-1, 1])
====  =======================  ======================================================

Every component is normalised "with respect to its maximum expected value" (§4.2):
``normalised = (physical - offset) / scale``. The paper does not print its table of maximum values;
ours (an assumption, reasons in cpp/sensing/observation.cpp) has ONE source: the C++
``sensing::ObservationScales`` (bound as ``ernest_cpp.sensing.ObservationScales``), which the
environments, the exported policies and the onboard runtime all use. Its layout version
(``sensing.OBSERVATION_LAYOUT_VERSION``) is recorded in every exported policy. Version 1 files were
ambiguous (this module once held a second table, 50 N·m / 0.3 m / 1 m, under the same name): a v1
policy is accepted only when its recorded ``obs_scale`` is the C++ table (``check_policy_layout``).
Force–torque noise (σ = 10 N per force, 2 N·m per torque, §4.2) is specified in physical units and
converted through the table: σ_normalised = σ / scale.

The action is exposed to the policy in [-1, 1]^3 and maps affinely to Vx ∈ [0, 0.2] m/s,
ψ̇ ∈ ±20°/s, φ̇ ∈ ±10°/s (§4.2).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import sensing as _sensing

POLICY_RATE_HZ = 2.0  # f_pi, Table 5
N_FTS = 4
FTS_AXES = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
FTS_START = 6
N_ELEVATION = 12
FTS_FORCE_SIGMA = 10.0  # N, §4.2
FTS_TORQUE_SIGMA = 2.0  # N·m, §4.2
#: The layout version of the C++ table; "ernest-obs-v1" files are checked against the table.
LAYOUT_VERSION = f"ernest-obs-v{_sensing.OBSERVATION_LAYOUT_VERSION}"
LEGACY_LAYOUT_VERSIONS = ("ernest-obs-v1",)

#: The §4.2 action ranges (Vx, psi_dot, phi_dot) [m/s, rad/s, rad/s]: from their one source, the
#: C++ ``sensing.ActionLimits`` that the environments and the runtime map actions with.
_LIMITS = _sensing.ActionLimits()
ACTION_LOW = np.array([0.0, -_LIMITS.yaw_rate_max, -_LIMITS.roll_rate_max])
ACTION_HIGH = np.array([_LIMITS.vx_max, _LIMITS.yaw_rate_max, _LIMITS.roll_rate_max])


@dataclass(frozen=True)
class NoiseGroup:
    """Indices [start, stop) of the observation that get Gaussian noise of std ``sigma`` (physical
    units) every ``step`` entries (so 6:30:6 style strides describe "Fx of every sensor")."""

    start: int
    stop: int
    sigma: float
    step: int = 1

    def indices(self) -> np.ndarray:
        return np.arange(self.start, self.stop, self.step, dtype=np.int64)


def paper_noise_groups() -> list[NoiseGroup]:
    """§4.2: σ 10 N on each force component and 2 N·m on each torque component of the 4 FTS."""
    groups = []
    for k in range(N_FTS):
        base = FTS_START + 6 * k
        groups.append(NoiseGroup(base, base + 3, FTS_FORCE_SIGMA))
        groups.append(NoiseGroup(base + 3, base + 6, FTS_TORQUE_SIGMA))
    return groups


@dataclass
class ObservationLayout:
    """Names and affine normalisation of an observation vector (normalised = (x - offset) / scale)."""

    version: str
    names: list[str]
    offset: np.ndarray
    scale: np.ndarray
    action_low: np.ndarray
    action_high: np.ndarray
    noise_groups: list[NoiseGroup] = field(default_factory=list)

    @property
    def obs_dim(self) -> int:
        return len(self.names)

    @property
    def act_dim(self) -> int:
        return len(self.action_low)

    def __post_init__(self):
        self.offset = np.asarray(self.offset, dtype=np.float64).reshape(-1)
        self.scale = np.asarray(self.scale, dtype=np.float64).reshape(-1)
        self.action_low = np.asarray(self.action_low, dtype=np.float64).reshape(-1)
        self.action_high = np.asarray(self.action_high, dtype=np.float64).reshape(-1)
        n = len(self.names)
        if self.offset.shape != (n,) or self.scale.shape != (n,):
            raise ValueError(f"observation layout {self.version!r}: offset and scale must have "
                             f"{n} entries, got {self.offset.shape[0]} and {self.scale.shape[0]}")
        if not np.all(np.isfinite(self.scale)) or np.any(self.scale <= 0):
            raise ValueError(f"observation layout {self.version!r}: every scale must be finite "
                             f"and > 0, got min {self.scale.min()}")
        if self.action_low.shape != self.action_high.shape or np.any(
                self.action_high <= self.action_low):
            raise ValueError(f"observation layout {self.version!r}: action_high must exceed "
                             f"action_low element-wise")
        for g in self.noise_groups:
            if not (0 <= g.start < g.stop <= n) or g.step < 1 or not g.sigma >= 0:
                raise ValueError(f"noise group {g} is outside the observation [0, {n}) or has a "
                                 f"negative sigma / step < 1")

    def noise_std_normalised(self) -> tuple[np.ndarray, np.ndarray]:
        """(indices, std) of the noise in normalised observation units (σ / scale per index)."""
        idx, std = [], []
        for g in self.noise_groups:
            i = g.indices()
            idx.append(i)
            std.append(g.sigma / self.scale[i])
        if not idx:
            return np.zeros(0, np.int64), np.zeros(0)
        idx_all = np.concatenate(idx)
        if len(np.unique(idx_all)) != len(idx_all):
            raise ValueError("noise groups overlap: each observation index may appear once")
        return idx_all, np.concatenate(std)

    def to_dict(self) -> dict:
        return {"version": self.version, "names": list(self.names),
                "offset": self.offset.tolist(), "scale": self.scale.tolist(),
                "action_low": self.action_low.tolist(), "action_high": self.action_high.tolist(),
                "noise_groups": [[g.start, g.stop, g.sigma, g.step] for g in self.noise_groups]}

    @classmethod
    def from_dict(cls, d: dict) -> "ObservationLayout":
        return cls(version=d["version"], names=list(d["names"]), offset=d["offset"],
                   scale=d["scale"], action_low=d["action_low"], action_high=d["action_high"],
                   noise_groups=[NoiseGroup(int(a), int(b), float(s), int(st))
                                 for a, b, s, st in d.get("noise_groups", [])])


def ernest_layout(scales=None) -> ObservationLayout:
    """The 45-value ERNEST layout: names and normalisation from the C++ table
    (``sensing.ObservationScales``, or ``scales`` if given, e.g. an env's ``options.scales``), the
    §4.2 action ranges and the paper's FTS noise."""
    sc = _sensing.ObservationScales() if scales is None else scales
    return ObservationLayout(LAYOUT_VERSION, list(_sensing.observation_names()),
                             np.zeros(_sensing.OBSERVATION_SIZE), np.asarray(sc.divisors()),
                             ACTION_LOW.copy(), ACTION_HIGH.copy(), paper_noise_groups())


def paper_layout() -> ObservationLayout:
    """The ERNEST layout with the default C++ table (what the rover environments publish)."""
    return ernest_layout()


def check_policy_layout(meta: dict, path: str, scales=None) -> None:
    """Refuse an exported policy whose observation table is not the one the environments and the
    runtime use (``scales``, default the C++ table): names the file, the entry and both values.
    ``layout_version`` must be the current one, or a legacy one with the same table."""
    version = meta.get("layout_version")
    if version != LAYOUT_VERSION and version not in LEGACY_LAYOUT_VERSIONS:
        raise ValueError(f"{path}: layout_version {version!r}; this version reads "
                         f"{LAYOUT_VERSION!r} (and {', '.join(LEGACY_LAYOUT_VERSIONS)})")
    want = np.asarray((_sensing.ObservationScales() if scales is None else scales).divisors())
    got = np.asarray(meta.get("obs_scale", []), dtype=np.float64)
    if got.shape != want.shape:
        raise ValueError(f"{path}: obs_scale has {got.size} values, the observation {want.size}")
    bad = np.flatnonzero(~np.isclose(got, want, rtol=1e-6, atol=0.0))
    if bad.size:
        i = int(bad[0])
        names = _sensing.observation_names()
        raise ValueError(f"{path}: the policy was trained with another observation scale table "
                         f"({version}): obs_scale[{i}] ({names[i]}) = {got[i]:g}, the environments "
                         f"use {want[i]:g} (sensing.ObservationScales); {bad.size} entries differ. "
                         f"Retrain, or export it again from a checkpoint made with this table.")
    offset = np.asarray(meta.get("obs_offset", np.zeros(want.size)), dtype=np.float64)
    if offset.shape != want.shape or np.any(offset != 0.0):
        raise ValueError(f"{path}: obs_offset must be {want.size} zeros (the observation has no "
                         f"offset)")


def generic_layout(obs_dim: int, action_low, action_high, version: str = "generic-v1",
                   offset=None, scale=None, noise_groups=None) -> ObservationLayout:
    """A layout for an arbitrary Box env: identity normalisation unless given, no noise by default."""
    return ObservationLayout(version, [f"obs{i}" for i in range(obs_dim)],
                             np.zeros(obs_dim) if offset is None else offset,
                             np.ones(obs_dim) if scale is None else scale,
                             action_low, action_high, list(noise_groups or []))


def parse_noise_groups(spec) -> list[NoiseGroup]:
    """Config form: a list of ``[start, stop, sigma]`` or ``[start, stop, sigma, step]`` or
    ``"start:stop[:step]=sigma"`` strings (sigma in physical units)."""
    groups = []
    for item in spec or []:
        if isinstance(item, str):
            rng, _, sig = item.partition("=")
            parts = [int(p) for p in rng.split(":")]
            if len(parts) not in (2, 3) or not sig:
                raise ValueError(f"noise group {item!r}: expected 'start:stop[:step]=sigma'")
            groups.append(NoiseGroup(parts[0], parts[1], float(sig), parts[2] if len(parts) == 3
                                     else 1))
        else:
            vals = list(item)
            if len(vals) not in (3, 4):
                raise ValueError(f"noise group {item!r}: expected [start, stop, sigma(, step)]")
            groups.append(NoiseGroup(int(vals[0]), int(vals[1]), float(vals[2]),
                                     int(vals[3]) if len(vals) == 4 else 1))
    return groups
