"""The exported policy file: its metadata read strictly, the checks the C++ runtime makes
(cpp/runtime/policy.cpp check_metadata, mirrored so that ``ernest evaluate`` refuses exactly the
files ``ernest_runtime`` refuses), and the digest of the whole archive.

``policy_sha256``: SHA-256 over every record of the TorchScript archive (a zip: code,
constants, pickled attributes, tensor data, metadata), uncompressed, in byte-wise name order,
except ``.data/serialization_id`` (an id torch derives at each save from the other records).
Per record: the name (without the archive's top folder), a newline, the size in decimal, a
newline, the bytes. The metadata record enters with the digest's own value replaced by 64 "0"
(it must occur there exactly once). Editing ``forward()``, a constant, a weight or a metadata
field therefore changes it. cpp/runtime/policy_digest.cpp computes the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import struct
import zipfile
import zlib

import numpy as np

METADATA_FILE = "ernest_metadata.json"
METADATA_RECORD = "extra/" + METADATA_FILE
FORMAT = "ernest-policy-v1"
WEIGHTS_KEY = "weights_sha256"
POLICY_KEY = "policy_sha256"
PLACEHOLDER = "0" * 64
SERIALIZATION_ID = ".data/serialization_id"
_HEX64 = re.compile(r"[0-9a-f]{64}")


class ExportError(ValueError):
    pass


# ---- strict metadata ------------------------------------------------------------------------
def _no_duplicates(pairs):
    out = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f'duplicate member name "{k}"')
        out[k] = v
    return out


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"number {text} is out of range")
    return value


def _no_constant(name: str):
    raise ValueError(f"{name} is not JSON")


def parse_metadata(text: str, path: str) -> dict:
    """RFC 8259 JSON as the runtime reads it: no NaN/Infinity, no overflowing number, no member
    name twice in one object; the root must be an object."""
    try:
        meta = json.loads(text, object_pairs_hook=_no_duplicates, parse_float=_finite_float,
                          parse_constant=_no_constant)
    except ValueError as exc:  # json.JSONDecodeError is a ValueError
        raise ExportError(f"{path}: {METADATA_FILE} is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise ExportError(f"{path}: {METADATA_FILE} is not a JSON object")
    return meta


# ---- checks ---------------------------------------------------------------------------------
def _bad(path: str, what: str):
    raise ExportError(f"{path}: policy metadata: {what}")


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _integer(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _field(meta: dict, key: str, path: str, kind: str):
    v = meta.get(key)
    ok = {"string": lambda x: isinstance(x, str), "number": _number, "integer": _integer,
          "array": lambda x: isinstance(x, list) and all(_number(e) for e in x)}[kind](v)
    if not ok:
        _bad(path, f"field '{key}' is missing or not {'an' if kind[0] in 'aei' else 'a'} {kind}"
                   + (" of numbers" if kind == "array" else ""))
    return v


def check_generic(meta: dict, path: str) -> None:
    """What every policy file must satisfy, whatever its environment: the format, whole sizes,
    a finite positive rate, finite tables of the right lengths, well-formed digests."""
    fmt = _field(meta, "format", path, "string")
    if fmt != FORMAT:
        _bad(path, f"format {fmt!r}, expected {FORMAT!r}")
    _field(meta, "layout_version", path, "string")
    n_obs, n_act = (_field(meta, k, path, "integer") for k in ("obs_dim", "act_dim"))
    if n_obs < 1 or n_act < 1:
        _bad(path, f"obs_dim {n_obs} and act_dim {n_act} must be >= 1")
    rate = _field(meta, "policy_rate_hz", path, "number")
    if not (math.isfinite(rate) and rate > 0):
        _bad(path, f"policy_rate_hz {rate} must be a finite number > 0 [Hz]")
    for key, n in (("obs_offset", n_obs), ("obs_scale", n_obs), ("action_low", n_act),
                   ("action_high", n_act)):
        if len(_field(meta, key, path, "array")) != n:
            _bad(path, f"{key} has {len(meta[key])} values, expected {n}")
    if not np.all(np.asarray(meta["action_low"]) < np.asarray(meta["action_high"])):
        _bad(path, "action_low must be below action_high in every entry")
    for key in (WEIGHTS_KEY, POLICY_KEY):
        if key in meta and not (isinstance(meta[key], str) and _HEX64.fullmatch(meta[key])):
            _bad(path, f"field '{key}' is not a 64-digit lower-case hex string")


def _close(a: float, b: float, rel: float) -> bool:
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))


def check_runtime(meta: dict, path: str, policy_rate_hz: float | None = None,
                  rel_tol: float = 1e-6) -> None:
    """The runtime's own checks (PolicyExpectations defaults): the ERNEST layout, 45 -> 3, the
    policy rate, the observation scale table of sensing.ObservationScales and the action limits
    of sensing.ActionLimits, each within rel_tol."""
    from .. import sensing
    from . import layout as L

    n_obs, n_act = (_field(meta, k, path, "integer") for k in ("obs_dim", "act_dim"))
    if n_obs != sensing.OBSERVATION_SIZE or n_act != sensing.ACTION_SIZE:
        _bad(path, f"the policy maps {n_obs} observation values to {n_act} commands, the runtime "
                   f"needs {sensing.OBSERVATION_SIZE} -> {sensing.ACTION_SIZE}")
    check_generic(meta, path)
    rate = L.POLICY_RATE_HZ if policy_rate_hz is None else policy_rate_hz
    version = meta["layout_version"]
    if version != L.LAYOUT_VERSION and version not in L.LEGACY_LAYOUT_VERSIONS:
        _bad(path, f"layout_version {version!r}, the runtime builds {L.LAYOUT_VERSION!r}")
    if not _close(meta["policy_rate_hz"], rate, rel_tol):
        _bad(path, f"policy_rate_hz {meta['policy_rate_hz']}, the runtime runs the policy at "
                   f"{rate} Hz")
    lim = sensing.ActionLimits()
    want = {"obs_offset": np.zeros(sensing.OBSERVATION_SIZE),
            "obs_scale": np.asarray(sensing.ObservationScales().divisors()),
            "action_low": [0.0, -lim.yaw_rate_max, -lim.roll_rate_max],
            "action_high": [lim.vx_max, lim.yaw_rate_max, lim.roll_rate_max]}
    for key, values in want.items():
        for i, (g, w) in enumerate(zip(meta[key], values)):
            if not _close(g, float(w), rel_tol):
                why = (f" ({sensing.observation_names()[i]}): the policy was trained with another "
                       "observation scale table than sensing.ObservationScales"
                       if key == "obs_scale" else "")
                _bad(path, f"{key}[{i}] = {g:g}, expected {float(w):g}{why}")


# ---- the archive digest -----------------------------------------------------------------------
def archive_records(path: str) -> dict[str, bytes]:
    """{name without the top folder: bytes} of a TorchScript archive, read from the local
    headers as libtorch reads them (stored or deflated records, no CRC check)."""
    try:
        with zipfile.ZipFile(path) as z, open(path, "rb") as f:
            records = {}
            for info in z.infolist():
                if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
                    raise ExportError(f"{path}: record {info.filename} has compression method "
                                      f"{info.compress_type}; TorchScript archives store or "
                                      "deflate their records")
                name = info.filename.split("/", 1)[-1]
                if name in records:
                    raise ExportError(f"{path}: record {name} appears twice in the archive")
                f.seek(info.header_offset)
                head = f.read(30)
                if head[:4] != b"PK\x03\x04":
                    raise ExportError(f"{path}: damaged archive (record {name})")
                n_name, n_extra = struct.unpack("<HH", head[26:30])
                f.seek(info.header_offset + 30 + n_name + n_extra)
                data = f.read(info.compress_size)
                if info.compress_type == zipfile.ZIP_DEFLATED:
                    data = zlib.decompress(data, -15)
                records[name] = data
    except (zipfile.BadZipFile, OSError, zlib.error) as exc:
        raise ExportError(f"{path}: not a readable policy archive ({exc})") from None
    return records


def policy_sha256(path: str, digest_in_metadata: str) -> str:
    """The digest of the archive at ``path`` (module docstring), its metadata's own digest
    value ``digest_in_metadata`` zeroed."""
    records = archive_records(path)
    meta = records.get(METADATA_RECORD)
    if meta is None:
        raise ExportError(f"{path}: the archive has no {METADATA_FILE}")
    value = digest_in_metadata.encode()
    if meta.count(value) != 1:
        raise ExportError(f"{path}: the {POLICY_KEY} value must appear exactly once in "
                          f"{METADATA_FILE}")
    records[METADATA_RECORD] = meta.replace(value, PLACEHOLDER.encode())
    records.pop(SERIALIZATION_ID, None)
    h = hashlib.sha256()
    for name in sorted(records, key=lambda n: n.encode()):
        h.update(f"{name}\n{len(records[name])}\n".encode())
        h.update(records[name])
    return h.hexdigest()
