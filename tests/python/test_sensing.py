"""ernest_cpp.sensing from Python: layout constants, filter, elevation sampling with holes, reward."""

import math

import numpy as np
import pytest

from ernest_cpp import sensing as S


def test_layout_constants_match_section_4_2():
    assert S.OBSERVATION_SIZE == 45 and S.ACTION_SIZE == 3 and S.ELEVATION_SAMPLES == 12
    names = S.observation_names()
    assert len(names) == 45 and len(set(names)) == 45
    assert [names[i] for i in S.FORCE_INDICES[:3]] == ["fts_FL_Fx", "fts_FL_Fy", "fts_FL_Fz"]
    assert [names[i] for i in S.TORQUE_INDICES[-3:]] == ["fts_RR_Tx", "fts_RR_Ty", "fts_RR_Tz"]
    assert names[S.OBSERVATION_INDEX["action"]] == "action_vx"
    d = S.ObservationScales().divisors()
    assert d.shape == (45,) and (d > 0).all()


def test_fts_filter_step_response_and_mean_removal():
    p = S.FtsProcessor()
    p.reset(np.zeros((4, 6)))
    for _ in range(400):  # one second at 400 Hz
        p.update(np.ones((4, 6)))
    assert p.filtered[0, 0] == pytest.approx(1 - math.exp(-2 * math.pi * 0.5 * 1.0), abs=1e-12)
    w = np.arange(24.0).reshape(4, 6)
    p.reset(w)
    np.testing.assert_allclose(p.processed().sum(axis=0), 0, atol=1e-12)
    with pytest.raises(ValueError, match="finite"):
        p.update(np.full((4, 6), np.nan))


def test_elevation_from_grid_with_holes_and_python_source():
    sampler = S.ElevationSampler()
    ground_z = sampler.options.ground_z
    xs = np.arange(-2, 3.01, 0.05)
    grid = np.tile((0.1 * xs)[:, None], (1, len(xs)))  # ramp z = 0.1 x
    grid[(xs > 0.55) & (xs < 0.95), :] = np.nan  # occlusion band
    src = S.GridHeightSource(grid, 0.05, -2.0, -2.0)
    assert src.height(0.7, 0.0) is None and src.height(0.3, 0.0) == pytest.approx(0.03)
    values, source = sampler.sample(np.array([0, 0, -ground_z]), np.eye(3), src)
    expected = [0.1 * sampler.point(k)[0] for k in range(12)]
    np.testing.assert_allclose(values, expected, atol=1e-9)
    assert source[0] == 1 and source[2] == 0

    class Flat(S.HeightSource):
        def height(self, x, y):
            return 5.0

    values, source = sampler.sample(np.array([1.0, 2.0, 5.0 - ground_z]), np.eye(3), Flat())
    np.testing.assert_allclose(values, 0, atol=1e-12)
    filled, any_valid = S.fill_line(np.arange(4.0), np.array([0, 9, 9, 3.0]),
                                    np.array([True, False, False, True]))
    np.testing.assert_allclose(filled, [0, 1, 2, 3]) and any_valid


def test_observation_scaling_and_errors():
    inp = S.ObservationInputs()
    inp.lateral_deviation = 1.0
    f = np.zeros((4, 6))
    f[2, 1] = -100.0
    inp.fts = f
    inp.action = np.array([0.5, 0, -1])
    obs = S.build_observation(inp)
    assert obs.shape == (45,)
    assert obs[1] == 0.5 and obs[S.OBSERVATION_INDEX["fts"] + 13] == -0.5
    assert list(obs[42:]) == [0.5, 0, -1]
    e = np.zeros(12)
    e[3] = np.inf
    inp.elevation = e
    with pytest.raises(ValueError, match="elev_FR_0"):
        S.build_observation(inp)


def test_action_mapping_and_reward():
    cmd = S.action_to_command(np.array([0.0, 1.0, -1.0]))
    np.testing.assert_allclose(cmd, [0.1, math.radians(20), -math.radians(10)])
    path = S.PathLine(0.0, 0.0, 0.0)
    terms = S.compute_reward(path, 0.0, 0.0, 0.05, 0.0, 0.0)  # 0.1 m/s for 0.5 s
    assert terms.progress == pytest.approx(0.05) and terms.reward == pytest.approx(0.2)
    with pytest.raises(ValueError, match="finite"):
        S.compute_reward(path, 0, 0, float("nan"), 0, 0)
