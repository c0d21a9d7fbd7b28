"""Python-side tests of ernest_cpp.statics: bindings, errors naming the field, and the C++ answers
against numpy (pseudo-inverse) and closed forms."""

import math

import numpy as np
import pytest

from ernest_cpp import statics as S


def hexagon(radius=2.5, n=6):
    t = np.arange(n) * 2 * np.pi / n
    return np.vstack([radius * np.cos(t), radius * np.sin(t), np.zeros(n)])


def test_margins_of_a_rectangle_match_the_closed_form():
    a, b, h = 1.2, 0.8, 1.75
    feet = np.array([[a, -a, -a, a], [b, b, -b, -b], [0, 0, 0, 0]], dtype=float)
    m = S.stability_margins(feet, [0.3, -0.1, h], S.EARTH_GRAVITY)
    d = min(a - 0.3, b - 0.1)
    assert m.support_vertices == 4 and m.cps_vertices == 1
    assert m.ssm == pytest.approx(d, abs=1e-12)
    assert m.nesm == pytest.approx(math.hypot(d, h) - h, abs=1e-12)
    assert m.ssm_cps == pytest.approx(-math.hypot(0.3, 0.1), abs=1e-12)
    frame = S.ProjectionFrame.from_gravity(S.EARTH_GRAVITY)
    poly = S.support_polygon(feet, frame)
    assert poly.vertices.shape == (2, 4) and poly.area() == pytest.approx(4 * a * b)
    assert len(poly.edge_contacts) == 4
    cps = S.conservative_support_polygon(hexagon(), frame)
    assert cps.size == 6 and cps.signed_distance([0, 0]) == pytest.approx(2.5 / 2)


def test_degenerate_stances_are_defined():
    m = S.stability_margins(np.zeros((3, 0)), [0, 0, 1], S.EARTH_GRAVITY)
    assert m.ssm == -math.inf and m.nesm == -math.inf
    line = np.array([[-1.0, 0, 1], [0, 0, 0], [0, 0, 0]])
    m = S.stability_margins(line, [0, 0.3, 1], S.EARTH_GRAVITY)
    assert m.support_vertices == 2 and m.ssm == pytest.approx(-0.3)
    assert not any(math.isnan(v) for v in (m.ssm, m.nesm, m.ssm_cps, m.nesm_cps))


def test_errors_name_the_argument():
    with pytest.raises(ValueError, match="contacts must have shape"):
        S.stability_margins(np.zeros((4, 3)), [0, 0, 1], S.EARTH_GRAVITY)
    with pytest.raises(ValueError, match="contacts"):
        S.stability_margins(np.full((3, 4), np.nan), [0, 0, 1], S.EARTH_GRAVITY)
    with pytest.raises(ValueError, match="gravity"):
        S.stability_margins(hexagon(), [0, 0, 1], [0, 0, 0])
    with pytest.raises(ValueError, match="cg"):
        S.zero_interaction_forces(hexagon(), [0, np.nan, 1], 10.0, S.EARTH_GRAVITY)
    with pytest.raises(ValueError, match="mass"):
        S.zero_interaction_forces(hexagon(), [0, 0, 1], 0.0, S.EARTH_GRAVITY)
    with pytest.raises(ValueError, match=r"stiffness\(2, 3\)"):
        k = np.full((3, 6), 1e5)
        k[2, 3] = -1.0
        S.sag_problem(hexagon(), [0, 0, 1.75], 850.0, k)
    with pytest.raises(ValueError, match="SagProblem.feet must have shape"):
        S.SagProblem().feet = np.zeros(6)
    p = S.sag_problem(hexagon(), [0, 0, 1.75], 850.0, 1e5)
    p.cg = [0, math.nan, 1]
    with pytest.raises(ValueError, match="cg"):
        S.solve_sag(p)


def test_zero_interaction_forces_equal_numpy_pinv():
    rng = np.random.default_rng(5)
    for n in range(3, 9):
        feet = np.vstack([rng.uniform(-2, 2, (2, n)), rng.uniform(-0.3, 0.3, (1, n))])
        cg, mass, g = np.array([0.2, -0.1, 1.5]), 850.0, np.array([0.3, -0.2, -9.8])
        forces, info = S.zero_interaction_forces(feet, cg, mass, g)
        A = np.zeros((6, 3 * n))
        for i, p in enumerate(feet.T):
            A[:3, 3 * i:3 * i + 3] = np.eye(3)
            A[3:, 3 * i:3 * i + 3] = [[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]]
        w = np.concatenate([-mass * g, -np.cross(cg, mass * g)])
        ref = np.linalg.pinv(A) @ w
        assert info.rank == 6 and info.residual < 1e-12
        np.testing.assert_allclose(forces.T.reshape(-1), ref, atol=1e-8 * mass * 9.81)


def test_sag_uniform_and_lifted_foot():
    p = S.sag_problem(hexagon(), [0, 0, 1.75], 850.0, stiffness=[2e5, 2e5, 1e5],
                      body_points=hexagon(1.2) + [[0], [0], [1.9]])
    r = S.solve_sag(p)
    sag = 850.0 * 9.81 / (6 * 1e5)
    assert r.status == S.SagStatus.Converged and r.loaded == 6
    np.testing.assert_allclose(r.deflections[2], -sag, atol=1e-12)
    np.testing.assert_allclose(r.body_points[2], 1.9 - sag, atol=1e-12)
    loads = [S.solve_sag(S.lift_foot(p, 0, dh)).forces[2, 0] for dh in np.linspace(0, 3 * sag, 13)]
    assert all(b <= a + 1e-9 for a, b in zip(loads, loads[1:]))
    assert loads[0] > 1000 and loads[-1] == 0.0
    r = S.solve_sag(S.lift_foot(S.lift_foot(S.lift_foot(S.lift_foot(p, 0, math.inf), 1, math.inf),
                                            2, math.inf), 3, math.inf))
    assert r.status == S.SagStatus.Unstable and np.isfinite(r.forces).all()


def test_calibration_recovers_a_known_constant():
    p = S.sag_problem(hexagon(), [0.1, 0, 1.75], 850.0, 1.0, body_points=hexagon(1.2) + [[0], [0], [1.9]])
    stances = []
    for lifted in ([], [0], [3]):
        q = p
        for leg in lifted:
            q = S.lift_foot(q, leg, 0.2)
        truth = S.sag_problem(q.feet, q.cg, q.mass, q.stiffness * 6e4, lift=q.lift,
                              body_points=q.body_points)
        stances.append(S.CalibrationStance(q, S.solve_sag(truth).body_points[2]))
    opts = S.CalibrationOptions()
    opts.grid_points = 21
    r = S.calibrate_spring_constant(stances, opts)
    assert r.k == pytest.approx(6e4, rel=1e-4)
    assert r.mean_error < 1e-7 and len(r.grid_k) == 21
    per_foot = S.calibrate_per_foot_constants(stances, r.k)
    np.testing.assert_allclose(per_foot.k, 6e4, rtol=1e-4)
    with pytest.raises(ValueError, match="k_initial"):
        S.calibrate_per_foot_constants(stances, -1.0)
