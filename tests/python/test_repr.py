"""Every bound class prints as ``Type(field=value unit, ...)``, not ``<... object at 0x...>``."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from ernest_cpp import _core, dynamics as D, opt, soil, statics as S


def bound_classes():
    for mod_name, module in inspect.getmembers(_core, inspect.ismodule):
        for name, cls in inspect.getmembers(module, inspect.isclass):
            if hasattr(cls, "__members__") or issubclass(cls, BaseException):
                continue  # enums print as Name.Member; exceptions as their message
            yield pytest.param(cls, id=f"{mod_name}.{name}")


def readable(text: str, cls: type) -> bool:
    return cls.__name__ in text and "object at 0x" not in text


def num(x: float) -> str:
    """A number as the reprs print it: the shortest text that reads back to the same float."""
    return repr(float(x)).removesuffix(".0")


@pytest.mark.parametrize("cls", list(bound_classes()))
def test_every_bound_class_has_a_readable_repr(cls):
    own = [k for k in cls.__mro__ if "__repr__" in vars(k) and k.__module__.startswith("ernest_cpp")]
    assert own, f"{cls.__name__} prints as <... object at 0x...>"
    try:
        obj = cls()
    except TypeError:
        return  # needs arguments: the instances below cover the result types
    assert readable(repr(obj), cls), repr(obj)


def test_numbers_print_readably_and_read_back_exactly():
    p = soil.SoilParameters()
    p.eps_motion, p.cohesion = 1e-7, 2000.0
    text = repr(p)
    assert text.startswith("SoilParameters(density=1520 kg/m^3, cohesion=2000 Pa, ")
    assert f"friction_angle={num(p.friction_angle)} rad" in text and text.endswith(", ...)")
    w = opt.CostWeights(duration=0.1 + 0.2, acceleration=1.0, deviation=2.5e-5, linear=1.0)
    assert repr(w) == "CostWeights(duration=0.30000000000000004, acceleration=1, deviation=2.5e-05, linear=1)"
    for x in (w.duration, w.deviation):  # every printed number reads back to the same float
        assert float(num(x)) == x
    assert repr(opt.Pose2(1.5, -0.25, 3.0)) == "Pose2(x=1.5 m, y=-0.25 m, heading=3 rad)"
    assert repr(S.MassModel()).startswith(f"MassModel(m_c={num(S.MassModel().chassis_mass)} kg, ")
    for text in (repr(p), repr(S.MassModel()), repr(opt.squirming())):
        assert ".000000" not in text  # no fixed 6-decimal padding (std::to_string)


def test_result_types_show_their_main_fields_with_units():
    c = soil.ContactState(sinkage=0.015, vx=0.15, vy=0.0, vcx=-0.05, vcy=0.0)
    assert repr(c) == "ContactState(sinkage=0.015 m, vx=0.15 m/s, vy=0 m/s, vcx=-0.05 m/s, vcy=0 m/s)"

    sim = D.make_sim("rigid")
    sim.reset(0.0, 0.0, 0.0)
    sim.step_n(10)
    text = repr(sim.state)
    assert text.startswith(f"RoverState(time={num(sim.state.time)} s, position=[")
    assert f"energy={num(sim.state.energy)} J" in text and "wheel_load=[" in text
    assert "clutch=ClutchState." in text and readable(repr(sim), D.RoverSim)

    problem = opt.asterix_problem(t1=1.6)
    result = opt.plan(problem, "naive")
    metrics = opt.evaluate_metrics(problem, result)
    assert repr(result).startswith("TransitionResult(requested=Strategy.Naive, ")
    assert f"duration={num(metrics.duration)} s" in repr(metrics)

    t = np.arange(3) * 2 * math.pi / 3
    feet = np.vstack([np.cos(t), np.sin(t), np.zeros(3)])
    _, info = S.zero_interaction_forces(feet, [0.0, 0.0, 1.0], 100.0, S.EARTH_GRAVITY)
    assert repr(info).startswith("DistributionInfo(rank=6, residual=")

    model, geometry, poses = S.MassModel(), S.RoverGeometry(), []
    for slope, heading in ((0.0, 0.0), (0.3, 0.0), (0.3, 1.5)):
        pose = S.slope_pose(slope, heading, 0.0)
        pose.loads = S.predict_loads(model, geometry, pose)
        poses.append(pose)
    fit = S.fit_mass_model(poses, geometry)
    assert repr(fit).startswith("MassFitResult(model=MassModel(") and " rmse=" in repr(fit)


def test_python_controllers_and_envs_print_their_settings():
    from ernest_cpp import envs as E
    from ernest_cpp.envs import baselines as B, climbing as C

    for obj in (B.PassiveController(speed=0.1), B.CrawlingGaitController(period=5.0, k_track=0.3),
                B.LoadBalancingController(max_steer_deg=20.0), C.StepClimbController(trigger=0.5),
                C.BicklerCrossController()):
        text = repr(obj)
        assert "object at 0x" not in text
        again = eval(text, {**vars(B), **vars(C)})  # the text builds an equal controller
        assert repr(again) == text and vars(again).keys() == vars(obj).keys()
    assert repr(B.CrawlingGaitController(period=5.0)) == "CrawlingGaitController(period=5.0)"
    assert repr(C.BicklerCrossController()) == "BicklerCrossController()"
    assert repr(E.ErnestEnv("bickler")) == "ErnestEnv('bickler', soil='dry_sand')"
    assert repr(E.ErnestEnv("slope", passive=True, episode_length=5.0)) == (
        "ErnestEnv('slope', soil='m90', passive=True, episode_length=5.0)")
    from ernest_cpp.rl.toy_envs import PointMassEnv

    assert repr(PointMassEnv(obs_dim=45, act_dim=3)) == "PointMassEnv(obs_dim=45, act_dim=3)"


def test_the_sb3_vector_env_prints_its_id_and_size():
    pytest.importorskip("stable_baselines3")
    from ernest_cpp.envs.sb3 import ErnestSB3VecEnv

    env = ErnestSB3VecEnv("ernest/Slope-v0", num_envs=2)
    try:
        assert repr(env) == "ErnestSB3VecEnv(env_id='ernest/Slope-v0', num_envs=2)"
    finally:
        env.close()
