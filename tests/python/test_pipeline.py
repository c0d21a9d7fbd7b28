"""``ernest train-default`` (rl.pipeline) on a tiny pipeline: specialists in parallel processes,
consolidation, export with checksum, report; a second run resumes (skips what is done)."""

from __future__ import annotations

import csv
import json
import os

import pytest
import yaml

from ernest_cpp._csv import bare
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
        assert "elapsed_s [s]" in rows[0].split(",") and len(rows) == 3  # evaluations at 20 and 40
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
    assert "  consolidation seed 0: done" in again


def _selection_rows(path: str) -> list[dict]:
    """selection.csv's rows keyed by the bare column names; every header names its unit."""
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        head = reader.fieldnames
        assert all(h.endswith("]") and " [" in h for h in head), head
        assert "candidate [-]" in head and "slope 18 m90 lateral [m]" in head, head
        return [{bare(k): v for k, v in r.items()} for r in reader]


def test_pipeline_selects_among_kept_agents_on_validation_episodes(tmp_path):
    cons = {"seeds": [0, 3], "set": ["consolidate.iterations=20", "consolidate.hidden=16",
                                      "consolidate.eval_episodes=1", "consolidate.batch_size=16",
                                      "consolidate.keep_every=10", "consolidate.keep_from=10"]}
    cfg = P.load_pipeline(_pipeline(tmp_path, consolidate=cons,
                                    select={"seeds": [10, 12], "slopes_deg": [18]}))
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists", "consolidate", "select", "export", "report"),
                   log=lines.append)
    out = cfg["out"]
    kept = {os.path.join(d, "checkpoints", n) for d in ("consolidated", "consolidated-s3")
            for n in ("iteration-00000010", "consolidated")}
    rows = _selection_rows(os.path.join(out, "selection.csv"))
    assert {r["candidate"] for r in rows[:-1]} == kept and rows[-1]["candidate"].startswith("crawl")
    crawl = rows[-1]
    for r in rows[:-1]:  # targets met on the validation episodes, as selection documents them
        slopes = ["slope 18 m90", "slope 18 wet_sand"]
        below = all(float(r[f"{k} TR"]) < float(crawl[f"{k} TR"]) for k in slopes)
        tracked = all(float(r[f"{k} lateral"]) <= 0.3 for k in slopes)
        step, trap = float(r["step crossed"]), float(r["trap crossed"])
        assert int(r["targets met"]) == (step >= 0.8) + (trap >= 0.8) + below + tracked
        assert float(r["crossings"]) == pytest.approx(step + trap)
    best = max(rows[:-1], key=lambda r: (int(r["targets met"]), float(r["crossings"]),
                                         -float(r["slope TR mean"])))
    chosen = json.load(open(os.path.join(out, "selected.json")))["checkpoint"]
    assert chosen == os.path.join(out, best["candidate"])
    assert any("[4/6] export " + chosen in ln for ln in lines)
    load_policy(cfg["policy"])
    report = open(os.path.join(out, "training.md")).read()
    assert "Consolidated policy against every specialist" in report  # the chosen agent's table
    assert "Choosing the policy on validation episodes" in report
    assert f"| {best['candidate']} | {best['targets met']} |" in report  # first row: the policy
    again: list[str] = []
    P.run_pipeline(cfg, stages=("consolidate", "select"), log=again.append)
    assert "  consolidation seed 3: done" in again and "[3/6] select: done" in again
    # Choosing again (more seeds, or after a kill) reuses each candidate's saved results; a
    # corrupt results file is evaluated again, to the same figures.
    first = open(os.path.join(out, "selection.csv")).read()
    broken = os.path.join(out, "consolidated", "checkpoints", "iteration-00000010", "validation.json")
    with open(broken, "w") as fh:
        fh.write("{not json")
    os.remove(os.path.join(out, "selected.json"))
    third: list[str] = []
    P.run_pipeline(cfg, stages=("select",), log=third.append)
    saved = [ln for ln in third if "(saved results)" in ln]
    assert len(saved) == len(kept) - 1 and not any("consolidated/checkpoints/iteration-00000010"
                                                   in ln for ln in saved)
    assert open(os.path.join(out, "selection.csv")).read() == first
    assert json.load(open(broken))["results"]["step"]["crossed"] is not None


