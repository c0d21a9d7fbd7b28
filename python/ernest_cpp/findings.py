"""Seed 000 §6's qualitative findings (Figs 8–11) checked against our per-configuration summary.

``paper_findings(summary)`` takes the list of dicts that ``opt.summarise`` returns (keys used:
configuration, strategy, duration_s, heading_deviation_deg, max_acc_steering, max_acc_roll,
cost_of_transport, energy_wheels_J, energy_articulation_J, distance_m) and returns one dict per
statement of the paper's text: figure, statement, paper, ours, holds (computed from the numbers)
and reason (empty when it holds; otherwise what the numbers show).

Definitions (see transitions.py): Fig. 9 is "heading deviation caused by transition" — our
``heading_deviation_deg``, the heading reached minus the heading eq 7 says g2 would have reached
from G1(t1) over the same window. The raw before/after heading change of §4 also contains the
gaits' own yaw over the window, which grows with the transition's duration, so it ranks
configurations by duration rather than by what the transition caused. Accelerations (Fig. 10) are
the mean of the steering and bogie (roll) maxima. Strategy values are means over its weight sets.
"""

from __future__ import annotations

STRATEGIES = ("bezier", "linear", "spline", "naive")
REQUIRED = ("configuration", "strategy", "duration_s", "heading_deviation_deg", "max_acc_steering",
            "max_acc_roll", "cost_of_transport", "energy_wheels_J", "energy_articulation_J",
            "distance_m")


def _check(summary: list[dict]) -> None:
    if not isinstance(summary, (list, tuple)) or not summary:
        raise ValueError("summary must be a non-empty list of per-configuration dicts")
    for i, row in enumerate(summary):
        missing = [k for k in REQUIRED if k not in row]
        if missing:
            raise ValueError(f"summary[{i}] lacks {missing}")
    present = {r["strategy"] for r in summary}
    if not set(STRATEGIES) <= present:
        raise ValueError(f"summary must cover the strategies {STRATEGIES}, got {sorted(present)}")


def _acc(r: dict) -> float:
    return 0.5 * (r["max_acc_steering"] + r["max_acc_roll"])


