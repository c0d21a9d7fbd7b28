"""Python side of ERNEST's statics: bindings, errors, the lift-off sweep and ``ernest statics``."""

import math
import os

import numpy as np
import pytest

from ernest_cpp import dynamics as D
from ernest_cpp import rover_statics as RS
from ernest_cpp import statics as S
from ernest_cpp.cli import main as cli_main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def truth():
    p = D.RoverParameters()
    return S.MassModel.from_parameters(p), S.RoverGeometry.from_parameters(p)


def test_flat_loads_balance_the_weight_and_split_evenly_left_right():
    m, g = truth()
    f = S.predict_loads(m, g, S.slope_pose(0.0, 0.0, 0.0))
    assert f.shape == (4,)
    assert math.isclose(f.sum(), 75 * 9.81, rel_tol=1e-12)
    assert math.isclose(f[0], f[1], rel_tol=1e-12) and math.isclose(f[2], f[3], rel_tol=1e-12)


def test_fit_recovers_a_synthetic_model_with_the_bogie_weighed():
    m, g = truth()
    poses = []
    for slope in (0.0, 15.0):
        for heading in (0.0, 90.0):
            for psi in (-30.0, 0.0, 30.0):
                q = S.slope_pose(math.radians(slope), math.radians(heading), math.radians(psi))
                q.phi = math.radians(psi / 6)
                q.loads = S.predict_loads(m, g, q)
                poses.append(q)
    o = S.MassFitOptions()
    o.fixed = [False, True, False, False, False, False]
    init = S.MassModel()
    init.bogie_mass = m.bogie_mass
    r = S.fit_mass_model(poses, g, init, o)
    assert r.converged and r.rank == 5
    np.testing.assert_allclose(r.model.vector(), m.vector(), atol=1e-7)
    assert r.r_squared > 1 - 1e-12 and r.std_error[1] == 0.0
    free = S.fit_mass_model(poses, g)  # without the weighed bogie: the split is not identifiable
    assert free.rank == 5 and not free.identifiable[0] and math.isinf(free.std_error[1])


def test_bad_input_raises_value_error_naming_the_field():
    m, g = truth()
    bad = S.MassModel()
    bad.bogie_mass = -1.0
    with pytest.raises(ValueError, match="bogie_mass"):
        S.predict_loads(bad, g, S.LoadPose())
    pose = S.LoadPose()
    pose.psi = float("nan")
    with pytest.raises(ValueError, match="psi"):
        S.predict_loads(m, g, pose)
    with pytest.raises(ValueError, match="poses"):
        S.fit_mass_model([S.LoadPose()], g)
    o = S.LiftoffOptions()
    o.torque_limit = -1.0
    with pytest.raises(ValueError, match="torque_limit"):
        S.max_roll_torque(m, g, S.LoadPose(), o)
    so = S.SurveyOptions()
    so.block_height = -0.1
    with pytest.raises(ValueError, match="block_height"):
        S.survey_loads(D.RoverParameters(), so)
    with pytest.raises(ValueError, match="slope"):
        S.slope_pose(float("nan"), 0.0, 0.0)


def test_every_function_has_a_docstring():
    for name in ("fit_mass_model", "predict_loads", "load_equations", "survey_loads",
                 "pose_from_state", "max_roll_torque", "slope_pose"):
        assert len(getattr(S, name).__doc__ or "") > 40, name


def test_liftoff_sweep_mirrors_in_psi_and_matches_the_flat_closed_form():
    s = RS.liftoff_sweep(np.array([-30.0, 0.0, 30.0]))
    # y_c = 0: psi -> -psi mirrors left and right, so the limits swap sign
    assert math.isclose(s["tau_pos"][0], -s["tau_neg"][2], rel_tol=1e-9)
    assert np.all(s["tau_pos"] > 0) and np.all(s["tau_neg"] < 0)
    np.testing.assert_allclose(s["loads_pos"].sum(axis=1), 75 * 9.81, rtol=1e-9)
    flat = RS.liftoff_sweep(np.array([0.0]), slope_deg=0.0)
    f = flat["loads_zero"][0]
    assert math.isclose(flat["tau_pos"][0], 0.4 * min(f[0] + f[1], f[2] + f[3]), rel_tol=1e-9)


def test_statics_command_writes_the_liftoff_plot_and_the_fit_report(tmp_path):
    out = tmp_path / "statics"
    policy = os.path.join(ROOT, "policies", "ernest_default.pt")
    assert cli_main(["statics", "--out", str(out), "--policy", policy, "--episode-length", "3",
                     "--steps", "liftoff,mass-model"]) == 0  # all six: test_statics_cli.py
    assert (out / "liftoff_torque.png").stat().st_size > 10_000
    assert (out / "mass_model_fit.png").stat().st_size > 10_000
    report = (out / "report.md").read_text()
    assert "Fig. 25" in report and "eq 11" in report and "learned policy" in report.lower()
    assert cli_main(["statics", "--out", str(out), "--steps", "nonsense"]) == 2
