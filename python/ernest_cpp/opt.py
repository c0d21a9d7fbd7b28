"""Gait transitions for the multi-modal rover Asterix (seed 000): gaits (eq 1), wheel kinematics
(eqs 20–23, odeint), the Naive, Bezier, Linear and Spline strategies solved with NLopt SLSQP under
a time budget (eqs 2–19), and the metrics (eqs 24–28). The work is done in C++
(``ernest_cpp._core.opt``); this module re-exports it and adds the paper's experiment protocol.
"""

from __future__ import annotations

import math
import time
from typing import Callable, Iterable

import numpy as np

from ._core.opt import (  # noqa: F401  (re-exports)
    ROLL,
    STEERING,
    AsterixKinematics,
    AsterixParameters,
    CostWeights,
    Gait,
    IntegrationOptions,
    KinematicsError,
    MetricsOptions,
    Pose2,
    SolverOptions,
    SolverResult,
    Strategy,
    TransitionMetrics,
    TransitionOptions,
    TransitionProblem,
    TransitionResult,
    WeightSet,
    compose,
    evaluate_metrics,
    gait_pose,
    minimize_slsqp,
    naive_transition,
    nlopt_status_name,
    plan_transition,
    relative,
    squirming,
    strategy_from_string,
    strategy_name,
    transition_constraints,
    transition_cost,
    transition_dimension,
    wheel_walking,
    weight_set_from_string,
    weight_set_name,
)

#: Optimised strategies and Table 1's weight sets, in the paper's order.
OPTIMISED = ("bezier", "linear", "spline")
WEIGHT_SETS = ("duration", "deviation", "balanced")
#: The ten configurations of Figs 8–11: three weight sets per optimised strategy, plus Naive.
CONFIGURATIONS = tuple((s, w) for s in OPTIMISED for w in WEIGHT_SETS) + (("naive", ""),)
#: The two directions of the protocol (§5 "Experimental Protocol").
DIRECTIONS = ("squirming->wheel_walking", "wheel_walking->squirming")


def as_strategy(strategy: str | Strategy) -> Strategy:
    """A Strategy from itself or its name (naive, bezier, linear, spline; any case)."""
    if isinstance(strategy, Strategy):
        return strategy
    if not isinstance(strategy, str):
        raise ValueError(f"strategy = {strategy!r} must be a Strategy or one of the names "
                         f"naive, bezier, linear, spline")
    return strategy_from_string(strategy.lower())


def weights_for(strategy: str | Strategy, weights: str | CostWeights | None) -> CostWeights:
    """Table 1 weights by set name, or the given CostWeights (None: balanced)."""
    if isinstance(weights, CostWeights):
        return weights
    if weights is not None and not isinstance(weights, str):
        raise ValueError(f"weights = {weights!r} must be a CostWeights, a weight-set name or None")
    s = as_strategy(strategy)
    if s == Strategy.Naive:
        return CostWeights()
    return CostWeights.table1(s, weight_set_from_string((weights or "balanced").lower()))


def asterix_problem(t1: float, direction: str = DIRECTIONS[0],
                    rover: AsterixParameters | None = None) -> TransitionProblem:
    """Transition between squirming and wheel-walking at time t1 of the first gait."""
    rover = rover or AsterixParameters()
    gaits = {"squirming": squirming(rover), "wheel_walking": wheel_walking(rover)}
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    a, b = direction.split("->")
    # (TransitionProblem's own ValueError names t1 with its range: not caught here)
    return TransitionProblem(rover, gaits[a], gaits[b], float(t1))


def plan(problem: TransitionProblem, strategy: str | Strategy = "bezier",
         weights: str | CostWeights | None = None, max_time: float = 0.5,
         **options) -> TransitionResult:
    """Plan one transition; ``options`` set TransitionOptions fields (e.g. waypoints=100)."""
    opts = TransitionOptions()
    opts.solver.max_time = float(max_time)
    for key, value in options.items():
        if not hasattr(opts, key):
            raise ValueError(f"unknown transition option {key!r}")
        setattr(opts, key, value)
    return plan_transition(problem, as_strategy(strategy), weights_for(strategy, weights), opts)


