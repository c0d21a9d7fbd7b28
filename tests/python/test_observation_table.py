"""One observation scale table: the C++ one (``sensing::ObservationScales``: torque 40 N·m,
elevation 0.5 m, lateral 2 m), bound to Python, which the environments, the exported policies
and the runtime use. Layout version 1 files exist with another table under the same version
string (torque 50 N·m, elevation 0.3 m, lateral 1 m); the layout version is 2, a version 1 policy
loads only if it carries the C++ table, and the legacy policy acts bit for bit as recorded.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
import torch

from ernest_cpp import cli, evaluate, sensing
from ernest_cpp.envs import ErnestEnv
from ernest_cpp.rl import layout as L
from ernest_cpp.rl.export import export_actor, load_policy
from ernest_cpp.rl.networks import Actor
from test_runtime import one_thread, run_runtime  # noqa: F401  (one_thread: a fixture)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# A policy exported with layout ernest-obs-v1 and the C++ normalisation table: a legacy file
# that must keep loading and acting bit for bit.
LEGACY_POLICY = os.path.join(ROOT, "tests", "data", "legacy_policy_v1.pt")

# (normalised observation seed, command) of that policy, one observation per call on one
# thread, recorded with torch alone: float32 bit patterns.
RECORDED_COMMANDS = [
    ["0x1.9987c4p-3", "-0x1.c4898ep-3", "-0x1.6d0478p-5"],
    ["0x1.9974ecp-3", "-0x1.655c76p-2", "0x1.639728p-3"],
    ["0x1.99997ep-3", "-0x1.657184p-2", "0x1.657184p-3"],
]


def fixed_observations() -> np.ndarray:
    rng = np.random.default_rng(2026)
    obs = rng.uniform(-0.1, 0.1, (3, 45)).astype(np.float32)
    obs[0] = 0.0
    return obs


def test_python_layout_is_the_cpp_table():
    lay = L.paper_layout()
    np.testing.assert_array_equal(lay.scale, np.asarray(sensing.ObservationScales().divisors()))
    assert lay.names == list(sensing.observation_names())
    assert lay.version == L.LAYOUT_VERSION == "ernest-obs-v2" == \
        f"ernest-obs-v{sensing.OBSERVATION_LAYOUT_VERSION}"
    env_lay = ErnestEnv("flat").observation_layout
    np.testing.assert_array_equal(env_lay.scale, lay.scale)
    assert env_lay.version == lay.version
    # no second table left in the Python module
    assert not any(hasattr(L, n) for n in ("FTS_FORCE_SCALE", "FTS_TORQUE_SCALE",
                                           "_paper_normalisation"))


def test_default_policy_acts_bit_for_bit_as_before(one_thread):
    _, meta = load_policy(LEGACY_POLICY)
    assert meta["layout_version"] == "ernest-obs-v1"  # a legacy file with the C++ table: accepted
    L.check_policy_layout(meta, LEGACY_POLICY)
    learned, passive = evaluate.controllers(LEGACY_POLICY)[evaluate.LEARNED]
    assert passive is False
    for obs, cmd_hex in zip(fixed_observations(), RECORDED_COMMANDS):
        cmd = np.array([float.fromhex(h) for h in cmd_hex])
        want = np.asarray(sensing.command_to_action(cmd))
        got = np.asarray(learned(obs))
        assert got.tobytes() == want.tobytes(), (got, want)


def test_default_policy_in_the_cpp_runtime_acts_as_in_python(tmp_path):
    obs = fixed_observations()
    np.savetxt(tmp_path / "obs.csv", obs.astype(np.float64), delimiter=",", fmt="%.9g")
    r = run_runtime("--policy", LEGACY_POLICY, "--replay", str(tmp_path / "obs.csv"),
                    "--actions", str(tmp_path / "act.csv"))
    assert r.returncode == 0, r.stderr
    got = np.loadtxt(tmp_path / "act.csv", delimiter=",", skiprows=1)[:, 1:]
    want = [sensing.command_to_action(np.array([float.fromhex(h) for h in c]))
            for c in RECORDED_COMMANDS]
    np.testing.assert_array_equal(got, np.asarray(want))


def old_python_table_layout() -> L.ObservationLayout:
    """A version 1 layout with the other table (torque 50, elevation 0.3, lateral 1)."""
    sc = sensing.ObservationScales()
    sc.torque, sc.elevation, sc.lateral = 50.0, 0.3, 1.0
    lay = L.ernest_layout(sc)
    lay.version = "ernest-obs-v1"
    return lay


def test_a_policy_with_the_other_table_is_refused_before_any_episode(tmp_path, capsys):
    torch.manual_seed(0)
    path = str(tmp_path / "other.pt")
    export_actor(Actor(45, 3, 32), old_python_table_layout(), path)
    with pytest.raises(ValueError, match=r"obs_scale\[1\] \(lateral_deviation\) = 1, the "
                                         r"environments use 2"):
        L.check_policy_layout(load_policy(path)[1], path)
    out = tmp_path / "report"
    assert cli.main(["evaluate", "--policy", path, "--out", str(out), "--no-video"]) == 2
    err = capsys.readouterr().err
    assert "another observation scale table" in err and "other.pt" in err
    assert not (out / "report.md").exists()
    # a version the code does not know is refused by name
    meta = load_policy(path)[1]
    meta["layout_version"] = "ernest-obs-v7"
    with pytest.raises(ValueError, match="layout_version 'ernest-obs-v7'"):
        L.check_policy_layout(meta, path)


def test_committed_default_policy_in_the_cpp_runtime_acts_as_in_python(tmp_path, one_thread):
    """The committed policy (layout v2) gives the same actions onboard as in Python."""
    policy = os.path.join(ROOT, "policies", "ernest_default.pt")
    _, meta = load_policy(policy)
    assert meta["layout_version"] == L.LAYOUT_VERSION
    obs = fixed_observations()
    learned, _ = evaluate.controllers(policy)[evaluate.LEARNED]
    want = np.asarray([learned(o) for o in obs])
    np.savetxt(tmp_path / "obs.csv", obs.astype(np.float64), delimiter=",", fmt="%.9g")
    r = run_runtime("--policy", policy, "--replay", str(tmp_path / "obs.csv"),
                    "--actions", str(tmp_path / "act.csv"))
    assert r.returncode == 0, r.stderr
    got = np.loadtxt(tmp_path / "act.csv", delimiter=",", skiprows=1)[:, 1:]
    np.testing.assert_array_equal(got, want)
