"""Onboard C++ runtime against the Python path.

The parity test exports a (randomly initialised, untrained) actor with ``ernest_cpp.rl.export``,
runs whole episodes with the Python environment and the Python actor (eager PyTorch, wrapped in the
export's ``ExportedPolicy`` normalisation), and the same episodes with the C++ ``ernest_runtime``
executable (libtorch and the TorchScript file, no Python), and compares the actions step by step.
``./run test`` passes the executable as ERNEST_RUNTIME_EXE (built by the C++ test build).

Why the Python actor runs inside ExportedPolicy: the export's numpy reference
(``export.reference_actions``) normalises in float64 and differs from the float32 normalisation of
the exported module by ~1e-7; the closed loop (contacts, a step edge) can amplify that to 1e-3
within an episode (measured: step scenario, seed 8, last step). With the normalisation done the
same way the actions agree exactly; the numpy reference is compared open loop, on the same
observations (test_same_observations_same_actions_as_the_numpy_reference).
"""

from __future__ import annotations

import glob
import os
import re
import subprocess

import numpy as np
import pytest
import torch

from ernest_cpp import sensing
from ernest_cpp.envs import ErnestEnv
from ernest_cpp.rl import layout as L
from ernest_cpp.rl.export import ExportedPolicy, export_actor, load_policy, reference_actions
from ernest_cpp.rl.networks import Actor

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def runtime_exe() -> str:
    exe = os.environ.get("ERNEST_RUNTIME_EXE", "")
    if exe and os.access(exe, os.X_OK):
        return exe
    found = sorted(glob.glob(os.path.join(ROOT, "build*", "cpp", "cpp", "runtime", "ernest_runtime")),
                   key=os.path.getmtime)
    assert found, ("ernest_runtime not built: run the C++ test build (./run test) or set "
                   "ERNEST_RUNTIME_EXE")
    return found[-1]


