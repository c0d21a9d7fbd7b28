"""Resuming training: which checkpoint a resume finds when ``LATEST`` is missing or damaged, the
refusal of settings that differ from the run's saved ones (unless ``--override-config``), the
``ernest train-default`` pipeline's resume call, and replay buffers holding non-finite values."""

from __future__ import annotations

import copy
import json
import os

import numpy as np
import pytest
import yaml

from ernest_cpp import cli
from ernest_cpp.rl import config as C
from ernest_cpp.rl import pipeline as P
from ernest_cpp.rl.checkpoints import load_checkpoint
from ernest_cpp.rl.replay import ReplayBuffer
from ernest_cpp.rl.storage import CorruptFileError, sha256_file
from ernest_cpp.rl.trainer import Trainer

POINT_MASS = "ernest-toy/PointMass-v0"
SMALL = ["td3.hidden=16", "td3.batch_size=32", "random_steps=50", "learning_starts=50",
         "eval.every_steps=0", "checkpoint.every_steps=100", "checkpoint.keep=3",
         "log.progress_bar=false", "log.tensorboard=false", "buffer_size=1000"]


def _sets(extra=()) -> list[str]:
    out = []
    for s in [*SMALL, *extra]:
        out += ["--set", s]
    return out


@pytest.fixture
def run(tmp_path):
    """A point-mass run with checkpoints at steps 100 and 200 (LATEST names step-200)."""
    path = str(tmp_path / "run")
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", path, "--steps", "200",
                     *_sets()]) == 0
    return path


def _ck_root(run: str) -> str:
    return os.path.join(run, "checkpoints")


def _damage(ck: str) -> None:
    agent = os.path.join(ck, "agent.pt")
    data = bytearray(open(agent, "rb").read())
    data[len(data) // 2] ^= 0xFF
    open(agent, "wb").write(bytes(data))


@pytest.mark.parametrize("latest", [None, b"", b"garbage\n", b"step-000000000999\n",
                                    b"../../elsewhere\n", b"\xff\xfe\x00step"])
def test_resume_finds_the_newest_intact_checkpoint_without_a_usable_latest(run, latest, capsys):
    root = _ck_root(run)
    if latest is None:
        os.remove(os.path.join(root, "LATEST"))
    else:
        with open(os.path.join(root, "LATEST"), "wb") as fh:
            fh.write(latest)
    assert load_checkpoint(run, with_buffer=False)["path"] == os.path.join(root,
                                                                          "step-000000000200")
    # The newest is damaged: the intact one before it.
    _damage(os.path.join(root, "step-000000000200"))
    assert load_checkpoint(run, with_buffer=False)["path"] == os.path.join(root,
                                                                          "step-000000000100")
    capsys.readouterr()
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "300"]) == 0
    assert "resumed" in capsys.readouterr().out
    ck = load_checkpoint(run, with_buffer=False)
    assert ck["state"]["step"] == 300 and ck["path"].endswith("step-000000000300")
    assert open(os.path.join(root, "LATEST")).read().strip() == "step-000000000300"


def test_a_consolidation_folder_is_found_by_its_latest_or_without_it(run, tmp_path):
    cons = str(tmp_path / "cons")
    assert cli.main(["consolidate", run, "--out", cons, "--no-eval", "--set",
                     "consolidate.iterations=5", "--set", "consolidate.hidden=16", "--set",
                     "consolidate.batch_size=16", "--set", "log.progress_bar=false"]) == 0
    final = os.path.join(cons, "checkpoints", "consolidated")
    assert load_checkpoint(cons, with_buffer=False)["path"] == final
    for latest in (b"", b"garbage\n", None):
        if latest is None:
            os.remove(os.path.join(cons, "checkpoints", "LATEST"))
        else:
            with open(os.path.join(cons, "checkpoints", "LATEST"), "wb") as fh:
                fh.write(latest)
        assert load_checkpoint(cons, with_buffer=False)["path"] == final


