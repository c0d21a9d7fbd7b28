"""``ernest train-default`` (rl.pipeline) on a tiny pipeline: specialists in parallel processes,
consolidation, export with checksum, report; a second run resumes (skips what is done)."""

from __future__ import annotations

import json
import os

import pytest
import yaml

from ernest_cpp.rl import pipeline as P
from ernest_cpp.rl.export import load_policy

TINY = ["td3.hidden=16", "random_steps=20", "learning_starts=20", "eval.every_steps=20",
        "eval.episodes=1", "checkpoint.every_steps=20", "log.tensorboard=false",
        "log.every_steps=10", "env.num_envs=1", "env.kwargs={episode_length: 5.0}"]


def _pipeline(tmp_path, **over) -> str:
    cfg = {"out": str(tmp_path / "runs"), "policy": str(tmp_path / "policy.pt"), "parallel": 2,
           "progress_every": 1,
           "specialists": {"step": {"scenario": "step", "steps": 40, "set": TINY},
                           "slope": {"scenario": "slope", "steps": 40, "set": TINY}},
           "consolidate": {"set": ["consolidate.iterations=20", "consolidate.hidden=16",
                                   "consolidate.eval_episodes=1",
                                   "consolidate.batch_size=16"]}}
    cfg.update(over)
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return str(path)


def test_pipeline_trains_consolidates_exports_and_resumes(tmp_path):
    cfg = P.load_pipeline(_pipeline(tmp_path))
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists", "consolidate", "export", "report"),
                   log=lines.append)
    out = cfg["out"]
    for name in ("step", "slope"):
        assert P._checkpoint_step(os.path.join(out, name)) == 40
        with open(os.path.join(out, name, "progress.json")) as fh:
            prog = json.load(fh)
        assert prog["step"] == 40 and prog["transitions_per_s"] > 0 and prog["updates_per_s"] > 0
        rows = open(os.path.join(out, name, "eval.csv")).read().splitlines()
        assert "elapsed_s" in rows[0].split(",") and len(rows) == 3  # evaluations at 20 and 40
    assert any("transitions/s" in ln for ln in lines)  # progress lines while they ran
    module, meta = load_policy(cfg["policy"])  # exported, checksummed, loadable
    assert meta["obs_dim"] == 45 and meta["act_dim"] == 3
    report = open(os.path.join(out, "training.md")).read()
    assert "Specialist step" in report and "Consolidated policy against every specialist" in report
    assert os.path.exists(os.path.join(out, "curves.png"))
    # Run again: every stage that is complete is skipped.
    again: list[str] = []
    P.run_pipeline(cfg, stages=("specialists", "consolidate"), log=again.append)
    assert "specialist step: done (40 transitions)" in again
    assert "[2/5] consolidate: done" in again


def test_pipeline_resumes_an_interrupted_specialist(tmp_path):
    cfg = P.load_pipeline(_pipeline(tmp_path))
    cfg["specialists"] = {"step": cfg["specialists"]["step"]}
    cfg["specialists"]["step"]["steps"] = 20
    P.run_pipeline(cfg, stages=("specialists",), log=lambda s: None)
    cfg["specialists"]["step"]["steps"] = 40  # as if it had been stopped after 20
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists",), log=lines.append)
    assert any("resuming at 20" in ln for ln in lines)
    assert P._checkpoint_step(os.path.join(cfg["out"], "step")) == 40


@pytest.mark.parametrize("over, match", [
    ({"parallel": 0}, "parallel"), ({"colour": "red"}, "unknown key"),
    ({"specialists": {}}, "specialists"),
    ({"specialists": {"x": {"scenario": "step"}}}, "scenario and steps"),
    ({"specialists": {"x": {"scenario": "step", "steps": 0}}}, "steps"),
    ({"specialists": {"x": {"scenario": "step", "steps": 5, "lr": 1}}}, "unknown key")])
def test_bad_pipeline_files_are_refused(tmp_path, over, match):
    with pytest.raises(ValueError, match=match):
        P.load_pipeline(_pipeline(tmp_path, **over))


def test_the_committed_pipeline_file_is_valid():
    here = os.path.dirname(__file__)
    cfg = P.load_pipeline(os.path.join(here, "..", "..", "policies", "default.yaml"))
    assert set(cfg["specialists"]) >= {"step", "slope", "rockfield", "ripples"}
