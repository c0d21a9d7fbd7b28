"""One short name per scenario everywhere: the C++ core's names (the runtime's --scenario), the
Gymnasium ids they register, ``ernest train --scenario`` and ``ernest evaluate --scenario``."""

import glob
import os
import subprocess

import gymnasium as gym
import pytest

import ernest_cpp.envs as E
from ernest_cpp.envs.core import scenario_names
from ernest_cpp import cli, evaluate
from ernest_cpp.rl.envs_util import resolve_env_id
from ernest_cpp.scenarios import SCENARIOS, TRAINING_SCENARIOS, scenario_env_id, scenario_name

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_the_table_is_the_cores_names_and_the_registered_ids():
    assert sorted(SCENARIOS) == sorted(scenario_names())  # the C++ core's names
    assert set(TRAINING_SCENARIOS) <= set(SCENARIOS)
    for name, env_id in SCENARIOS.items():
        assert env_id in gym.registry and E.ENV_IDS[env_id] == name
        assert scenario_env_id(name) == env_id and scenario_name(env_id) == name
        assert gym.spec(env_id).kwargs["scenario"] == name
    with pytest.raises(ValueError, match="rockfield, step"):
        scenario_env_id("BicklerTrap-v0")


@pytest.mark.parametrize("alias", ["rock_field", "bickler_trap", "RockField-v0", "Bickler"])
def test_the_env_refuses_other_names_listing_the_short_ones(alias):
    with pytest.raises(ValueError, match="allowed: rockfield, step, ripples, slope, bickler"):
        E.ErnestEnv(alias)
    with pytest.raises(ValueError, match="allowed: rockfield"):
        E.make_options(alias)


def test_train_takes_every_short_name(capsys):
    for name, env_id in SCENARIOS.items():
        assert resolve_env_id({"scenario": name}) == env_id
        assert cli.main(["train", "--scenario", name, "--print-config"]) == 0
        assert f"scenario: {name}" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        cli.main(["train", "--scenario", "BicklerTrap-v0", "--print-config"])


def test_evaluate_picks_courses_by_short_name():
    assert evaluate.courses(None) == evaluate.COURSES
    slope = evaluate.courses(["slope_eval"])
    assert [c[0] for c in slope] == ["20 deg slope, dry M90", "20 deg slope, wet sand"]
    assert evaluate.courses(["bickler", "bickler"]) == [evaluate.COURSES[0]]
    assert evaluate.courses(["flat"]) == [("flat (ernest/Flat-v0)", "ernest/Flat-v0", {})]
    with pytest.raises(SystemExit):
        cli.main(["evaluate", "--scenario", "BicklerTrap-v0"])


def test_runtime_offers_the_same_names():
    exe = os.environ.get("ERNEST_RUNTIME_EXE", "")
    if not (exe and os.access(exe, os.X_OK)):
        found = sorted(glob.glob(os.path.join(ROOT, "build*", "cpp", "cpp", "runtime",
                                              "ernest_runtime")), key=os.path.getmtime)
        assert found, "ernest_runtime not built: set ERNEST_RUNTIME_EXE"
        exe = found[-1]
    out = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60).stdout
    line = next(ln for ln in out.splitlines() if ln.startswith("scenarios:"))
    assert sorted(line.split()[1:]) == sorted(SCENARIOS)


def test_evaluate_records_the_animation_on_the_chosen_scenario(tmp_path, monkeypatch):
    from ernest_cpp.envs import render

    assert evaluate.video_course(evaluate.COURSES)[1] == "ernest/Course-v0"  # all: mixed course
    assert evaluate.video_course(evaluate.courses(["slope_eval", "bickler"])) == evaluate.COURSES[1]
    recorded = []

    def record(env, policy, path, **kwargs):  # the recording itself is render.py's, tested there
        recorded.append((env.scenario_name, env.options.soil, os.path.basename(path)))
        open(path, "wb").close()

    monkeypatch.setattr(render, "record_episode", record)
    # the keyword entry point of `ernest evaluate --scenario bickler --out ...`
    assert evaluate.main(out=str(tmp_path), scenario=["bickler"]) == 0
    assert recorded == [("bickler", "dry_sand", "bickler.gif")]
    assert not (tmp_path / "course.gif").exists()
    assert "(bickler.gif)" in (tmp_path / "report.md").read_text()
