"""Python-side tests of ernest_cpp.soil: bindings, errors, numpy sweeps and the soil-curves job."""

import csv
import math

import numpy as np
import pytest

from ernest_cpp import soil as S
from ernest_cpp.cli import main as cli_main


def model(name="m90", points=S.DEFAULT_POINTS_PER_PANEL):
    return S.BekkerWongModel(S.soil_preset(name), S.ernest_wheel(), points)


def test_presets_follow_table_2():
    dry, m90 = S.SoilParameters.dry_sand(), S.SoilParameters.m90()
    assert (dry.density, dry.cohesion, dry.sinkage_exponent) == (1600, 1200, 1.9)
    assert math.isclose(math.degrees(dry.friction_angle), 33.3)
    assert (dry.k_c, dry.k_phi, dry.shear_modulus_x) == (10.3e3, 5309.4e3, 0.015)
    assert (m90.density, m90.cohesion, m90.sinkage_exponent) == (1520, 2000, 1.3)
    assert (m90.k_c, m90.k_phi, m90.shear_modulus_x) == (572.1e3, 4915.3e3, 0.0254)
    assert (m90.a0, m90.a1, m90.b0, m90.b1) == (0.43, 0.32, -0.16, 0.0)
    assert (m90.eps_slip, m90.eps_motion, m90.eps_contact_x) == (100, 5e-5, 0.01)
    wet = S.SoilParameters.wet_sand()
    assert wet.cohesion > m90.cohesion and wet.friction_angle < m90.friction_angle
    assert set(S.SoilParameters.preset_names()) == {"dry_sand", "m90", "wet_sand"}


def test_no_force_above_ground_and_rest_symmetry():
    m = model()
    f = m.evaluate(S.ContactState(sinkage=-0.01, vx=0.1, vcx=-0.05))
    assert (f.fx, f.fy, f.fz, f.axle_torque) == (0, 0, 0, 0)
    rest = m.evaluate(S.ContactState(sinkage=0.02))
    assert rest.fz > 0 and abs(rest.fx) < 1e-9 * rest.fz and rest.fy == 0


def test_batch_is_numpy_in_numpy_out_and_matches_single():
    m = model("wet_sand")
    rng = np.random.default_rng(0)
    states = np.column_stack([rng.uniform(1e-3, 0.1, 64), rng.uniform(-0.3, 0.3, (64, 4))])
    forces = m.evaluate_batch(states)
    assert forces.shape == (64, 4) and forces.dtype == np.float64
    for i in (0, 17, 63):
        f = m.evaluate(S.ContactState(*states[i]))
        np.testing.assert_array_equal(forces[i], [f.fx, f.fy, f.fz, f.axle_torque])
    with pytest.raises(TypeError):
        m.evaluate_batch(np.zeros((3, 4)))


@pytest.mark.parametrize("field,value", [("cohesion", -1.0), ("sinkage_exponent", float("nan")),
                                         ("shear_modulus_y", 0.0), ("friction_angle", 2.0)])
def test_invalid_parameters_raise_value_error_naming_the_field(field, value):
    p = S.SoilParameters.m90()
    setattr(p, field, value)
    with pytest.raises(ValueError, match=f"SoilParameters.{field}"):
        p.validate()
    with pytest.raises(ValueError, match=field):
        S.BekkerWongModel(p, S.ernest_wheel())


@pytest.mark.parametrize("field", ["sinkage", "vx", "vy", "vcx", "vcy"])
def test_non_finite_inputs_raise_value_error(field):
    m = model()
    st = S.ContactState(sinkage=0.01, vx=0.1)
    for bad in (float("nan"), float("inf")):
        setattr(st, field, bad)
        with pytest.raises(ValueError, match=field):
            m.evaluate(st)
    states = np.array([[0.01, 0.1, 0.0, np.nan, 0.0]])
    with pytest.raises(ValueError, match="vcx"):
        m.evaluate_batch(states)


def test_unknown_preset_and_bad_rig_inputs():
    with pytest.raises(ValueError, match="dry_sand, m90, wet_sand"):
        S.soil_preset("clay")
    with pytest.raises(ValueError, match="load"):
        S.solve_equilibrium(model(), -5.0, 0.2)
    with pytest.raises(ValueError, match="slip"):
        S.solve_equilibrium(model(), 100.0, 1.5)


def test_drawbar_curve_arrays_and_physics():
    load = 75 * 9.81 / 4
    c = S.drawbar_curve("m90", load, np.linspace(-0.6, 0.9, 16))
    assert set(c) == set(S.SWEEP_COLUMNS)
    assert all(isinstance(v, np.ndarray) and v.shape == (16,) for v in c.values())
    assert c["converged"].all()
    np.testing.assert_allclose(c["normal_force"], load, rtol=1e-6)
    driving = c["slip"] > 0.05
    assert (c["drawbar_pull"][c["slip"] < -0.05] < 0).all()
    assert np.all(np.diff(c["drawbar_pull"][driving]) > 0)
    assert (c["torque"][driving] > 0).all()


def test_equilibrium_sinkage_rises_with_load_from_10_to_2000_newtons():
    m = model()
    loads = [10, 50, 200, 800, 2000]
    sinkages = [S.solve_equilibrium(m, w, 0.2).sinkage for w in loads]
    assert all(b > a for a, b in zip(sinkages, sinkages[1:]))
    r = S.solve_equilibrium(model("dry_sand"), 2000.0, 0.2)
    assert not r.converged and r.sinkage == pytest.approx(0.17)  # axle-deep: reported, not hidden


def test_rigid_contact_parameters():
    rc = S.RigidContactParameters()
    assert (rc.stiffness, rc.damping, rc.friction_min, rc.friction_max) == (20e3, 20, 0.5, 0.9)
    dt = 1e-3
    assert rc.erp(dt) / (rc.cfm(dt) * dt) == pytest.approx(20e3)
    with pytest.raises(ValueError, match="dt"):
        rc.erp(0.0)


def test_soil_curves_command_writes_csv_and_plots(tmp_path, capsys):
    out = tmp_path / "soil"
    assert cli_main(["soil-curves", "--out", str(out), "--points", "9"]) == 0
    for name in ("soil_curves.csv", "drawbar_pull.png", "sinkage.png", "torque.png", "summary.md"):
        assert (out / name).stat().st_size > 0
    with open(out / "soil_curves.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 3 * 2 * 9
    assert {r["soil [-]"] for r in rows} == {"dry_sand", "m90", "wet_sand"}
    assert "drawbar_pull [N]" in rows[0] and "sinkage [m]" in rows[0]  # units in the header
    assert "| m90 | Mars |" in capsys.readouterr().out
    assert cli_main(["soil-curves", "--out", str(out), "--points", "0"]) == 2