def test_no_intact_checkpoint_and_no_latest_says_why(run):
    root = _ck_root(run)
    os.remove(os.path.join(root, "LATEST"))
    for d in ("step-000000000100", "step-000000000200"):
        _damage(os.path.join(root, d))
    with pytest.raises(CorruptFileError, match=r"no intact checkpoint among the 2 step-N "
                                               r"folders.*step-000000000200.*checksum mismatch"):
        load_checkpoint(run, with_buffer=False)
    with open(os.path.join(root, "LATEST"), "w") as fh:
        fh.write("garbage\n")
    with pytest.raises(CorruptFileError, match="no intact checkpoint among"):
        load_checkpoint(run, with_buffer=False)
    empty = os.path.join(os.path.dirname(run), "empty")
    os.makedirs(os.path.join(empty, "checkpoints"))
    with pytest.raises(CorruptFileError, match="no checkpoint found"):
        load_checkpoint(empty, with_buffer=False)


def test_resume_refuses_other_settings_unless_overridden(run, capsys):
    config_yaml = os.path.join(run, "config.yaml")
    before = open(config_yaml).read()
    capsys.readouterr()
    for extra, want in [(["--seed", "7"], "seed: 0 -> 7"),
                        (["--set", "td3.tau=0.01"], "td3.tau: 0.005 -> 0.01"),
                        (["--set", "env.kwargs={obs_dim: 3}"],
                         "env.kwargs.obs_dim: (not set) -> 3"),
                        (["--set", "demos.episodes=1"], "demos.episodes: 0 -> 1")]:
        assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "300", *extra]) == 2
        err = capsys.readouterr().err
        assert want in err and "--override-config" in err and "step-000000000200" in err, err
        assert open(config_yaml).read() == before  # refused before anything is written
        assert load_checkpoint(run, with_buffer=False)["state"]["step"] == 200
    # The same through the Python API.
    cfg = load_checkpoint(run, with_buffer=False)["state"]["config"]
    with pytest.raises(ValueError, match=r"seed: 0 -> 3.*override_config=True"):
        Trainer(C.merge(cfg, {"seed": 3}), run, resume=True, log=lambda *a: None)
    assert open(config_yaml).read() == before
    # Length, logging and checkpoints kept may change without it.
    from ernest_cpp.rl.checkpoints import config_changes

    assert config_changes(cfg, C.merge(cfg, {"total_steps": 9, "checkpoint": {"keep": 1},
                                             "log": {"progress_bar": True, "every_steps": 7},
                                             "ray": {"address": "auto"},
                                             "consolidate": {"lr": 0.1}})) == []
    # A preset setting newer than the run counts with its preset value, saved or not.
    older = copy.deepcopy(cfg)
    del older["env"]["autoreset"], older["demos"]
    assert config_changes(older, cfg) == [] and config_changes(older, older) == []
    assert config_changes(older, C.merge(cfg, {"env": {"autoreset": "next"}})) == \
        ['env.autoreset: "same" -> "next"']
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "300", "--set",
                     "log.progress_bar=false", "--set", "checkpoint.keep=2", "--set",
                     "log.every_steps=100"]) == 0
    saved = yaml.safe_load(open(config_yaml))
    assert saved["seed"] == 0 and saved["total_steps"] == 300 and saved["checkpoint"]["keep"] == 2
    # --override-config continues with the new settings and records them.
    capsys.readouterr()
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "400", "--seed", "7",
                     "--override-config"]) == 0
    assert "changed settings (--override-config): seed: 0 -> 7" in capsys.readouterr().out
    assert yaml.safe_load(open(config_yaml))["seed"] == 7
    ck = load_checkpoint(run, with_buffer=False)
    assert ck["state"]["step"] == 400 and ck["state"]["config"]["seed"] == 7
    assert cli.main(["train", "--env", POINT_MASS, "--run-dir", run + "-new",
                     "--override-config"]) == 2
    assert "--override-config applies to --resume only" in capsys.readouterr().err


