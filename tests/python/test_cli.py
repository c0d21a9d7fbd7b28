"""The ``ernest`` command on wrong invocations: one clear line and exit code 2,
never a traceback; usage of the subcommand that was mistyped; ``--version``; plain-text help."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import ernest_cpp
from ernest_cpp import cli

POINT_MASS = "ernest-toy/PointMass-v0"


def _one_line_error(capsys, *parts: str) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for p in parts:
        assert p in err, err
    return err


def test_missing_config_file(capsys):
    assert cli.main(["train", "--env", POINT_MASS, "--config", "/missing.yaml"]) == 2
    _one_line_error(capsys, "ernest train: error:", "--config /missing.yaml", "No such file")


def test_invalid_config_yaml(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("td3: [unclosed\n")
    assert cli.main(["train", "--env", POINT_MASS, "--config", str(bad)]) == 2
    _one_line_error(capsys, "not valid YAML")


@pytest.mark.parametrize("command", ["evaluate", "soil-curves"])
def test_output_folder_that_cannot_exist(capsys, command):
    assert cli.main([command, "--out", "/dev/null/x"]) == 2
    _one_line_error(capsys, f"ernest {command}: error:", "/dev/null/x", "Not a directory")


def test_console_script_exits_2_without_traceback():
    # the installed entry point, as a user runs it
    r = subprocess.run([sys.executable, "-c", "import sys; from ernest_cpp.cli import main; "
                        "sys.exit(main())", "evaluate", "--out", "/dev/null/x"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "/dev/null/x" in r.stderr


def test_unknown_option_prints_the_subcommand_usage(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["train", "--bogus"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: ernest train") and "--steps" in err
    assert "ernest train: error: unrecognized arguments: --bogus" in err


@pytest.mark.parametrize("value", ["-5", "0", "many"])
def test_steps_must_be_a_positive_whole_number(capsys, value):
    with pytest.raises(SystemExit) as e:
        cli.main(["train", "--env", POINT_MASS, "--steps", value])
    assert e.value.code == 2
    assert "argument --steps" in capsys.readouterr().err


def test_total_steps_from_settings_must_be_positive(tmp_path, capsys):
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", str(tmp_path / "r"), "--set",
                     "total_steps=-5", "--set", "log.progress_bar=false", "--set",
                     "log.tensorboard=false"]) == 2
    _one_line_error(capsys, "total_steps = -5")


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out == f"ernest {ernest_cpp.__version__}\n"


def test_version_of_the_installed_command_is_the_package_version():
    from importlib.metadata import version
    exe = os.path.join(os.path.dirname(sys.executable), "ernest")
    r = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout == f"ernest {version('ernest-cpp')}\n"
    assert ernest_cpp.__version__ == version("ernest-cpp")


def test_help_is_plain_text(capsys):
    parser, sub = cli.build_parser()
    texts = [parser.format_help()] + [p.format_help() for p in sub.choices.values()]
    for text in texts:
        assert "``" not in text and ":class:" not in text and ":func:" not in text
    assert "ernest COMMAND --help" in texts[0]


@pytest.mark.parametrize("command", [["train", "--env", "ernest/Slope-v0"], ["perception"],
                                     ["footfall"], ["evaluate"], ["reproduce"]])
@pytest.mark.parametrize("seed, message", [("-1", "-1 is outside [0, 2**64)"),
                                           (str(2 ** 64), f"{2 ** 64} is outside [0, 2**64)"),
                                           ("x", "'x' is not a whole number")])
def test_every_seed_option_names_itself_and_its_range(capsys, command, seed, message):
    with pytest.raises(SystemExit) as exc:
        cli.main(command + ["--seed", seed])
    assert exc.value.code == 2
    assert f"argument --seed: {message}" in capsys.readouterr().err


def test_print_config_prints_the_resolved_settings_and_trains_nothing(tmp_path, capsys):
    import yaml

    run = tmp_path / "run"
    assert cli.main(["train", "--scenario", "step", "--preset", "paper", "--seed", "3",
                     "--set", "td3.batch_size=64", "--run-dir", str(run), "--print-config"]) == 0
    cfg = yaml.safe_load(capsys.readouterr().out)
    assert cfg["env"]["scenario"] == "step" and cfg["seed"] == 3
    assert cfg["td3"]["batch_size"] == 64 and "consolidate" in cfg  # the whole settings tree
    assert not run.exists()


def test_resume_with_no_more_steps_than_done_names_both_counts(tmp_path, capsys):
    run = str(tmp_path / "run")
    quick = ["--set", "log.progress_bar=false", "--set", "log.tensorboard=false",
             "--set", "eval.every_steps=0", "--set", "random_steps=50",
             "--set", "learning_starts=50", "--set", "td3.hidden=16"]
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", run, "--steps", "200"] + quick) == 0
    capsys.readouterr()
    for extra, given in ((["--steps", "150"], "--steps 150"),
                         (["--set", "total_steps=100"], "--set total_steps=100"),
                         ([], "total_steps 200 (the run's saved settings)")):
        assert cli.main(["train", "--run-dir", run, "--resume", *extra]) == 2
        _one_line_error(capsys, given, "has done 200 transitions already", "--steps above 200")


# The Python API behind each command: a keyword entry point that takes the command's options by
# name (README, "Every command from Python"); cli.run takes any command by name.
ENTRY_POINTS = {
    "soil-curves": "ernest_cpp.soil_curves:main", "evaluate": "ernest_cpp.evaluate:main",
    "transitions": "ernest_cpp.transitions:main", "slope-demo": "ernest_cpp.slope_demo:main",
    "reproduce": "ernest_cpp.reproduce:main", "statics": "ernest_cpp.rover_statics:main",
    "walker": "ernest_cpp.walker_demo:main", "perception": "ernest_cpp.perception_demo:main",
    "footfall": "ernest_cpp.footfall_demo:main", "train": "ernest_cpp.rl.commands:train",
    "consolidate": "ernest_cpp.rl.commands:consolidate",
    "export": "ernest_cpp.rl.commands:export_policy",
    "stamp-policy": "ernest_cpp.rl.commands:stamp",
    "train-default": "ernest_cpp.rl.pipeline:train_default",
    "view": "ernest_cpp.viewer.command:main",
}


def test_every_command_has_a_keyword_entry_point():
    import importlib

    _, sub = cli.build_parser()
    assert set(ENTRY_POINTS) <= set(sub.choices)
    for command in sub.choices:  # any command, also by name
        assert cli.command_argv(command) == [command]
    for command, target in ENTRY_POINTS.items():
        module, name = target.split(":")
        fn = getattr(importlib.import_module(module), name)
        assert f"``ernest {command}``" in fn.__doc__, target


def test_keyword_options_map_to_the_command_line():
    argv = cli.command_argv("evaluate", out="o", scenario=["step", "bickler"], no_video=True,
                            policy=None, seed=3)
    assert argv == ["evaluate", "--out", "o", "--scenario", "step", "--scenario", "bickler",
                    "--no-video", "--seed", "3"]
    assert cli.command_argv("consolidate", runs=["a", "b"], out="c", set=["seed=1"]) == [
        "consolidate", "--out", "c", "--set", "seed=1", "--", "a", "b"]
    with pytest.raises(TypeError, match="unknown keyword.*outt.*known: .*out"):
        cli.command_argv("evaluate", outt="o")
    with pytest.raises(TypeError, match="unknown command 'evaluat'"):
        cli.command_argv("evaluat")
    with pytest.raises(TypeError, match="no_video = 'yes' must be True or False"):
        cli.command_argv("evaluate", no_video="yes")


def test_a_command_runs_from_python_with_keywords(capsys):
    from ernest_cpp.rl import commands

    assert commands.train(scenario="step", print_config=True, set=["td3.hidden=32"]) == 0
    out = capsys.readouterr().out
    assert "scenario: step" in out and "hidden: 32" in out
    with pytest.raises(ValueError, match="--seed"):  # checked as on the command line
        commands.train(scenario="step", seed=-1, print_config=True)
    with pytest.raises(ValueError, match="invalid choice: 'rock_field'"):
        commands.train(scenario="rock_field", print_config=True)
