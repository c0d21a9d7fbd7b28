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


@pytest.mark.parametrize("cls", list(bound_classes()))
def test_every_bound_class_has_a_readable_repr(cls):
    own = [k for k in cls.__mro__ if "__repr__" in vars(k) and k.__module__.startswith("ernest_cpp")]
    assert own, f"{cls.__name__} prints as <... object at 0x...>"
    try:
        obj = cls()
    except TypeError:
        return  # needs arguments: the instances below cover the result types
    assert readable(repr(obj), cls), repr(obj)


def test_result_types_show_their_main_fields_with_units():
    c = soil.ContactState(sinkage=0.015, vx=0.15, vy=0.0, vcx=-0.05, vcy=0.0)
    assert repr(c) == "ContactState(sinkage=0.015 m, vx=0.15 m/s, vy=0 m/s, vcx=-0.05 m/s, vcy=0 m/s)"

    sim = D.make_sim("rigid")
    sim.reset(0.0, 0.0, 0.0)
    sim.step_n(10)
    text = repr(sim.state)
    assert text.startswith("RoverState(time=0.125 s, position=[") and "wheel_load=[" in text
    assert "clutch=ClutchState." in text and readable(repr(sim), D.RoverSim)

    problem = opt.asterix_problem(t1=1.6)
    result = opt.plan(problem, "naive")
    metrics = opt.evaluate_metrics(problem, result)
    assert repr(result).startswith("TransitionResult(requested=Strategy.Naive, ")
    assert f"duration={metrics.duration:.6g} s" in repr(metrics)

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
