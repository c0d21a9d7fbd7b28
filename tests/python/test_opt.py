"""Python API of the gait-transition subsystem (seed 000): NLopt wrapper with Python callbacks,
kinematics, strategies and the experiment command."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

import ernest_cpp
from ernest_cpp import opt as O


def tutorial(x):
    return math.sqrt(x[1]), np.array([0.0, 0.5 / math.sqrt(x[1])])


def tutorial_constraints(x):
    vals, jac = [], []
    for a, b in ((2.0, 0.0), (-1.0, 1.0)):
        u = a * x[0] + b
        vals.append(u ** 3 - x[1])
        jac.append([3 * a * u * u, -1.0])
    return np.array(vals), np.array(jac)


def test_exposed_as_submodule():
    assert ernest_cpp.opt.plan_transition is ernest_cpp._core.opt.plan_transition
    from ernest_cpp import cli, transitions

    assert transitions in cli._COMMANDS


def test_minimize_slsqp_tutorial_from_python():
    opts = O.SolverOptions()
    opts.xtol_rel, opts.ftol_rel, opts.ftol_abs, opts.max_time = 1e-10, 0.0, 0.0, 5.0
    r = O.minimize_slsqp(tutorial, [1.234, 5.678], [-math.inf, 0.0], [math.inf, math.inf],
                         [(2, tutorial_constraints)], [], opts)
    assert r.converged, r.status_name
    assert r.x[0] == pytest.approx(1 / 3, abs=1e-6)
    assert r.x[1] == pytest.approx(8 / 27, abs=1e-6)
    assert r.value == pytest.approx(0.544331, abs=1e-6)


class MyCallbackError(Exception):
    pass


def test_objective_exception_reaches_python_with_its_type():
    calls = []

    def objective(x):
        calls.append(1)
        if len(calls) == 2:
            raise MyCallbackError("raised inside the NLopt objective")
        return tutorial(x)

    with pytest.raises(MyCallbackError, match="inside the NLopt objective"):
        O.minimize_slsqp(objective, [1.234, 5.678], [-math.inf, 0.0], [math.inf, math.inf],
                         [(2, tutorial_constraints)])
    assert len(calls) == 2  # stopped at the failing call


def test_constraint_exception_reaches_python_with_its_type():
    def bad_constraint(x):
        raise KeyError("constraint")

    with pytest.raises(KeyError):
        O.minimize_slsqp(tutorial, [1.234, 5.678], [-math.inf, 0.0], [math.inf, math.inf],
                         [(2, bad_constraint)])


def test_steering_callback_exception_reaches_python():
    kin = O.AsterixKinematics()

    def steering(t):
        if t > 0.5:
            raise ZeroDivisionError("steering")
        return 0.1, 0.0

    with pytest.raises(ZeroDivisionError):
        kin.integrate(steering, 0.0, 2.0)


def test_invalid_parameters_raise_value_error_naming_the_field():
    p = O.AsterixParameters()
    p.l_x = -0.2
    with pytest.raises(ValueError, match="l_x"):
        p.validate()
    with pytest.raises(ValueError):
        O.plan(O.asterix_problem(0.0), "warp-drive")
    with pytest.raises(ValueError, match="strategy = 1.5 must be a Strategy"):
        O.as_strategy(1.5)
    with pytest.raises(ValueError, match="weights = 3 must be"):
        O.weights_for("bezier", 3)
    assert O.as_strategy("Bezier") == O.as_strategy(O.as_strategy("bezier"))


def test_constant_steering_circle_from_python():
    p = O.AsterixParameters()
    kin = O.AsterixKinematics(p)
    theta = 0.3
    radius = kin.turning_radius(theta)
    assert radius == pytest.approx(p.l_x * math.cos(theta / 2) / math.tan(theta / 2))
    end = kin.integrate(lambda t: (theta, 0.0), 0.0, 7.0)
    # circle centre at (0, -radius) for theta > 0 (clockwise turn)
    assert math.hypot(end.x, end.y + radius) == pytest.approx(radius, abs=1e-8)
    assert end.heading == pytest.approx(-p.forward_speed / p.l_x * math.tan(theta / 2) * 7.0)


@pytest.mark.parametrize("strategy", ["naive", "bezier", "linear", "spline"])
def test_every_strategy_plans_a_feasible_transition(strategy):
    pb = O.asterix_problem(1.6)
    t0 = time.perf_counter()
    r = O.plan(pb, strategy, "balanced", max_time=0.3)
    wall = time.perf_counter() - t0
    iteration = r.solver.seconds / max(1, r.solver.evaluations)
    assert wall < 0.3 + iteration + 0.02  # budget + one SLSQP iteration + Python overhead
    assert not r.fell_back, r.fallback_reason
    m = O.evaluate_metrics(pb, r)
    assert m.start_position_residual < 1e-9 and m.end_position_residual < 1e-9
    if strategy != "naive":
        assert m.start_velocity_residual < 1e-6 and m.end_velocity_residual < 1e-6
        assert r.max_violation <= 1e-6
    q, dq, _ = r.sample(np.linspace(0.0, r.duration, 301))
    assert q.shape == (301, 2)
    assert np.all(np.abs(q) <= np.asarray(pb.position_limit) * (1 + 1e-6))
    assert m.cost_of_transport == pytest.approx(
        m.energy / (pb.rover.mass * pb.rover.gravity * m.distance))


def test_fallback_reports_reason():
    pb = O.asterix_problem(0.0)
    opts = O.IntegrationOptions()
    opts.max_steps = 1
    r = O.plan(pb, "spline", "deviation", 0.3, integration=opts)
    assert r.fell_back and r.strategy == O.Strategy.Naive and r.requested == O.Strategy.Spline
    assert "spline failed" in r.fallback_reason


def test_cost_gradient_matches_finite_differences():
    pb = O.asterix_problem(2.0)
    opts = O.TransitionOptions()
    opts.waypoints = 8
    w = O.CostWeights.table1(O.Strategy.Linear, O.WeightSet.Deviation)
    n = O.transition_dimension(pb, O.Strategy.Linear, opts)
    x = np.concatenate([[1.5, 3.0], 0.1 * np.sin(np.arange(n - 2))])
    f, g = O.transition_cost(pb, O.Strategy.Linear, w, opts, x)
    h = 1e-6
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        fd = (O.transition_cost(pb, O.Strategy.Linear, w, opts, x + e)[0]
              - O.transition_cost(pb, O.Strategy.Linear, w, opts, x - e)[0]) / (2 * h)
        assert g[i] == pytest.approx(fd, rel=1e-5, abs=1e-5)


def test_transitions_command_writes_outputs(tmp_path):
    from ernest_cpp import cli

    out = tmp_path / "tr"
    rc = cli.main(["transitions", "--out", str(out), "--points", "1", "--max-time", "0.05"])
    assert rc == 0
    for name in ("transitions.csv", "summary.md", "fig8_duration.png", "fig9_heading.png",
                 "fig10_max_acceleration.png", "fig11_cost_of_transport.png", "fig2_naive.png",
                 "fig3_bezier.png", "fig4_linear.png", "asterix_example.png", "findings.md"):
        assert (out / name).stat().st_size > 0, name
    lines = (out / "transitions.csv").read_text().strip().splitlines()
    assert len(lines) == 1 + 10 * 2  # header + 10 configurations x 2 directions x 1 point
    head = lines[0].split(",")
    assert all(" [" in h and h.endswith("]") for h in head), head  # every column names its unit
    assert {"t1 [s]", "max_acc_steering [rad/s^2]", "cost [-]", "res_start_pos [rad]",
            "res_end_vel [rad/s]", "solve_ms [ms]"} <= set(head)
    assert not list(out.glob("*.tmp*"))  # atomic writes leave no temporaries
    assert cli.main(["transitions", "--out", str(out), "--max-time", "-1"]) == 2