def run_runtime(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([runtime_exe(), *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    torch.manual_seed(1234)
    actor = Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 512)
    lay = ErnestEnv("flat").observation_layout
    path = str(tmp_path_factory.mktemp("policy") / "actor.pt")
    export_actor(actor, lay, path)
    return actor, lay, path


@pytest.fixture
def one_thread():
    """Python torch on one intra-op thread like the runtime (restored afterwards)."""
    old = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(old)


def python_episode(policy, scenario: str, seed: int, duration: float, terrain_source="truth"):
    """The Python path: ErnestEnv, physical observation -> policy (torch, float32) -> physical
    command -> sensing.command_to_action -> env.step, until the episode ends. Returns the actions,
    the normalised observations they were computed from, the metrics and the last info."""
    env = ErnestEnv(scenario, episode_length=duration, terrain_source=terrain_source)
    scale = np.asarray(env.options.scales.divisors())
    obs, _ = env.reset(seed=seed)
    actions, observations = [], []
    while True:
        with torch.no_grad():
            cmd = policy(torch.as_tensor(obs * scale, dtype=torch.float32)).numpy().astype(np.float64)
        action = np.asarray(sensing.command_to_action(cmd))
        actions.append(action)
        observations.append(obs)
        obs, _, term, trunc, info = env.step(action)
        if term or trunc:
            return np.array(actions), np.array(observations), env.metrics, info


def cpp_episode(path, scenario, seed, duration, tmp_path, mode="env", terrain_source="truth"):
    out = tmp_path / f"actions_{scenario}_{seed}_{mode}.csv"
    tel = tmp_path / f"telemetry_{scenario}_{seed}_{mode}.csv"
    r = run_runtime("--policy", path, "--scenario", scenario, "--seed", str(seed), "--duration",
                    str(duration), "--actions", str(out), "--telemetry", str(tel), "--mode", mode,
                    "--terrain-source", terrain_source)
    assert r.returncode == 0, r.stdout + r.stderr
    return np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:], r.stdout, tel


@pytest.mark.parametrize("scenario,seed", [("rockfield", 3), ("step", 8), ("ripples", 2)])
def test_parity_python_actor_vs_cpp_runtime_whole_episode(exported, tmp_path, one_thread, scenario,
                                                           seed):
    actor, lay, path = exported
    python_actor = ExportedPolicy(actor, lay, L.POLICY_RATE_HZ).eval()  # eager, not TorchScript
    duration = 10.0
    py, _, metrics, info = python_episode(python_actor, scenario, seed, duration)
    cpp, stdout, tel = cpp_episode(path, scenario, seed, duration, tmp_path)
    assert py.shape == cpp.shape == (int(duration / 0.5), 3)  # the whole episode (time limit)
    assert info["message"] == "time limit"
    # The policy must actually vary its actions over the episode for the comparison to bite.
    assert np.ptp(py, axis=0).max() > 1e-2
    np.testing.assert_allclose(cpp, py, rtol=0, atol=1e-5)

    # The executable reports the same episode figures as the Python env (Table 6 metrics).
    def printed(name):
        m = re.search(name + r"\s+([-+0-9.eE]+)", stdout)
        assert m, stdout
        return float(m.group(1))

    assert printed("progress along the path") == pytest.approx(metrics["progress"], abs=2e-3)
    assert printed("travel reduction") == pytest.approx(metrics["travel_reduction"], abs=2e-3)
    assert printed("cost of transport") == pytest.approx(metrics["cost_of_transport"], rel=2e-3)
    # Telemetry: one row per policy step with the actions sent.
    rows = np.genfromtxt(tel, delimiter=",", names=True)
    assert len(rows) == len(py)
    np.testing.assert_allclose(rows["action_vx"], cpp[:, 0], atol=1e-12)


def test_parity_with_stereo_elevation_map(exported, tmp_path, one_thread):
    # terrain_source="stereo": the elevation samples come from the map fused from ray-cast
    # StereoBM pairs (seed 004 §2.4); the C++ runtime (no Python) makes the Python path's decisions.
    actor, lay, path = exported
    python_actor = ExportedPolicy(actor, lay, L.POLICY_RATE_HZ).eval()
    py, obs, _, _ = python_episode(python_actor, "rockfield", 3, 5.0, terrain_source="stereo")
    truth, truth_obs, _, _ = python_episode(python_actor, "rockfield", 3, 5.0)
    cpp, _, _ = cpp_episode(path, "rockfield", 3, 5.0, tmp_path, terrain_source="stereo")
    assert py.shape == cpp.shape == (10, 3)
    np.testing.assert_allclose(cpp, py, rtol=0, atol=1e-5)
    elev = slice(sensing.OBSERVATION_INDEX["elevation"], sensing.OBSERVATION_INDEX["elevation"] + 12)
    assert not np.allclose(obs[:, elev], truth_obs[:, elev])  # the map is what the policy saw
    # the onboard 400 Hz loop fuses its own map from the interface's stereo pairs
    onboard, _, _ = cpp_episode(path, "rockfield", 3, 5.0, tmp_path, mode="onboard",
                                terrain_source="stereo")
    assert onboard.shape == (10, 3) and np.all(np.isfinite(onboard))


def test_parity_python_torchscript_module_vs_cpp_runtime(exported, tmp_path, one_thread):
    # The exported file itself, run by Python torch, gives the C++ runtime's actions too.
    _, _, path = exported
    module, _ = load_policy(path)
    py, _, _, _ = python_episode(module, "slope", 4, 6.0)
    cpp, _, _ = cpp_episode(path, "slope", 4, 6.0, tmp_path)
    np.testing.assert_allclose(cpp, py, rtol=0, atol=1e-5)


def test_same_observations_same_actions_as_the_numpy_reference(exported, tmp_path, one_thread):
    # Open loop: the observations of a Python episode through the export's numpy reference path
    # (float64 normalisation, Python actor) and through the C++ runtime (--replay).
    actor, lay, path = exported
    py_module = ExportedPolicy(actor, lay, L.POLICY_RATE_HZ).eval()
    _, observations, _, _ = python_episode(py_module, "step", 8, 10.0)
    scale = np.asarray(ErnestEnv("flat").options.scales.divisors())
    want = np.array([np.asarray(sensing.command_to_action(c))
                     for c in reference_actions(actor, lay, observations.astype(np.float64) * scale)])
    obs_csv = tmp_path / "observations.csv"
    np.savetxt(obs_csv, observations, delimiter=",", fmt="%.9g")
    out = tmp_path / "replayed.csv"
    r = run_runtime("--policy", path, "--replay", str(obs_csv), "--actions", str(out))
    assert r.returncode == 0, r.stdout + r.stderr
    got = np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:]
    assert got.shape == want.shape == (20, 3)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)


