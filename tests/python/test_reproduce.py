"""``ernest reproduce``: findings are computed from the numbers (flip the numbers, the finding
flips), reasons come from ``REASONS`` or a placeholder, and a cheap end-to-end run writes the
report."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ernest_cpp import reproduce as R
from ernest_cpp.cli import main as cli_main


def _by_id(rows):
    return {r["id"]: r for r in rows}


def test_table6_findings_hold_on_the_papers_numbers_and_flip_with_them():
    rows = _by_id(R.table6_findings(R.PAPER_TABLE6_WITH_GAIT))
    assert rows and all(r["holds"] is True for r in rows.values())
    flipped = dict(R.PAPER_TABLE6_WITH_GAIT)
    flipped[("dry", R.PASSIVE)], flipped[("dry", R.LEARNED)] = (
        R.PAPER_TABLE6[("dry", R.LEARNED)], R.PAPER_TABLE6[("dry", R.PASSIVE)])
    rows = _by_id(R.table6_findings(flipped))
    assert rows["004.t6.dry.tr.learned"]["holds"] is False
    assert rows["004.t6.dry.cot.learned"]["holds"] is False
    assert rows["004.t6.wet.tr.learned"]["holds"] is True
    wet = dict(R.PAPER_TABLE6_WITH_GAIT)
    wet[("wet", R.PASSIVE)] = {"tr": 45.0, "cot": 10.0}  # a passive rover that climbs wet sand
    rows = _by_id(R.table6_findings(wet))
    assert rows["004.t6.wet.passive_immobilised"]["holds"] is False
    assert rows["004.t6.wet.cot.learned"]["holds"] is False  # 12.8 > 10
    assert rows["004.t6.gap_tr"]["holds"] is False  # 15 pp on wet < 38.9 on dry
    # the crawling-gait rows read the crawling gait's numbers
    slow = dict(R.PAPER_TABLE6_WITH_GAIT)
    slow[("dry", R.CRAWLING)] = {"tr": 90.0, "cot": 30.0}
    rows = _by_id(R.table6_findings(slow))
    assert rows["004.t6.dry.tr.crawling"]["holds"] is False
    assert rows["004.t6.dry.tr.learned"]["holds"] is True
    # without a learned policy its findings are not applicable, not failed
    rows = _by_id(R.table6_findings({k: v for k, v in R.PAPER_TABLE6_WITH_GAIT.items()
                                     if k[1] != R.LEARNED}))
    assert rows["004.t6.dry.tr.learned"]["holds"] is None
    assert rows["004.t6.dry.tr.crawling"]["holds"] is True


def test_cot_is_compared_as_energy_per_mass_and_distance():
    # our cost_of_transport is E / (m g d); Table 6 normalises by mass and distance only
    assert R.cot_paper_units(1.0) == pytest.approx(9.81)
    assert R.cot_paper_units(math.inf) == math.inf


def test_obstacle_findings_follow_the_outcome():
    res = {("bickler", R.PASSIVE): {"crossed": False, "wheels_over": [2], "progress": 1.0,
                                    "front_back": [0]},
           ("bickler", R.LEARNED): {"crossed": True, "wheels_over": [4], "progress": 9.0},
           ("step", R.LEARNED): {"crossed": True, "wheels_over": [4], "progress": 3.0},
           ("step", R.PASSIVE): {"crossed": False, "wheels_over": [0], "progress": 0.8}}
    rows = _by_id(R.obstacle_findings(res))
    assert rows["004.s5.bickler.passive"]["holds"] is True
    assert rows["004.s5.bickler.passive_straddles"]["holds"] is True  # 2 wheels over
    assert rows["004.s5.bickler.passive_reverse"]["holds"] is True  # and cannot reverse out
    assert rows["004.s5.bickler.learned"]["holds"] is True
    assert rows["004.s5.step.passive"]["holds"] is None  # the paper does not report it
    res[("bickler", R.PASSIVE)] = {"crossed": True, "wheels_over": [4], "progress": 9.0}
    res[("step", R.LEARNED)] = {"crossed": False, "wheels_over": [2], "progress": 1.0}
    rows = _by_id(R.obstacle_findings(res))
    assert rows["004.s5.bickler.passive"]["holds"] is False
    assert rows["004.s5.bickler.passive_straddles"]["holds"] is False
    assert "004.s5.bickler.passive_reverse" not in rows  # no reverse test run
    for over, back in (([2, 2, 0], [0, 2, 2]), ([0], [0])):  # reversed out / never straddled
        res[("bickler", R.PASSIVE)] = {"crossed": False, "wheels_over": over, "progress": 1.0,
                                       "front_back": back}
        assert _by_id(R.obstacle_findings(res))["004.s5.bickler.passive_reverse"]["holds"] is False
    assert rows["004.s5.step.learned"]["holds"] is False


def test_rig_findings_follow_the_curves():
    s = np.linspace(0.0, 0.9, 19)
    rising = 0.5 * (1.0 - np.exp(-s / 0.15)) - 0.1  # rises and levels off at 0.4

    def rig(m90, wet, dry=rising):
        return {"dry_sand": {"slip": s, "dpw": dry}, "m90": {"slip": s, "dpw": m90},
                "wet_sand": {"slip": s, "dpw": wet}}

    rows = _by_id(R.rig_findings(rig(rising + 0.05, 0.6 * rising)))
    assert rows["004.rig.m90.rises"]["holds"] and rows["004.rig.m90.saturates"]["holds"]
    assert rows["004.rig.m90_slope"]["holds"] is True  # peak 0.45 >= tan 20
    assert rows["004.rig.wet_slope"]["holds"] is True  # peak 0.24 < tan 20
    assert rows["004.rig.m90_vs_dry"]["holds"] is True
    rows = _by_id(R.rig_findings(rig(0.3 - 0.3 * s, 1.2 * rising, dry=0.5 * s)))
    assert rows["004.rig.m90.rises"]["holds"] is False  # falls with slip
    assert rows["004.rig.dry_sand.saturates"]["holds"] is False  # still rising linearly
    assert rows["004.rig.m90_slope"]["holds"] is False
    assert rows["004.rig.wet_slope"]["holds"] is False  # peak 0.48: wet sand too strong


def _summary(values):
    out = []
    for strategy, (dur, head, acc, cot) in values.items():
        out.append({"configuration": strategy, "strategy": strategy, "duration_s": dur,
                    "heading_change_deg": head, "max_acc_steering": acc, "max_acc_roll": acc,
                    "cost_of_transport": cot})
    return out


def test_transition_findings_hold_when_the_numbers_say_so():
    paper_like = {"naive": (2.0, 5.0, 3.0, 0.05), "bezier": (0.5, 4.0, 1.0, 0.04),
                  "linear": (1.5, 3.0, 6.0, 0.08), "spline": (1.6, 4.0, 9.0, 0.09)}
    rows = R.transition_findings(_summary(paper_like))
    assert len(rows) == 9 and all(r["holds"] for r in rows)
    assert {"figure", "statement", "paper", "ours", "holds", "reason"} <= set(rows[0])
    reversed_ = {"naive": (0.4, 1.0, 3.0, 0.20), "bezier": (0.8, 1.5, 1.3, 0.14),
                 "linear": (1.1, 2.1, 0.8, 0.137), "spline": (1.1, 2.1, 0.8, 0.137)}
    rows = _by_id(R.transition_findings(_summary(reversed_)))
    assert rows["000.naive_most_heading"]["holds"] is False
    assert rows["000.bezier_low_acc"]["holds"] is False
    assert rows["000.naive_low_cot"]["holds"] is False


def test_reasons_fill_only_rows_that_do_not_hold(monkeypatch):
    rows = [{"id": "x.holds", "statement": "s", "paper": "p", "ours": "o", "holds": True},
            {"id": "x.fails", "statement": "s", "paper": "p", "ours": "o", "holds": np.False_},
            {"id": "x.na", "statement": "s", "paper": "p", "ours": "o", "holds": None}]
    text = "\n".join(R.findings_table(rows))
    assert "reproduce.REASONS['x.fails']" in text and "x.holds']" not in text
    monkeypatch.setitem(R.REASONS, "x.fails", "measured: the wheel chatters at the step rate")
    monkeypatch.setitem(R.REASONS, "x.holds", "never shown")
    text = "\n".join(R.findings_table(rows))
    assert "measured: the wheel chatters" in text and "never shown" not in text
    assert "| **no** |" in text and "| n/a |" in text


def test_reproduce_command_writes_the_report_cheaply(tmp_path, capsys, monkeypatch):
    from ernest_cpp import transitions

    # the other branch's transitions.paper_findings is used when present
    monkeypatch.setattr(transitions, "paper_findings", lambda summary: [
        {"figure": "Fig. 9", "statement": "stub statement", "paper": "p", "ours": "o",
         "holds": False, "reason": "stub reason"}], raising=False)
    out = tmp_path / "rep"
    assert cli_main(["reproduce", "--out", str(out), "--quick", "--episode-length", "2",
                     "--seeds", "1", "--max-time", "0.02", "--rig-points", "10",
                     "--policy", ""]) == 0
    text = (out / "report.md").read_text()
    for heading in ("## 1. Seed 004 Table 6", "## 2. Seed 004 §5.2", "## 3. Seed 004 §3.3",
                    "## 4. Seed 000"):
        assert heading in text
    assert "| dry (m90) | passive bogie | 81.9 |" in text
    assert "| wet (wet_sand) | learned policy | 30.0 | not run |" in text
    assert "stub statement" in text and "stub reason" in text
    for name in ("table6.png", "rig.png", "fig8_duration.png", "fig19_20_step_climb.png"):
        assert (out / name).stat().st_size > 1000
    assert not list(out.glob("*.tmp*"))
    log = capsys.readouterr().out
    assert "[4/4]" in log and "seed 0:" in log and "wrote" in log
    assert cli_main(["reproduce", "--out", str(out), "--sections", "moon"]) == 2
