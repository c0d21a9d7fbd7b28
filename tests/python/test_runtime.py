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


def read_csv(path) -> dict[str, np.ndarray]:
    """The runtime's CSV as {header: column}; each header names its unit, e.g. 'time [s]'."""
    with open(path) as fh:
        header = fh.readline().rstrip("\n").split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, k] for k, name in enumerate(header)}


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
    rows = read_csv(tel)
    assert len(rows["action_vx [-]"]) == len(py)
    np.testing.assert_allclose(rows["action_vx [-]"], cpp[:, 0], atol=1e-12)


def test_runtime_stands_each_scenario_on_its_gymnasium_ids_soil(exported, tmp_path, one_thread):
    """Without --soil the runtime takes the scenario's soil (envs.core.default_soil), as its
    Gymnasium id does: the Bickler trap on dry sand, the same episode as ernest/BicklerTrap-v0."""
    import gymnasium as gym

    from ernest_cpp.scenarios import SCENARIOS

    actor, lay, path = exported
    for scenario in ("bickler", "step"):
        soil = gym.make(SCENARIOS[scenario]).unwrapped.options.soil
        assert soil == ("dry_sand" if scenario == "bickler" else "m90")
        r = run_runtime("--policy", path, "--scenario", scenario, "--seed", "1", "--duration", "1",
                        "--quiet")
        assert r.returncode == 0, r.stdout + r.stderr
        assert f"scenario {scenario} on {soil} seed 1 " in r.stdout, r.stdout
    python_actor = ExportedPolicy(actor, lay, L.POLICY_RATE_HZ).eval()
    py, _, metrics, _ = python_episode(python_actor, "bickler", 4, 3.0)
    cpp, stdout, _ = cpp_episode(path, "bickler", 4, 3.0, tmp_path)
    np.testing.assert_allclose(cpp, py, rtol=0, atol=1e-5)
    m = re.search(r"progress along the path\s+([-+0-9.eE]+)", stdout)
    assert float(m.group(1)) == pytest.approx(metrics["progress"], abs=2e-3)
    r = run_runtime("--policy", path, "--scenario", "bickler", "--seed", "1", "--duration", "1",
                    "--soil", "m90", "--quiet")  # a chosen soil still wins
    assert r.returncode == 0 and "scenario bickler on m90 seed 1 " in r.stdout, r.stdout


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
    rows = read_csv(tel)
    assert len(rows["time [s]"]) == 150  # 50 Hz telemetry for 3 s
    assert np.all(np.diff(rows["time [s]"]) > 0) and np.all(np.isfinite(rows["power [W]"]))


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


# ------------------------------------------------------------------ files: outputs and inputs
EPISODE = ["--scenario", "flat", "--seed", "1", "--duration", "1", "--quiet"]


def _observations_csv(path, rows: int = 3, header: str | None = None) -> None:
    lines = ([header] if header is not None else []) + \
        [",".join(f"{0.01 * (k + i):.6g}" for i in range(sensing.OBSERVATION_SIZE))
         for k in range(rows)]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("mode", ["env", "onboard"])
@pytest.mark.parametrize("option, target", [
    ("--actions", "/dev/full"), ("--telemetry", "/dev/full"), ("--actions", "/proc/version"),
    ("--telemetry", "/proc/version"), ("--actions", "{tmp}/no_such_dir/a.csv"),
    ("--telemetry", "{tmp}")])
def test_runtime_exits_nonzero_when_an_output_cannot_be_written(exported, tmp_path, mode, option,
                                                                target):
    if target.startswith("/") and not os.path.exists(target):
        pytest.skip(f"{target} does not exist here")
    _, _, path = exported
    target = target.format(tmp=tmp_path)
    r = run_runtime("--policy", path, *EPISODE, "--mode", mode, option, target)
    assert r.returncode == 1, (r.returncode, r.stdout, r.stderr)
    assert f"cannot write {target}" in r.stderr, r.stderr


def test_replay_exits_nonzero_when_the_actions_cannot_be_written(exported, tmp_path):
    _, _, path = exported
    obs = tmp_path / "obs.csv"
    _observations_csv(obs)
    for target in ("/dev/full", str(tmp_path / "no_such_dir" / "a.csv"), str(tmp_path)):
        if target == "/dev/full" and not os.path.exists(target):
            continue
        r = run_runtime("--policy", path, "--replay", str(obs), "--actions", target)
        assert r.returncode == 1 and f"cannot write {target}" in r.stderr, (target, r.stderr)
        assert "replayed" not in r.stdout


