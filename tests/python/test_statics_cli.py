"""``ernest statics``: every step's plot and report section, the stability map against closed
forms and the polygon, the Fig. 11-style calibration, and the step selection's errors."""

import math

import numpy as np
import pytest
from matplotlib.path import Path as MplPath

from ernest_cpp import rover_statics as RS
from ernest_cpp import walker_statics as WS
from ernest_cpp.cli import main as cli_main

PLOTS = ("stability_map.png", "fig11_sag.png", "fig16_lifted_legs.png", "fig15_sway_gait.png",
         "liftoff_torque.png", "mass_model_fit.png")
SECTIONS = ("## Stability map of a stance", "## Fig. 11: sag prediction", "## Fig. 16",
            "## Figs 14–15: sway gait", "## Lift-off roll torque", "## Mass model")


def test_statics_command_writes_six_plots_and_every_section(tmp_path):
    out = tmp_path / "statics"
    assert cli_main(["statics", "--out", str(out), "--policy", ""]) == 0
    for name in PLOTS:
        assert (out / name).stat().st_size > 10_000, name
    report = (out / "report.md").read_text()
    positions = [report.index(s) for s in SECTIONS]
    assert positions == sorted(positions)  # in the order of STEPS
    for name in PLOTS:
        assert f"({name})" in report, name  # each plot is linked from the report
    # the paper's numbers stand beside ours where it gives them
    for paper in ("50.28 %", "43.43 %", "over 20 %", "1.2 cm", "R² = 0.96"):
        assert paper in report, paper
    assert "synthetic" in report.lower()


def test_stability_map_is_positive_inside_the_polygon_and_negative_outside():
    m = WS.stability_map(n=41, extent=2.4)
    support = m["support"]
    centroid = support.mean(axis=1)  # a regular hexagon: the vertices' mean is the centroid
    ix, iy = (int(np.argmin(np.abs(m["x"] - centroid[0]))),
              int(np.argmin(np.abs(m["y"] - centroid[1]))))
    r = float(np.max(np.linalg.norm(m["feet"][:2], axis=0)))
    assert m["ssm"][iy, ix] == pytest.approx(r * math.cos(math.pi / 6), abs=1e-9)  # inradius
    assert m["ssm_cps"][iy, ix] == pytest.approx(r / 2, abs=1e-9)
    assert m["nesm"][iy, ix] > 0 and m["nesm_slope"][iy, ix] > 0
    X, Y = np.meshgrid(m["x"], m["y"])
    pts = np.c_[X.ravel(), Y.ravel()]
    poly = MplPath(support.T)
    inside = poly.contains_points(pts, radius=-1e-6).reshape(X.shape)   # shrunk: strictly in
    outside = ~poly.contains_points(pts, radius=1e-6).reshape(X.shape)  # grown: strictly out
    assert inside.sum() > 100 and outside.sum() > 100
    assert np.all(m["ssm"][inside] > 0) and np.all(m["nesm"][inside] > 0)
    assert np.all(m["ssm"][outside] < 0) and np.all(m["nesm"][outside] < 0)
    # the CPS lies inside the support polygon
    assert MplPath(support.T).contains_points(m["cps"].T).all()
    # on the slope, the tipping point moves uphill by h tan(theta) (gravity's projection)
    x0 = r - m["cg"][2] * math.tan(math.radians(m["slope_deg"]))
    assert WS.tipping_x(m["slope_deg"]) == pytest.approx(x0, abs=1e-9)
    with pytest.raises(ValueError, match="extent"):
        WS.stability_map(n=11, extent=-1.0)


def test_sag_calibration_recovers_a_known_constant_and_lifted_corners_sag_most():
    exact = WS.sag_experiment(k_true=6e4, spread=0.0, noise=0.0)
    assert exact["fit"].k == pytest.approx(6e4, rel=1e-4)
    assert max(np.max(np.abs(r["predicted"] - r["measured"])) for r in exact["rows"]) < 1e-6
    rows = {r["legs"]: r for r in exact["rows"]}
    six = rows[()]
    # six equal springs under a centred CG: every corner sinks m g / (6 k)
    np.testing.assert_allclose(six["rigid"] - six["predicted"], 850 * 9.81 / (6 * 6e4), rtol=1e-6)
    lifted = rows[(5,)]["predicted"]
    assert np.argmin(lifted) == 5 and np.argmax(lifted) == 2  # the lifted corner and its opposite
    noisy = WS.sag_experiment()
    errs = np.concatenate([r["predicted"] - r["measured"] for r in noisy["rows"]])
    assert np.mean(np.abs(errs)) < 0.012  # within the paper's 1.2 cm
    with pytest.raises(ValueError, match="spread"):
        WS.sag_experiment(spread=1.5)


def test_steps_select_a_subset_and_bad_steps_are_clear_errors(tmp_path, capsys):
    out = tmp_path / "s"
    assert cli_main(["statics", "--out", str(out), "--steps", "sway-gait"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["fig15_sway_gait.png", "report.md"]
    report = (out / "report.md").read_text()
    assert "## Figs 14–15" in report and "## Fig. 16" not in report
    bad = tmp_path / "bad"
    capsys.readouterr()
    assert cli_main(["statics", "--out", str(bad), "--steps", "stability,nonsense"]) == 2
    err = capsys.readouterr().err
    assert "unknown step 'nonsense'" in err
    for name, _ in RS.STEPS:
        assert name in err
    assert not bad.exists()  # nothing ran
    assert cli_main(["statics", "--out", str(bad), "--steps", ","]) == 2
    assert "names no step" in capsys.readouterr().err
    assert cli_main(["statics", "--out", str(bad), "--stride", "-1"]) == 2
