"""Torque-aware FootFall from Python (seed 003 §7.1): the bindings' limiting cases on a coarse map
(an infinite limit leaves the map unchanged, zero makes every stable cell Overloaded), the stance
torques against walker.stance_loads, bad limits refused naming the field, the peak-torque smoother."""

import math

import numpy as np
import pytest

from ernest_cpp import footfall as F
from ernest_cpp import walker as W


@pytest.fixture(scope="module")
def scene():
    model = W.WalkerModel(W.sdm_b_parameters())
    body, q = np.asarray(model.standard_body_pose()), model.standard_configuration
    feet = np.asarray(model.contact_points(body, q))
    terrain = F.rock_field(F.RockFieldOptions(), feet[:2].copy())
    return model, body, q, terrain


def _map(scene, **kw):
    model, body, q, terrain = scene
    o = F.StabilityMapOptions()
    o.cell = 0.1
    for k, v in kw.items():
        setattr(o, k, v)
    return F.StabilityMapper(model, terrain, body, q, 0, o).map()


def test_limiting_cases(scene):
    plain, evaluated, zero = _map(scene), _map(scene, torques=True), _map(scene, max_saturation=0.0)
    assert np.array_equal(np.asarray(plain.status), np.asarray(evaluated.status))
    assert np.array_equal(np.asarray(plain.margin), np.asarray(evaluated.margin), equal_nan=True)
    assert np.isnan(np.asarray(plain.saturation)).all() and math.isnan(plain.lift_saturation)
    reachable = np.asarray(evaluated.status) > 0
    assert np.isfinite(np.asarray(evaluated.saturation)[reachable]).all()
    assert zero.count(F.CellStatus.Stable) == 0
    assert zero.count(F.CellStatus.Overloaded) == plain.count(F.CellStatus.Stable)


def test_stance_torques_and_errors(scene):
    model, body, q, _ = scene
    t = F.StanceTorques(model, body, q, 0)
    assert t.down(q[:, 0]).saturation == pytest.approx(W.stance_loads(model, body, q, []).peak_saturation, abs=1e-9)
    up = W.lift_legs(model, body, q, [0], 0.2)
    assert t.lifted(up[:, 0]).saturation == pytest.approx(W.stance_loads(model, body, up, [0]).peak_saturation, abs=1e-9)
    o = F.StabilityMapOptions()
    for bad in (math.nan, -1.0):
        o.max_saturation = bad
        with pytest.raises(ValueError, match="max_saturation"):
            o.validate()
    with pytest.raises(ValueError, match="q_leg"):
        t.lifted(np.full(6, np.nan))


def test_peak_torque_smoother(scene):
    model, body, q, terrain = scene
    checker = F.LegCollisionChecker(model, terrain, body, q, 0)
    t = F.StanceTorques(model, body, q, 0)
    a = W.lift_legs(model, body, q, [0], 0.3)[:, 0]
    b = W.lift_legs(model, body, q, [0], 0.6)[:, 0]
    path = np.stack([a, 0.5 * (a + b) + 0.2, b], axis=1)
    r = F.smooth_path_for_torque(checker, t, path)
    assert r.peak_saturation <= r.initial_peak_saturation + 1e-3
    assert np.allclose(r.path[:, 0], a) and np.allclose(r.path[:, -1], b)
    assert F.SmoothingOptions().objective == F.SmoothingObjective.Length
