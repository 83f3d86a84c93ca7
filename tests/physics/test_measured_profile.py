import numpy as np
import pytest

from wearcast.physics.profiles.measured import ProfileCurve, rail_curve, s1002_curve
from wearcast.physics.profiles.rails import rail_60e1_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm


def test_spline_of_sampled_s1002_reproduces_it():
    # Interpolating arc-length spline through analytic samples 0.1 mm apart.  Measured error:
    # 1.05e-4 mm at the 1.2e-4 mm step the published coefficients leave at y = -35 (README),
    # up to 6e-5 mm within 1 mm of the other section junctions (curvature jumps, worst on the
    # steep flange flank), 2.2e-5 mm at the 3.7e-5 mm step at y = -26, and below 1e-5 mm
    # elsewhere (below 1e-6 on most of the tread; 5e-6 on the near-vertical flange back).
    curve = s1002_curve(step_mm=0.1)
    y = np.linspace(-69.0, 59.0, 6401)
    error = np.abs(curve.height_mm(y) - s1002_height_mm(y))
    assert error.max() < 1.5e-4
    junctions = np.array([-62.7647, -49.6625, -39.7645, -38.4267, -35.0, -26.0, 32.158])
    away = np.min(np.abs(y[:, None] - junctions[None, :]), axis=1) > 1.0
    assert error[away].max() < 1e-5


def test_s1002_slopes_and_curvatures_match_its_sections():
    curve = s1002_curve()
    # section E: straight flank F = -AE - BE*y, slope -2.747477419 (70 deg)
    assert curve.slope(-39.0) == pytest.approx(-2.747477419, rel=1e-5)
    # section G: flange tip, arc R12 with its centre below the profile -> curvature -1/12;
    # section A: 1:15 cone -> slope -1/15, curvature 0
    assert curve.curvature_per_mm(-55.0) == pytest.approx(-1 / 12, rel=1e-4)
    assert curve.slope(45.0) == pytest.approx(-1 / 15, rel=1e-6)
    assert abs(curve.curvature_per_mm(45.0)) < 1e-6
    # section D: flange root arc R13, centre above -> +1/13
    assert curve.curvature_per_mm(-37.0) == pytest.approx(1 / 13, rel=1e-3)


@pytest.mark.parametrize("radius_mm", [13.0, 300.0])
def test_curvature_of_a_sampled_circle(radius_mm):
    # a valley (centre above the points) has curvature +1/R, a hill -1/R; 1-degree samples
    theta = np.radians(np.arange(-60.0, 60.5, 1.0))
    y, z = radius_mm * np.sin(theta), radius_mm * (1 - np.cos(theta))
    valley = ProfileCurve.from_points(y, z)
    hill = ProfileCurve.from_points(y, -z)
    probe = np.linspace(-0.7, 0.7, 15) * radius_mm
    np.testing.assert_allclose(valley.curvature_per_mm(probe), 1 / radius_mm, rtol=1e-4)
    np.testing.assert_allclose(hill.curvature_per_mm(probe), -1 / radius_mm, rtol=1e-4)


def test_overhanging_profile_is_single_valued_only_where_it_is():
    # a cup: three quarters of a circle of radius 10 around (0, 10), open at the top, its rims
    # at y = +/-7.07 curling back over the sides (like a flange with a lip)
    theta = np.radians(np.arange(-135.0, 135.5, 0.5))
    y, z = 10 * np.sin(theta), 10 - 10 * np.cos(theta)
    curve = ProfileCurve.from_points(y, z)
    # |y| < 7.07: the arc passes once (bottom), 7.07 < |y| < 10: twice (overhang)
    assert curve.height_mm(0.0) == pytest.approx(0.0, abs=1e-6)
    assert curve.height_mm(5.0) == pytest.approx(10 - np.sqrt(75.0), abs=1e-6)
    assert np.isnan(curve.height_mm(8.0)) and np.isnan(curve.height_mm(11.0))
    # by arc length everything is defined: vertical tangent at the side point (y = 10)
    s_top = np.pi / 2 * 10 + np.radians(135) * 10
    assert abs(np.cos(curve.tangent_angle_at(s_top))) < 1e-3
    assert curve.curvature_at(curve.sample(1.0)) == pytest.approx(0.1, rel=1e-3)


def test_point_order_does_not_matter():
    y = np.linspace(-20, 20, 81)
    z = 0.01 * y**2
    forward = ProfileCurve.from_points(y, z)
    backward = ProfileCurve.from_points(y[::-1], z[::-1])
    probe = np.linspace(-19, 19, 7)
    np.testing.assert_allclose(forward.height_mm(probe), backward.height_mm(probe), atol=1e-12)
    np.testing.assert_allclose(forward.curvature_per_mm(probe),
                               backward.curvature_per_mm(probe), atol=1e-9)


def test_smoothing_recovers_a_noisy_measured_circle():
    # a measured R80 arc with 10 um scatter (MiniProf class): with smoothing_mm = 0.01 the
    # curvature is recovered to 10 % and the shape to the scatter level; without smoothing the
    # noise dominates the curvature.
    rng = np.random.default_rng(7)
    theta = np.radians(np.linspace(-20, 20, 400))
    y = 80 * np.sin(theta)
    z = -80 * (1 - np.cos(theta)) + rng.normal(0, 0.01, theta.size)
    smooth = ProfileCurve.from_points(y, z, smoothing_mm=0.01)
    raw = ProfileCurve.from_points(y, z)
    probe = np.linspace(-20, 20, 9)
    np.testing.assert_allclose(smooth.curvature_per_mm(probe), -1 / 80, rtol=0.1)
    np.testing.assert_allclose(smooth.height_mm(probe), -80 * (1 - np.cos(np.arcsin(probe / 80))),
                               atol=0.01)
    assert np.max(np.abs(raw.curvature_per_mm(probe) + 1 / 80)) > 10 / 80


def test_rail_curve_matches_the_analytic_rail_and_bad_input_is_refused():
    curve = rail_curve("60E1")
    # 1e-4 mm on the head; on the 1:20 flank the vertical error is 20 times the normal one
    # (2e-4 mm next to the R13/flank tangent point, i.e. 1e-5 mm normal to the surface)
    y = np.linspace(-36.5, 36.5, 147)
    on_head = np.abs(y) < 35.99
    np.testing.assert_allclose(curve.height_mm(y[on_head]), rail_60e1_height_mm(y[on_head]),
                               atol=1e-4)
    np.testing.assert_allclose(curve.height_mm(y[~on_head]), rail_60e1_height_mm(y[~on_head]),
                               atol=20 * 2e-5)
    assert curve.curvature_per_mm(0.0) == pytest.approx(-1 / 300, rel=1e-3)
    with pytest.raises(ValueError, match="at least 4"):
        ProfileCurve.from_points([0, 1, 2], [0, 1, 2])
    with pytest.raises(ValueError, match="same length"):
        ProfileCurve.from_points([0, 1, 2, 3], [0, 1, 2])