def test_pipeline_refines_the_chosen_agent_and_chooses_again(tmp_path):
    cons = {"seeds": [0], "set": ["consolidate.iterations=20", "consolidate.hidden=16",
                                  "consolidate.eval_episodes=1", "consolidate.batch_size=16"]}
    refine = {"set": ["consolidate.w_delta=1.0", "consolidate.lr=1e-4",
                      "consolidate.iterations=20", "consolidate.keep_every=10",
                      "consolidate.keep_from=10"]}
    cfg = P.load_pipeline(_pipeline(tmp_path, consolidate=cons, refine=refine,
                                    select={"seeds": [10, 11], "slopes_deg": [18]}))
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists", "consolidate", "select", "export"),
                   log=lines.append)
    out = cfg["out"]
    first = json.load(open(os.path.join(out, "selected.json")))["checkpoint"]
    assert first == os.path.join(out, "consolidated", "checkpoints", "consolidated")
    log = open(os.path.join(out, "refined.log")).read()
    assert f"continuing {first}" in log and "rewards relabelled to w_delta = 1" in log
    rows = _selection_rows(os.path.join(out, "refined", "selection.csv"))
    assert [r["candidate"] for r in rows[:-1]] == [
        os.path.join("..", "consolidated", "checkpoints", "consolidated"),  # the first choice
        os.path.join("checkpoints", "iteration-00000010"), os.path.join("checkpoints", "consolidated")]
    best = max(rows[:-1], key=lambda r: (int(r["targets met"]), float(r["crossings"]),
                                         -float(r["slope TR mean"])))
    chosen = json.load(open(os.path.join(out, "refined", "selected.json")))["checkpoint"]
    assert chosen == os.path.normpath(os.path.join(out, "refined", best["candidate"]))
    assert any("[4/6] export " + chosen in ln for ln in lines)
    again: list[str] = []
    P.run_pipeline(cfg, stages=("select",), log=again.append)
    assert "[3/6] select: done" in again and "      refine: done" in again
    folder = tmp_path / "a-folder"
    folder.mkdir()
    with pytest.raises(RuntimeError, match="not a regular file"):  # never replaced by the policy
        P.run_pipeline({**cfg, "policy": str(folder)}, stages=("export",), log=lambda s: None)
    assert folder.is_dir()
    with pytest.raises(ValueError, match="refine needs a select section"):
        P.load_pipeline(_pipeline(tmp_path, refine=refine))
    with pytest.raises(ValueError, match="pipeline refine"):
        P.load_pipeline(_pipeline(tmp_path, refine={"sett": []}, select={}))
    with pytest.raises(ValueError, match="select.slope_spread_deg"):  # checked as select is
        P.load_pipeline(_pipeline(tmp_path, refine={"select": {"slope_spread_deg": -1}}, select={}))
    # refine.select replaces keys of select for the refined agents' choice only
    two = P.load_pipeline(_pipeline(tmp_path, refine={"select": {"slopes_deg": [20],
                                                                 "slope_seeds": [100, 102]}},
                                    select={"seeds": [10, 11]}))
    assert two["select"]["slopes_deg"] == [18.0, 22.0] and two["select"]["slope_seeds"] == [0, 1]
    assert two["refine"]["select"]["slopes_deg"] == [20]
    assert two["refine"]["select"]["seeds"] == [10, 11]


def test_pipeline_resumes_an_interrupted_specialist(tmp_path):
    cfg = P.load_pipeline(_pipeline(tmp_path))
    cfg["specialists"] = {"step": cfg["specialists"]["step"]}
    cfg["specialists"]["step"]["steps"] = 20
    P.run_pipeline(cfg, stages=("specialists",), log=lambda s: None)
    cfg["specialists"]["step"]["steps"] = 40  # as if it had been stopped after 20
    os.remove(os.path.join(cfg["out"], "step", "checkpoints", "LATEST"))  # lost: found without it
    lines: list[str] = []
    P.run_pipeline(cfg, stages=("specialists",), log=lines.append)
    assert any("resuming at 20" in ln for ln in lines)
    assert P._checkpoint_step(os.path.join(cfg["out"], "step")) == 40