def test_runtime_never_overwrites_an_input(exported, tmp_path):
    _, _, path = exported
    obs = tmp_path / "obs.csv"
    _observations_csv(obs)
    before = obs.read_bytes()
    policy_before = open(path, "rb").read()
    link = tmp_path / "link.csv"
    os.symlink(obs, link)
    hard = tmp_path / "hard.csv"
    os.link(obs, hard)
    same = [str(obs), str(tmp_path / "." / "obs.csv"), str(link), str(hard)]
    for out in same:
        r = run_runtime("--policy", path, "--replay", str(obs), "--actions", out)
        assert r.returncode == 2, (out, r.stdout, r.stderr)
        assert "is the same file as --replay" in r.stderr and out in r.stderr, r.stderr
        assert obs.read_bytes() == before
    for option in ("--actions", "--telemetry"):
        r = run_runtime("--policy", path, *EPISODE, option, path)
        assert r.returncode == 2 and "is the same file as --policy" in r.stderr, r.stderr
    r = run_runtime("--policy", path, "--replay", str(obs), "--actions", path)
    assert r.returncode == 2 and "is the same file as --policy" in r.stderr, r.stderr
    assert open(path, "rb").read() == policy_before
    # Two outputs into one file would interleave: refused too.
    out = tmp_path / "out.csv"
    out.write_text("keep\n")
    r = run_runtime("--policy", path, *EPISODE, "--actions", str(out), "--telemetry",
                    str(tmp_path / "." / "out.csv"))
    assert r.returncode == 2 and "--telemetry" in r.stderr and "same file as --actions" \
        in r.stderr, r.stderr
    assert out.read_text() == "keep\n"
    if os.path.exists("/dev/null"):  # a device taking both outputs loses nothing: accepted
        r = run_runtime("--policy", path, *EPISODE, "--actions", "/dev/null", "--telemetry",
                        "/dev/null")
        assert r.returncode == 0, r.stderr
    # An ordinary replay still works, with or without a header line.
    for header in (None, "o0,o1,o2"):
        _observations_csv(obs, header=header)
        r = run_runtime("--policy", path, "--replay", str(obs), "--actions", str(out))
        assert r.returncode == 0 and "replayed 3 observations" in r.stdout, r.stdout + r.stderr
        assert len(out.read_text().splitlines()) == 4


N = sensing.OBSERVATION_SIZE


def _row(first: str = "0", last: str = "0", n: int = N) -> str:
    return ",".join([first] + ["0.25"] * (n - 2) + [last])


@pytest.mark.parametrize("lines, where, what", [
    ([_row(), _row("nan")], "line 2, column 1", "'nan' is not a finite number"),
    ([_row("nan")], "line 1, column 1", "'nan' is not a finite number"),
    ([_row(), _row("-inf")], "line 2, column 1", "'-inf' is not a finite number"),
    ([_row("INF")], "line 1, column 1", "'INF' is not a finite number"),
    (["o1,o2", _row("0.5xyz")], "line 2, column 1", "'0.5xyz' is not a number"),
    ([_row(last="abc")], f"line 1, column {N}", "'abc' is not a number"),
    ([_row(), _row("1e999")], "line 2, column 1", "'1e999' is not a finite number"),
    ([_row(), _row(last="-1e999")], f"line 2, column {N}", "'-1e999' is not a finite number"),
    ([_row(), "0,,0"], "line 2, column 2", "'' is not a number"),
    ([_row(), _row(), "header,again"], "line 3, column 1", "'header' is not a number"),
    ([_row(), _row(n=N - 1)], "line 2", f"expected {N} values, found {N - 1}"),
    ([_row(n=N + 1)], "line 1", f"expected {N} values, found {N + 1}"),
    ([_row(), _row("0x1p3")], "line 2, column 1", "'0x1p3' is not a number"),
])
def test_replay_refuses_malformed_rows_naming_file_line_and_column(exported, tmp_path, lines,
                                                                   where, what):
    _, _, path = exported
    obs = tmp_path / "obs.csv"
    obs.write_text("\n".join(lines) + "\n")
    out = tmp_path / "actions.csv"
    r = run_runtime("--policy", path, "--replay", str(obs), "--actions", str(out))
    assert r.returncode == 1, (r.stdout, r.stderr)
    assert f"{obs}: {where}" in r.stderr and what in r.stderr, r.stderr
    assert "replayed" not in r.stdout


def test_replay_reads_crlf_and_spaced_fields(exported, tmp_path):
    _, _, path = exported
    obs, ref = tmp_path / "obs.csv", tmp_path / "ref.csv"
    _observations_csv(ref)
    obs.write_bytes(b"".join(b" " + ln.replace(b",", b" , ") + b"\r\n"
                             for ln in ref.read_bytes().splitlines()))
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert run_runtime("--policy", path, "--replay", str(ref), "--actions", str(a)).returncode == 0
    r = run_runtime("--policy", path, "--replay", str(obs), "--actions", str(b))
    assert r.returncode == 0, r.stderr
    assert a.read_text() == b.read_text()


def test_replay_refuses_a_directory_or_an_unreadable_input(exported, tmp_path):
    _, _, path = exported
    out = tmp_path / "actions.csv"
    r = run_runtime("--policy", path, "--replay", str(tmp_path), "--actions", str(out))
    assert r.returncode == 1 and f"cannot read {tmp_path}" in r.stderr, r.stderr
    assert "is a directory" in r.stderr and "replayed" not in r.stdout
    r = run_runtime("--policy", path, "--replay", str(tmp_path / "missing.csv"), "--actions",
                    str(out))
    assert r.returncode == 1 and f"cannot read {tmp_path / 'missing.csv'}" in r.stderr, r.stderr
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    r = run_runtime("--policy", path, "--replay", str(empty), "--actions", str(out))
    assert r.returncode == 1 and f"{empty}: no observations" in r.stderr, r.stderr


def test_runtime_exits_nonzero_when_standard_output_cannot_be_written(exported, tmp_path):
    if not os.path.exists("/dev/full"):
        pytest.skip("/dev/full does not exist here")
    _, _, path = exported
    obs = tmp_path / "obs.csv"
    _observations_csv(obs)
    for args in ([*EPISODE], ["--replay", str(obs), "--actions", str(tmp_path / "a.csv")]):
        with open("/dev/full", "w") as full:
            r = subprocess.run([runtime_exe(), "--policy", path, *args], stdout=full,
                               stderr=subprocess.PIPE, text=True, timeout=300)
        assert r.returncode == 1 and "cannot write standard output" in r.stderr, (args, r.stderr)