def test_onboard_mode_runs_the_400hz_loop(exported, tmp_path):
    _, _, path = exported
    cpp, stdout, tel = cpp_episode(path, "flat", 1, 3.0, tmp_path, mode="onboard")
    assert len(cpp) == 6 and "watchdog trips           0" in stdout
    rows = np.genfromtxt(tel, delimiter=",", names=True)
    assert len(rows) == 150  # 50 Hz telemetry for 3 s
    assert np.all(np.diff(rows["time"]) > 0) and np.all(np.isfinite(rows["power"]))


def test_runtime_rejects_wrong_files_clearly(exported, tmp_path):
    actor, _, _ = exported
    r = run_runtime("--policy", str(tmp_path / "missing.pt"), "--scenario", "flat", "--seed", "1",
                    "--duration", "1")
    assert r.returncode == 1 and "missing file" in r.stderr and "missing.pt" in r.stderr
    # A policy exported with another normalisation table (version 1 files may carry one under
    # the same version string) does not match the runtime's observation layout: refused before
    # anything runs, naming the first entry that differs.
    other = str(tmp_path / "other_layout.pt")
    sc = sensing.ObservationScales()
    sc.torque, sc.elevation, sc.lateral = 50.0, 0.3, 1.0
    lay = L.ernest_layout(sc)
    lay.version = "ernest-obs-v1"
    export_actor(actor, lay, other)
    r = run_runtime("--policy", other, "--scenario", "flat", "--seed", "1", "--duration", "1")
    assert r.returncode == 1, r.stdout
    assert "layout mismatch" in r.stderr and "obs_scale[1] = 1, expected 2 (lateral_deviation)" \
        in r.stderr and "another observation scale table" in r.stderr, r.stderr


def test_runtime_usage_errors_are_distinct_with_exit_code_2(tmp_path):
    # each usage error has its own message; all exit with 2 (documented in --help)
    r = run_runtime("--help")
    assert r.returncode == 0 and "exit status" in r.stdout and "2 usage error" in r.stdout
    ok = ["--policy", "p.pt", "--scenario", "flat", "--seed", "1", "--duration", "1"]

    def without(*names):
        out, skip = [], False
        for a in ok:
            if skip:
                skip = False
            elif a in names:
                skip = True
            else:
                out.append(a)
        return out

    cases = [
        (["--bogus"], "unknown argument '--bogus'"),
        (["--policy"], "--policy needs a value"),
        (without("--policy"), "--policy FILE is required"),
        (without("--scenario"), "--scenario NAME is required"),
        (without("--seed"), "--seed N is required"),
        (without("--duration"), "--duration S is required"),
        (ok[:5] + ["abc"] + ok[6:], "--seed 'abc' is not an integer"),
        (ok[:5] + ["-4"] + ok[6:], "--seed -4 must be >= 0"),
        (ok[:7] + ["3x"], "--duration '3x' is not a finite number"),
        (ok[:7] + ["inf"], "--duration 'inf' is not a finite number"),
        (ok[:7] + ["0"], "must be > 0"),
        (ok[:3] + ["moon"] + ok[4:], "--scenario 'moon' is not one of: "),
        (ok + ["--mode", "fast"], "--mode 'fast' is not one of: env, onboard"),
        (ok + ["--soil", "clay"], "--soil: "),
        (ok + ["--terrain-source", "lidar"], "--terrain-source 'lidar' is not one of"),
        (["--policy", "p.pt", "--replay", "obs.csv"], "--replay needs --actions"),
        (["--policy", "p.pt", "--replay", "o.csv", "--actions", "a.csv", "--seed", "1"],
         "--replay runs logged observations"),
    ]
    messages = set()
    for args, want in cases:
        r = run_runtime(*args)
        assert r.returncode == 2, (args, r.stderr)
        assert want in r.stderr and "ernest_runtime --help" in r.stderr, (args, r.stderr)
        messages.add(r.stderr.splitlines()[0])
    assert len(messages) == len(cases)