def metrics_row(problem: TransitionProblem, result: TransitionResult,
                metrics: TransitionMetrics) -> dict:
    """Flat dict of one transition's metrics (CSV row)."""
    acc = np.asarray(metrics.max_acceleration, dtype=float)
    return {
        "strategy": strategy_name(result.requested),
        "used": strategy_name(result.strategy),
        "t1": problem.t1,
        "duration_s": metrics.duration,
        "phase_shift_s": result.phase_shift,
        "heading_change_deg": math.degrees(metrics.heading_change),
        "heading_deviation_deg": math.degrees(metrics.heading_deviation),
        "position_deviation_m": metrics.position_deviation,
        "distance_m": metrics.distance,
        "max_acc_steering": float(acc[STEERING]),
        "max_acc_roll": float(acc[ROLL]) if acc.size > 1 else 0.0,
        "energy_J": metrics.energy,
        "energy_wheels_J": metrics.energy_wheels,
        "energy_articulation_J": metrics.energy_articulation,
        "cost_of_transport": metrics.cost_of_transport,
        "res_start_pos": metrics.start_position_residual,
        "res_start_vel": metrics.start_velocity_residual,
        "res_end_pos": metrics.end_position_residual,
        "res_end_vel": metrics.end_velocity_residual,
        "cost": result.cost,
        "max_violation": result.max_violation,
        "solver_status": result.solver.status_name,
        "evaluations": result.solver.evaluations,
        "solve_ms": 1e3 * result.seconds,
        "fell_back": int(result.fell_back),
        "fallback_reason": result.fallback_reason,
    }


def run_protocol(points: int = 5, max_time: float = 0.5,
                 configurations: Iterable[tuple[str, str]] = CONFIGURATIONS,
                 rover: AsterixParameters | None = None,
                 log: Callable[[str], None] | None = print) -> list[dict]:
    """The paper's protocol (§5): in each direction, switch at ``points`` uniform times over the
    first gait's period, for every configuration. Returns one dict per transition."""
    if not 1 <= points <= 1000:
        raise ValueError(f"points = {points} must be in [1, 1000]")
    rover = rover or AsterixParameters()
    rows = []
    for strategy, wset in configurations:
        t0 = time.perf_counter()
        label = f"{strategy}/{wset}" if wset else strategy
        n_before = len(rows)
        for direction in DIRECTIONS:
            period = asterix_problem(0.0, direction, rover).from_gait.period
            for k in range(points):
                problem = asterix_problem(period * k / points, direction, rover)
                result = plan(problem, strategy, wset or None, max_time)
                metrics = evaluate_metrics(problem, result)
                row = metrics_row(problem, result, metrics)
                row.update(configuration=label, weights=wset, direction=direction)
                rows.append(row)
        if log:
            new = rows[n_before:]
            fb = sum(r["fell_back"] for r in new)
            med = float(np.median([r["solve_ms"] for r in new]))
            log(f"  {label:20s} {len(new):3d} transitions in {time.perf_counter() - t0:6.2f} s "
                f"(median solve {med:7.2f} ms, fallbacks {fb})")
    return rows


def summarise(rows: list[dict]) -> list[dict]:
    """Mean (and std) of the metrics per configuration, in CONFIGURATIONS order."""
    keys = ("duration_s", "heading_change_deg", "heading_deviation_deg", "position_deviation_m",
            "max_acc_steering", "max_acc_roll", "cost_of_transport", "energy_J", "energy_wheels_J",
            "energy_articulation_J", "distance_m", "solve_ms")
    out = []
    labels = []
    for r in rows:
        if r["configuration"] not in labels:
            labels.append(r["configuration"])
    for label in labels:
        sel = [r for r in rows if r["configuration"] == label]
        s = {"configuration": label, "strategy": sel[0]["strategy"], "n": len(sel),
             "fallbacks": sum(r["fell_back"] for r in sel)}
        for k in keys:
            vals = np.array([abs(r[k]) if k.startswith("heading") else r[k] for r in sel], float)
            s[k] = float(np.mean(vals))
            s[k + "_std"] = float(np.std(vals))
        s["solve_ms_median"] = float(np.median([r["solve_ms"] for r in sel]))
        out.append(s)
    return out
