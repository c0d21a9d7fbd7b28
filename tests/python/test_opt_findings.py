"""Exact joint limits of the transitions and the seed 000 §6 findings check
(``transitions.paper_findings``)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from ernest_cpp import opt as O
from ernest_cpp.transitions import paper_findings


@pytest.mark.parametrize("weights", O.WEIGHT_SETS)
@pytest.mark.parametrize("direction", O.DIRECTIONS)
def test_bezier_never_exceeds_the_limits_between_samples(weights, direction):
    period = O.asterix_problem(0.0, direction).from_gait.period
    for k in range(40):
        pb = O.asterix_problem(period * k / 40, direction)
        r = O.plan(pb, "bezier", weights)
        assert not r.fell_back, r.fallback_reason
        q, dq, _ = r.sample(np.linspace(0.0, r.duration, 2001))
        P, V = np.asarray(pb.position_limit), np.asarray(pb.velocity_limit)
        dense = max(np.max(np.abs(q) / P - 1), np.max(np.abs(dq) / V - 1))
        peak_q, peak_v = r.peaks()
        exact = max(np.max(peak_q / P - 1), np.max(peak_v / V - 1))
        assert dense <= 1e-9 and exact <= 1e-9
        assert r.max_violation == pytest.approx(exact, abs=1e-12)
        assert dense - 1e-12 <= r.max_violation <= dense + 1e-5


def test_limit_margin_is_validated_by_name():
    o = O.TransitionOptions()
    o.limit_margin = -1.0
    with pytest.raises(ValueError, match="limit_margin"):
        o.validate()


def _summary(**overrides):
    """A synthetic summary in which every one of the paper's statements holds."""
    base = {"bezier": dict(duration_s=0.5, heading_deviation_deg=1.0, max_acc_steering=0.5,
                           max_acc_roll=0.5, cost_of_transport=0.10),
            "linear": dict(duration_s=1.5, heading_deviation_deg=0.5, max_acc_steering=1.0,
                           max_acc_roll=1.0, cost_of_transport=0.20),
            "spline": dict(duration_s=1.5, heading_deviation_deg=0.6, max_acc_steering=2.0,
                           max_acc_roll=2.0, cost_of_transport=0.20),
            "naive": dict(duration_s=2.0, heading_deviation_deg=2.5, max_acc_steering=1.0,
                          max_acc_roll=1.0, cost_of_transport=0.15)}
    rows = []
    for strategy, values in base.items():
        for w in (O.WEIGHT_SETS if strategy != "naive" else ("",)):
            row = dict(values, configuration=f"{strategy}/{w}" if w else strategy,
                       strategy=strategy, energy_wheels_J=1.0, energy_articulation_J=0.5,
                       distance_m=0.05)
            row.update(overrides.get(row["configuration"], {}))
            rows.append(row)
    return rows


def test_paper_findings_follow_the_numbers():
    findings = paper_findings(_summary())
    assert len(findings) == 10
    for f in findings:
        assert set(f) == {"figure", "statement", "paper", "ours", "holds", "reason"}
        assert f["holds"] and f["reason"] == "", f
    # Flip the numbers: Naive becomes the quickest and the straightest, Bezier the costliest.
    flipped = _summary(naive={"duration_s": 0.1, "heading_deviation_deg": 0.1,
                              "cost_of_transport": 0.5},
                       **{f"bezier/{w}": {"cost_of_transport": 0.3, "max_acc_steering": 5.0,
                                          "max_acc_roll": 5.0} for w in O.WEIGHT_SETS})
    after = {f["statement"]: f for f in paper_findings(flipped)}
    for key in ("Naive has a long duration", "Naive has the highest heading",
                "Naive has an extremely low cost", "Bezier has the lowest cost",
                "Bezier has lower joint accelerations", "Spline performs poorly",
                "Linear improves the heading"):
        f = next(v for s, v in after.items() if s.startswith(key))
        assert not f["holds"] and f["reason"], f
    assert not next(v for s, v in after.items() if s.startswith("Bezier has the shortest"))["holds"]
    assert next(v for s, v in after.items() if s.startswith("Linear transitions are longer"))["holds"]


def test_paper_findings_rejects_bad_input():
    with pytest.raises(ValueError, match="summary"):
        paper_findings([])
    rows = _summary()
    del rows[0]["cost_of_transport"]
    with pytest.raises(ValueError, match="cost_of_transport"):
        paper_findings(rows)
    with pytest.raises(ValueError, match="strategies"):
        paper_findings([r for r in copy.deepcopy(_summary()) if r["strategy"] != "naive"])
