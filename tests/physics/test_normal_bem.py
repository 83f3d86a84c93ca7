"""Boundary-element normal contact (Kalker/Love coefficients, Polonsky-Keer CG): Hertz limit,
force-approach monotonicity, symmetry, and the two ways of prescribing the problem."""

from pathlib import Path

import numpy as np
import pytest

from wearcast.physics.contact.hertz import effective_modulus_mpa, hertz_contact
from wearcast.physics.contact.normal_bem import influence_coefficients, solve_normal_bem


def _grid(a, b, d=0.2, margin=1.3):
    x = np.arange(-margin * a, margin * a, d)
    y = np.arange(-margin * b, margin * b, d)
    return x - x.mean(), y - y.mean()


@pytest.mark.parametrize(("curv_a", "curv_b", "force"), [
    (1 / 920, 1 / 920, 10_000.0),        # circle
    (1 / 920, 1 / 600 + 0.002, 10_000.0),  # wheel on a rail crown, b/a ~ 0.45
    (1 / 920, 1 / 6000, 20_000.0),        # long lateral ellipse (a/b ~ 0.3), conformal-ish
])
def test_hertz_limit(curv_a, curv_b, force):
    hz = hertz_contact(force, curv_a, curv_b)
    x, y = _grid(hz.a_mm, hz.b_mm, d=min(hz.a_mm, hz.b_mm) / 10)
    xx, yy = np.meshgrid(x, y)
    res = solve_normal_bem(curv_a * xx**2 + curv_b * yy**2, x, y, normal_force_n=force)
    assert res.converged
    assert res.normal_force_n == pytest.approx(force, rel=1e-9)
    assert res.peak_pressure_mpa == pytest.approx(hz.p0_mpa, rel=0.02)
    assert res.approach_mm == pytest.approx(hz.approach_mm, rel=0.01)
    assert res.area_mm2 == pytest.approx(hz.area_mm2, rel=0.05)
    # pressure centre at the origin, no pressure on the border of the grid
    assert np.hypot(*res.centre_mm) < 1e-6 * hz.a_mm + 1e-9
    border = np.concatenate([res.pressure_mpa[0], res.pressure_mpa[-1],
                             res.pressure_mpa[:, 0], res.pressure_mpa[:, -1]])
    assert np.all(border == 0.0)


def test_prescribed_approach_gives_back_the_force():
    hz = hertz_contact(10_000.0, 1 / 920, 1 / 400)
    x, y = _grid(hz.a_mm, hz.b_mm)
    xx, yy = np.meshgrid(x, y)
    gap = xx**2 / 920 + yy**2 / 400
    by_force = solve_normal_bem(gap, x, y, normal_force_n=10_000.0)
    by_approach = solve_normal_bem(gap, x, y, approach_mm=by_force.approach_mm)
    assert by_approach.normal_force_n == pytest.approx(10_000.0, rel=1e-5)
    np.testing.assert_allclose(by_approach.pressure_mpa, by_force.pressure_mpa,
                               atol=1e-4 * by_force.peak_pressure_mpa)
    # an approach smaller than the smallest gap: no contact
    none = solve_normal_bem(gap + 0.01, x, y, approach_mm=0.005)
    assert none.normal_force_n == 0.0


def test_force_grows_with_approach_faster_than_linearly():
    # Hertz: F ~ delta^1.5; on any convex gap F(delta) is increasing and convex
    x, y = _grid(6.0, 6.0)
    xx, yy = np.meshgrid(x, y)
    gap = xx**2 / 920 + 0.004 * yy**2 + 0.0005 * yy**3  # non-symmetric, non-Hertzian
    deltas = np.array([0.01, 0.02, 0.03, 0.04])
    forces = np.array([solve_normal_bem(gap, x, y, approach_mm=d).normal_force_n
                       for d in deltas])
    assert np.all(np.diff(forces) > 0)
    assert np.all(np.diff(forces, 2) > 0)


def test_mirror_symmetry_and_asymmetric_gap():
    x, y = _grid(5.0, 5.0)
    xx, yy = np.meshgrid(x, y)
    gap = xx**2 / 920 + 0.004 * yy**2 + 0.0005 * yy**3
    res = solve_normal_bem(gap, x, y, normal_force_n=8_000.0)
    mirrored = solve_normal_bem(gap[::-1, :], x, y, normal_force_n=8_000.0)
    np.testing.assert_allclose(mirrored.pressure_mpa, res.pressure_mpa[::-1, :],
                               atol=1e-6 * res.peak_pressure_mpa)
    # symmetric in x (rolling direction), and the cubic term pushes the pressure centre
    # towards y < 0 where the bodies are closer
    np.testing.assert_allclose(res.pressure_mpa, res.pressure_mpa[:, ::-1],
                               atol=1e-6 * res.peak_pressure_mpa)
    assert res.centre_mm[1] < -0.05


def test_influence_coefficient_of_a_square():
    # centre displacement of a uniform pressure on a square of side 2c:
    # u = 4 c p ln(1 + sqrt 2) * 2 / (pi E*)  (Johnson 1985 §3.4 with 1/E* for both bodies)
    e_star = effective_modulus_mpa()
    c = influence_coefficients(1, 1, 2.0, 2.0, e_star)
    assert c.shape == (1, 1)
    assert c[0, 0] == pytest.approx(8.0 * np.log(1.0 + np.sqrt(2.0)) / (np.pi * e_star),
                                    rel=1e-12)


#: A coarse-grid normal problem of the contact pipeline on a raw MiniProf wheel
#: (left-wheel-v1-pre-dry on 60E1, shift +2 mm, yaw -0.01 rad, roll +0.002 rad from the rigid
#: one, 10 kN) with the warm start the pipeline gave it: from that start the iteration lost
#: every element in contact (found by the slow raw-wheel sweep of test_contact_robustness).
WARM_CASE = Path(__file__).with_name("fixtures") / "bem_warm_start_case.npz"


@pytest.mark.parametrize("compiled", [True, False])
def test_a_warm_start_that_loses_the_contact_is_solved_again_from_the_default_start(compiled):
    case = np.load(WARM_CASE)
    kw = {"approach_mm": float(case["approach_mm"]), "young_mpa": float(case["young_mpa"]),
          "poisson": float(case["poisson"]), "tol": 1e-6, "compiled": compiled}
    cold = solve_normal_bem(case["gap_mm"], case["x_mm"], case["y_mm"], **kw)
    warm = solve_normal_bem(case["gap_mm"], case["x_mm"], case["y_mm"],
                            initial_pressure_mpa=case["warm_mpa"], **kw)
    assert cold.normal_force_n > 0
    np.testing.assert_allclose(warm.pressure_mpa, cold.pressure_mpa,
                               atol=1e-4 * cold.peak_pressure_mpa)
