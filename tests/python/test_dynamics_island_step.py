"""Our own island step (SimOptions.stepper = Stepper.Own, the default; cpp/solver/island_step.hpp)
against ODE's dWorldStep from Python: the option, its counts, and the same run to rounding."""

import numpy as np

from ernest_cpp import dynamics as D
from ernest_cpp.soil import soil_preset


def _run(stepper, steps: int = 320, resolve_rhs_only: bool = True):
    # Table 2's soil as printed (eps_slip 100): the scenario these figures were measured on
    o = D.make_options("soil", soil=soil_preset("m90"), friction=0.8)
    o.stepper = stepper
    o.resolve_rhs_only = resolve_rhs_only
    rock = [D.BoxObstacle(np.array([0.85, 0.4, 0.0]), np.array([0.1, 0.12, 0.08]), 0.4, 0.0, 0.0)]
    sim = D.make_sim(obstacles=rock, options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15)
    c = D.Commands()
    c.wheel_speed = [0.15 / sim.parameters.wheel_radius] * 4
    c.yaw_rate = 0.05
    sim.set_commands(c)
    for _ in range(steps):
        sim.step()
    return sim


def test_stepper_option_default_and_binding():
    assert D.SimOptions().stepper == D.Stepper.Own
    o = D.SimOptions()
    o.stepper = D.Stepper.Ode
    o.validate()
    assert o.stepper == D.Stepper.Ode


def test_own_step_agrees_with_dworldstep_and_is_counted():
    own, ode = _run(D.Stepper.Own), _run(D.Stepper.Ode)
    s = own.solver_stats
    assert s.own_steps >= 320 and s.own_fallbacks == 0
    assert s.obstacle_guessed + s.obstacle_bounded > 0  # the rock was touched
    assert "own_steps=" in repr(s) and "own_fallbacks=" in repr(s)
    assert ode.solver_stats.own_steps == 0
    # the same run to rounding: per-step differences ~1e-15 m (test_dynamics_island_step)
    np.testing.assert_allclose(own.state_vector(), ode.state_vector(), rtol=1e-9, atol=1e-9)
    assert own.state.position[0] > 0.4


def test_solver_stats_count_the_sparse_solves_plans():
    # SolverStats.plans_made / plans_grown: the sparse solves' symbolic analyses (LdltPlan)
    for stepper in (D.Stepper.Own, D.Stepper.Ode):
        s = _run(stepper, steps=120).solver_stats
        assert 1 <= s.plans_made <= s.sparse_solves, stepper
        assert 0 <= s.plans_grown <= 3 * s.sparse_solves, stepper
        assert f"plans_made={s.plans_made}, plans_grown={s.plans_grown}" in repr(s)


def test_right_hand_side_resolves_give_the_same_bits():
    # SimOptions.resolve_rhs_only (default on): the implicit slip's level-only re-solves take the
    # last attempt's rows and factor (IslandStep::resolve); the same run bit for bit when off.
    assert D.SimOptions().resolve_rhs_only is True
    on, off = _run(D.Stepper.Own), _run(D.Stepper.Own, resolve_rhs_only=False)
    son, soff = on.solver_stats, off.solver_stats
    assert 0 < son.rhs_resolves < son.own_steps and soff.rhs_resolves == 0
    assert son.cap_resolves >= 0 and soff.cap_resolves == 0
    assert f"rhs_resolves={son.rhs_resolves}, cap_resolves={son.cap_resolves}" in repr(son)
    assert son.own_steps == soff.own_steps and son.slip_solves == soff.slip_solves
    np.testing.assert_array_equal(on.state_vector(), off.state_vector())