def test_override_config_is_in_the_help(capsys):
    with pytest.raises(SystemExit):
        cli.main(["train", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--override-config" in out and "another --seed" in out and "LATEST is missing" in out


def test_pipeline_resume_call_keeps_working_and_refuses_changed_settings(tmp_path):
    """``ernest train-default`` resumes a specialist with the same --scenario, --set lines and
    --set log.progress_bar=false it started it with, and a larger --steps: accepted. Changing a
    specialist's settings in the pipeline file between runs is refused, naming them in its log."""
    tiny = ["td3.hidden=16", "random_steps=10", "learning_starts=10", "eval.every_steps=0",
            "checkpoint.every_steps=10", "log.tensorboard=false", "env.num_envs=1",
            "env.kwargs={episode_length: 5.0}"]
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "out": str(tmp_path / "runs"), "policy": str(tmp_path / "policy.pt"), "parallel": 1,
        "specialists": {"step": {"scenario": "step", "steps": 10, "set": tiny}}}))
    cfg = P.load_pipeline(str(path))
    P.run_pipeline(cfg, stages=("specialists",), log=lambda s: None)
    run_dir = os.path.join(cfg["out"], "step")
    assert P._checkpoint_step(run_dir) == 10
    cfg["specialists"]["step"]["steps"] = 20
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists",), log=lines.append)
    assert any("resuming at 10" in ln for ln in lines)
    assert P._checkpoint_step(run_dir) == 20
    cfg["specialists"]["step"]["steps"] = 30
    cfg["specialists"]["step"]["set"] = tiny + ["td3.hidden=32"]
    with pytest.raises(RuntimeError, match="exit code 2"):
        P.run_pipeline(cfg, stages=("specialists",), log=lambda s: None)
    assert "td3.hidden: 16 -> 32" in open(run_dir + ".log").read()
    assert P._checkpoint_step(run_dir) == 20


def _rechecksum(store: str, rel: str) -> None:
    """Update ``store``'s manifest for its file ``rel`` (as if the damage had been stored)."""
    mpath = os.path.join(store, "manifest.json")
    man = json.load(open(mpath))
    p = os.path.join(store, rel)
    man["files"][rel] = {"bytes": os.path.getsize(p), "sha256": sha256_file(p)}
    json.dump(man, open(mpath, "w"))


@pytest.mark.parametrize("field, index, value", [("rew", (17,), np.nan), ("obs", (3, 1), np.inf),
                                                 ("act", (0, 0), -np.inf),
                                                 ("next_obs", (99, 2), np.nan)])
def test_replay_buffer_with_non_finite_values_is_refused(tmp_path, field, index, value):
    rng = np.random.default_rng(0)
    buf = ReplayBuffer(100, 4, 2)
    buf.add(rng.normal(size=(100, 4)), rng.uniform(-1, 1, (100, 2)), rng.normal(size=100),
            rng.normal(size=(100, 4)), np.zeros(100))
    path = str(tmp_path / "b")
    buf.save(path, chunk_rows=40)
    chunk = index[0] // 40
    rel = os.path.join(field, f"{chunk:06d}.npy")
    arr = np.load(os.path.join(path, rel))
    arr[(index[0] - 40 * chunk,) + index[1:]] = value
    np.save(os.path.join(path, rel), arr)
    _rechecksum(path, rel)
    for verify in (True, False):
        with pytest.raises(CorruptFileError, match=rf"{rel}: non-finite {field} value .* at stored "
                                                    rf"row {index[0]}"):
            ReplayBuffer.load(path, verify=verify)


def test_resume_refuses_a_checkpoint_whose_buffer_holds_nan_rewards(run, capsys):
    ck = os.path.join(_ck_root(run), "step-000000000200")
    rel = os.path.join("buffer", "rew", "000000.npy")
    arr = np.load(os.path.join(ck, rel))
    arr[5] = np.nan
    np.save(os.path.join(ck, rel), arr)
    _rechecksum(os.path.join(ck, "buffer"), os.path.relpath(rel, "buffer"))
    _rechecksum(ck, rel)
    _rechecksum(ck, os.path.join("buffer", "manifest.json"))
    with pytest.raises(CorruptFileError, match="non-finite rew value nan at stored row 5"):
        load_checkpoint(run)
    capsys.readouterr()
    assert cli.main(["train", "--run-dir", run, "--resume", "--steps", "300"]) == 2
    err = capsys.readouterr().err
    assert os.path.join(ck, rel) in err and "non-finite rew" in err, err