def paper_findings(summary: list[dict]) -> list[dict]:
    """One dict per qualitative statement of seed 000 §6 (see the module docstring)."""
    _check(summary)
    by = {s: [r for r in summary if r["strategy"] == s] for s in STRATEGIES}

    def mean(strategy: str, key) -> float:
        rows = by[strategy]
        get = key if callable(key) else (lambda r: r[key])
        return sum(get(r) for r in rows) / len(rows)

    def ranking(key, fmt: str = "{:.3g}") -> str:
        vals = sorted(((mean(s, key), s) for s in STRATEGIES))
        return " < ".join(f"{s} {fmt.format(v)}" for v, s in vals)

    T = {s: mean(s, "duration_s") for s in STRATEGIES}
    H = {s: mean(s, "heading_deviation_deg") for s in STRATEGIES}
    A = {s: mean(s, _acc) for s in STRATEGIES}
    C = {s: mean(s, "cost_of_transport") for s in STRATEGIES}
    naive = by["naive"][0]
    bez_T_max = max(r["duration_s"] for r in by["bezier"])
    others_H = max((r for r in summary if r["strategy"] != "naive"),
                   key=lambda r: r["heading_deviation_deg"])

    def energy_split(s: str) -> str:
        return (f"{s}: wheels {mean(s, 'energy_wheels_J'):.3g} J + articulation "
                f"{mean(s, 'energy_articulation_J'):.3g} J over {mean(s, 'distance_m'):.3g} m")

    out = []

    def add(fig, statement, paper, ours, holds, reason):
        out.append({"figure": fig, "statement": statement, "paper": paper, "ours": ours,
                    "holds": bool(holds), "reason": "" if holds else reason})

    add("Fig. 8", "Naive has a long duration (longer than every Bezier configuration)",
        "Naive long; Bezier short", f"naive {naive['duration_s']:.3g} s vs longest Bezier "
        f"{bez_T_max:.3g} s", naive["duration_s"] > bez_T_max,
        "the Naive trapezoid (at the joint velocity/acceleration limits) is faster than "
        "the slowest Bezier weight set")
    add("Fig. 9", "Naive has the highest heading deviation of all configurations",
        "Naive highest", f"naive {naive['heading_deviation_deg']:.3g}° vs highest other "
        f"{others_H['configuration']} {others_H['heading_deviation_deg']:.3g}°",
        naive["heading_deviation_deg"] > others_H["heading_deviation_deg"],
        "the Naive reset to g2(0) deviates less than that optimised configuration")
    add("Fig. 11", "Naive has an extremely low cost of transport (below Linear and Spline)",
        "Naive low (long transitions cover ground)", ranking("cost_of_transport"),
        C["naive"] < min(C["linear"], C["spline"]),
        f"Naive's trapezoid runs the joints at their velocity limit, so its articulation energy "
        f"grows faster than its distance ({energy_split('naive')}; {energy_split('spline')})")
    add("Fig. 8", "Bezier has the shortest transitions", "Bezier shortest",
        ranking("duration_s", "{:.3g} s"), T["bezier"] == min(T.values()),
        f"{min(T, key=T.get)} is shorter on average")
    add("Fig. 9", "Bezier has an average heading deviation (neither best nor worst)",
        "Bezier average", ranking("heading_deviation_deg", "{:.3g}°"),
        min(H.values()) < H["bezier"] < max(H.values()),
        f"Bezier (2 variables) converges to the lowest deviation ({H['bezier']:.2g}°); Linear and "
        f"Spline (198 variables) stop at the 0.5 s limit before reaching as low")
    add("Fig. 10", "Bezier has lower joint accelerations than the waypoint strategies",
        "Bezier low; Linear and Spline high", ranking(_acc, "{:.3g} rad/s²"),
        A["bezier"] < min(A["linear"], A["spline"]),
        f"our waypoints are joined by a C1 cubic spline whose eq 8 acceleration term is "
        f"integrated exactly (no jumps between waypoints), and Bezier's shorter T "
        f"({T['bezier']:.3g} s vs {T['linear']:.3g} s) needs larger accelerations")
    add("Fig. 8", "Linear transitions are longer than Bezier's", "Linear high duration",
        f"linear {T['linear']:.3g} s vs bezier {T['bezier']:.3g} s", T["linear"] > T["bezier"],
        "Linear converges to shorter transitions than Bezier here")
    add("Fig. 9", "Linear improves the heading over Naive (by about 2°)",
        "Linear below Naive by ≈ 2°", f"naive − linear = {H['naive'] - H['linear']:.3g}°",
        H["linear"] < H["naive"], "Linear deviates more than the Naive reset")
    add("Fig. 10", "Spline performs poorly in joint acceleration (highest of the optimised)",
        "Spline highest", ranking(_acc, "{:.3g} rad/s²"),
        A["spline"] >= max(A["bezier"], A["linear"]),
        f"with the same C1 interpolation and acceleration cost Spline and Linear differ only by "
        f"eq 19's term (Δ {A['spline'] - A['linear']:+.2g} rad/s²); both stay below Bezier")
    add("Fig. 11", "Bezier has the lowest cost of transport of all strategies", "Bezier lowest",
        ranking("cost_of_transport"), C["bezier"] == min(C.values()),
        f"in our energy model the wheels' energy is proportional to distance, so CoT differs by "
        f"articulation energy per metre ({energy_split('bezier')}; "
        f"{energy_split(min(C, key=C.get))})")
    return out


def findings_markdown(findings: list[dict]) -> str:
    lines = [f"Seed 000 §6 findings: {sum(f['holds'] for f in findings)} of {len(findings)} hold.",
             "", "| figure | paper's statement | paper | ours | holds | reason (measured) |",
             "|---|---|---|---|---|---|"]
    for f in findings:
        cells = [f["figure"], f["statement"], f["paper"], f["ours"],
                 "yes" if f["holds"] else "no", f["reason"]]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines)