@pytest.mark.parametrize("over, match", [
    ({"parallel": 0}, "parallel"), ({"colour": "red"}, "unknown key"),
    ({"specialists": {}}, "specialists"),
    ({"specialists": {"x": {"scenario": "step"}}}, "scenario and steps"),
    ({"specialists": {"x": {"scenario": "step", "steps": 0}}}, "steps"),
    ({"specialists": {"x": {"scenario": "step", "steps": 5, "lr": 1}}}, "unknown key"),
    ({"consolidate": {"seeds": [0, 0]}}, "consolidate.seeds"),
    ({"consolidate": {"seeds": []}}, "consolidate.seeds"),
    ({"consolidate": {"lr": 1}}, "unknown key"),
    ({"select": {"seeds": [0, 10]}}, "must not overlap the reported seeds"),
    ({"select": {"seeds": [20, 10]}}, "select.seeds"),
    ({"select": {"slopes_deg": [20]}}, "other than the reported 20"),
    ({"select": {"slopes_deg": [20], "slope_seeds": [5, 15]}}, "other than the reported 20"),
    ({"select": {"slope_seeds": [3, 3]}}, "select.slope_seeds"),
    ({"select": {"slope_spread_deg": -0.5}}, "slope_spread_deg"),
    ({"select": {"slope_spread_deg": float("nan")}}, "slope_spread_deg"),
    ({"select": {"max_lateral": 0}}, "max_lateral"),
    ({"select": {"workers": 0}}, "workers"),
    ({"select": {"min_crossed": 1.5}}, "min_crossed"),
    ({"select": {"colour": 1}}, "unknown key")])
def test_bad_pipeline_files_are_refused(tmp_path, over, match):
    with pytest.raises(ValueError, match=match):
        P.load_pipeline(_pipeline(tmp_path, **over))


def test_held_out_slope_seeds_may_validate_on_the_reported_angle_distribution():
    from ernest_cpp.rl.selection import check_select, validation_courses

    sel = check_select({"slopes_deg": [20], "slope_seeds": [100, 103], "slope_spread_deg": 0.5})
    slopes = [c for c in validation_courses(sel) if c[3] is None]
    assert [c[0] for c in slopes] == ["slope 20 m90", "slope 20 wet_sand"]
    for _, env_id, kwargs, _, seeds in slopes:
        assert env_id == "ernest/SlopeEval-v0" and seeds == [100, 101, 102]
        assert kwargs["randomisation"] == {"eval_slope_deg": 20.0, "eval_slope_spread_deg": 0.5}
    # the default keeps the fixed angle and one episode per slope
    default = [c for c in validation_courses(check_select({})) if c[3] is None]
    assert all(c[4] == [0] and "eval_slope_spread_deg" not in c[2]["randomisation"]
               for c in default)


def test_the_committed_pipeline_file_is_valid():
    here = os.path.dirname(__file__)
    cfg = P.load_pipeline(os.path.join(here, "..", "..", "policies", "default.yaml"))
    assert set(cfg["specialists"]) >= {"step", "slope", "rockfield", "ripples"}


@pytest.mark.parametrize("c, match", [
    ({"keep_every": -1}, "keep_every"), ({"keep_every": 1.5}, "keep_every"),
    ({"keep_from": 11}, "at most consolidate.iterations"), ({"keep_from": True}, "keep_from")])
def test_bad_keep_settings_are_refused(c, match):
    from ernest_cpp.rl.consolidate import keep_settings

    with pytest.raises(ValueError, match=match):
        keep_settings({"iterations": 10, **c})
    assert keep_settings({"iterations": 10, "keep_every": 5, "keep_from": 5}) == (5, 5)
