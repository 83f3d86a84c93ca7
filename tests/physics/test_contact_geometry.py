
from dataclasses import replace

import numpy as np
import pytest

from wearcast.physics.contact.geometry import (
    contact_points,
    contact_table,
    rigid_wheel_gap,
    rigid_wheel_gap_beyond_rail,
    s1002_60e1,
    wheel_gap,
)
from wearcast.physics.profiles.rails import rail_60e1_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm

SHIFTS = np.linspace(-10.0, 10.0, 401)


@pytest.fixture(scope="module")
def wheelset():
    return s1002_60e1()


@pytest.fixture(scope="module")
def table(wheelset):
    return contact_table(wheelset, SHIFTS)


def test_mirror_symmetry(table):
    # the left wheel at +y is the right wheel at -y; roll is odd, height even in y
    left, right = table.left.primary, table.right.primary
    for name in ("y_wheel_mm", "y_rail_mm", "contact_angle_rad", "rolling_radius_mm",
                 "curvature_a_per_mm", "curvature_b_per_mm"):
        np.testing.assert_allclose(getattr(left, name), getattr(right, name)[::-1], atol=1e-8)
    np.testing.assert_allclose(table.left.primary.y_track_mm,
                               -table.right.primary.y_track_mm[::-1], atol=1e-8)
    np.testing.assert_allclose(table.roll_rad, -table.roll_rad[::-1], atol=1e-12)
    np.testing.assert_allclose(table.height_mm, table.height_mm[::-1], atol=1e-9)


def test_rolling_radius_difference_is_zero_centred_and_monotone(table):
    dr = table.rolling_radius_difference_mm
    assert dr[SHIFTS == 0.0][0] == pytest.approx(0.0, abs=1e-9)
    # monotone over the whole range: tread, flange root and flange (it jumps where the
    # contact jumps, but never goes back)
    assert np.all(np.diff(dr) > 0)
    assert np.all(np.sign(dr[SHIFTS != 0]) == np.sign(SHIFTS[SHIFTS != 0]))


def test_both_wheels_touch_without_penetration(wheelset, table):
    # equilibrium of the rigid geometry: each wheel's minimum gap is zero, no point penetrates
    for side in ("left", "right"):
        _, gap = wheel_gap(wheelset, SHIFTS[::20], side)
        # the samples are 0.2 mm apart in arc length; the solver refines the minimum between
        # them, so the sampled minimum may sit above zero by up to ~1e-3 mm on the steep flange
        assert np.all(gap.min(axis=1) < 1e-3)
        assert gap.min() > -1e-6


@pytest.mark.parametrize("side", ["left", "right"])
def test_contact_points_lie_on_both_profiles_with_a_common_tangent(table, side):
    patch = getattr(table, side).primary
    # on the analytic profiles (the splines reproduce them to 1e-4 mm)
    np.testing.assert_allclose(patch.z_wheel_mm, s1002_height_mm(patch.y_wheel_mm), atol=2e-4)
    np.testing.assert_allclose(patch.z_rail_mm, rail_60e1_height_mm(patch.y_rail_mm), atol=2e-4)
    # delta is minus the inclined rail's tangent angle (both rails are upright profiles turned
    # by 1:40; u points away from the track centre)
    h = 1e-5
    rail_slope = (rail_60e1_height_mm(patch.y_rail_mm + h)
                  - rail_60e1_height_mm(patch.y_rail_mm - h)) / (2 * h)
    rail_delta = -(np.arctan(rail_slope) + np.arctan(1 / 40))
    np.testing.assert_allclose(patch.contact_angle_rad, rail_delta, atol=2e-5)  # spline: 5e-6
    # tangency: the wheel profile angle turned by the roll (left: minus, right: plus) is the
    # same angle; measured 4e-4 rad at worst (flange, contact point refined between samples)
    sign = -1.0 if side == "left" else 1.0
    np.testing.assert_allclose(patch.contact_angle_rad,
                               patch.wheel_angle_rad + sign * table.roll_rad, atol=1e-3)
    assert np.all(patch.contact_angle_rad < 0)  # tread and flange both push to the centre


def test_hertz_curvatures_on_the_tread(table):
    # centred wheelset: tread contact on the rail crown (R300) -> B = (1/300 + k_wheel) / 2,
    # A = cos(gamma) / (2 r)
    centre = table.left.primary.row(int(np.flatnonzero(SHIFTS == 0.0)[0]))
    assert centre.rail_curvature_per_mm == pytest.approx(1 / 300, rel=1e-3)
    assert centre.curvature_b_per_mm == pytest.approx(
        0.5 * (centre.rail_curvature_per_mm + centre.wheel_curvature_per_mm), rel=1e-12)
    # the S1002 tread there is concave towards the rail (negative), less than the crown
    assert -1 / 300 < centre.wheel_curvature_per_mm < 0
    assert centre.curvature_a_per_mm == pytest.approx(
        np.cos(centre.wheel_angle_rad) / (2 * centre.rolling_radius_mm), rel=1e-12)
    assert centre.rolling_radius_mm == pytest.approx(460.0 + centre.z_wheel_mm)


def test_flange_contact_and_two_point_contact(wheelset):
    shifts = np.arange(4.5, 7.001, 0.05)
    table = contact_table(wheelset, shifts)
    primary, secondary = table.left.primary, table.left.secondary
    # the primary jumps from the tread to the flange root near 5 mm; around the jump the
    # tread point is a second contact within the tolerance, closest right at the jump
    jump = np.flatnonzero(np.diff(primary.y_wheel_mm) < -5.0)[0]
    assert secondary.valid[jump] and secondary.valid[jump + 1]
    assert np.all(secondary.gap_mm[secondary.valid] <= 0.05)
    assert min(secondary.gap_mm[jump], secondary.gap_mm[jump + 1]) < 0.01
    # deep flange contact beyond 6.5 mm: steep contact angle of the S1002 flange (70 deg flank)
    deep = shifts >= 6.5
    assert np.all(primary.contact_angle_rad[deep] < -0.75)
    assert np.all(primary.y_wheel_mm[deep] < -38.0)
    # the right wheel stays on its tread
    assert np.all(table.right.primary.y_wheel_mm > 0.0)
    # a zero tolerance removes the secondary patches
    strict = contact_table(wheelset, shifts, two_point_gap_mm=0.0)
    assert not strict.left.secondary.valid[jump - 3]


def test_contact_points_single_shift_matches_table(wheelset, table):
    i = int(np.flatnonzero(np.isclose(SHIFTS, 5.0))[0])
    single = contact_points(wheelset, 5.0)
    assert single.roll_rad == pytest.approx(table.roll_rad[i], abs=1e-12)
    assert single.left[0].y_wheel_mm == pytest.approx(table.left.primary.y_wheel_mm[i])
    assert len(single.left) == 1 + int(table.left.secondary.valid[i])
    assert single.rolling_radius_difference_mm == pytest.approx(
        table.rolling_radius_difference_mm[i])


def test_wheel_gap_refuses_an_unknown_side(wheelset):
    with pytest.raises(ValueError, match="side"):
        wheel_gap(wheelset, [0.0], "middle")


def test_yaw_mirror_symmetry_and_lead(wheelset):
    # mirror image: shift +y with yaw +psi on the left wheel is shift -y with yaw -psi on the
    # right one; the flanging wheel's contact leads its wheel centre, the other one's barely
    shifts = np.array([-8.0, -3.0, 3.0, 8.0])
    yaws = 0.002 * shifts
    table = contact_table(wheelset, shifts, yaw_rad=yaws)
    left, right = table.left.primary, table.right.primary
    np.testing.assert_allclose(left.y_wheel_mm, right.y_wheel_mm[::-1], atol=1e-8)
    np.testing.assert_allclose(left.contact_angle_rad, right.contact_angle_rad[::-1], atol=1e-9)
    np.testing.assert_allclose(left.x_track_mm, right.x_track_mm[::-1], atol=1e-8)
    np.testing.assert_allclose(table.roll_rad, -table.roll_rad[::-1], atol=1e-12)
    # lead of the contact ahead of the centre of its wheel circle (axial position d/2 + y_wheel)
    axial = wheelset.tape_circle_distance_mm / 2 + left.y_wheel_mm
    lead_left = left.x_track_mm + axial * np.sin(yaws)
    # x lead = r tan(delta) sin(psi) for the flange at 8 mm (r ~ 490, delta ~ 0.95, 16 mrad)
    expected = left.rolling_radius_mm[3] * np.tan(-left.contact_angle_rad[3]) * np.sin(yaws[3])
    assert lead_left[3] == pytest.approx(expected, rel=0.01)
    assert abs(lead_left[2]) < 1.0  # tread: tiny lead
    # yaw = 0 is exactly the 2D result; an absurd yaw is refused
    flat = contact_table(wheelset, shifts)
    again = contact_table(wheelset, shifts, yaw_rad=np.zeros(4))
    np.testing.assert_array_equal(flat.left.primary.y_wheel_mm, again.left.primary.y_wheel_mm)
    assert np.all(flat.left.primary.x_track_mm == 0.0)
    with pytest.raises(ValueError, match="yaw"):
        contact_table(wheelset, shifts, yaw_rad=0.5)


def test_min_gap_kernel_matches_numpy_reference():
    # the compiled minimum gap without yaw (min_gap_kernel) against the (N, M) numpy gaps, on
    # both sides, over shifts that put the flange on the gauge corner and rolls of both signs
    from wearcast.physics.contact import geometry as geo
    from wearcast.physics.contact.track_profiles import wheel_curve_from_height, wheelset_track
    from wearcast.physics.profiles.s1002 import s1002_height_mm

    wt = wheelset_track(wheel_curve_from_height(s1002_height_mm, (-55.0, 45.0)), "60E1",
                        1.0 / 40.0, 460.0)
    rng = np.random.default_rng(1)
    shift = rng.uniform(-17.0, 17.0, 300)
    roll = rng.uniform(-0.02, 0.02, 300)
    for side in geo._prepare(wt):
        got = geo._min_gap(side, shift, roll, np.zeros(300), 460.0)
        ref = geo._min_gap_numpy(side, shift, roll, np.zeros(300), 460.0)
        assert np.all(np.isfinite(got[0]))
        np.testing.assert_allclose(got[0], ref[0], rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(got[1], ref[1], rtol=1e-12, atol=1e-12)


def test_gap_beyond_the_rail_continues_the_rigid_gap(wheelset):
    # over the rail: rigid_wheel_gap's gap and pose; beyond its ends: finite, rising away from
    # the rail (the end faces continued), and the distance inside the rail's envelope is
    # positive exactly where there is rail below and moves with the shift continuously (the
    # wheel points and the rail are sampled at 0.05 mm; the distance is not quantised by them)
    shifts = np.arange(5.0, 9.0, 0.01)
    y, gap, roll = rigid_wheel_gap(wheelset, shifts, "left")
    y2, ext, roll2, inside = rigid_wheel_gap_beyond_rail(wheelset, shifts, "left")
    assert np.array_equal(y, y2) and np.array_equal(roll, roll2)
    on = np.isfinite(gap)
    assert np.array_equal(ext[on], gap[on])
    assert np.all(np.isfinite(ext))
    assert np.all(inside[~on] <= 1e-9) and np.all(inside[on] >= -1e-9)
    # at the gauge side the wheel's flange hangs beside the rail: the continued gap is large
    gauge = (~on) & (y[None, :] < -30.0)
    assert gauge.any() and np.all(ext[gauge] > 2.0)
    # the distance of one wheel point grows with every 0.01 mm of shift (1.1-9 mm per mm with
    # the roll of the climbing flange), never by a step of the samples' 0.05 mm and never
    # standing still between them, as a distance counted in samples would
    k = int(np.argmin(np.abs(y + 45.0)))
    step = np.diff(inside[:, k])
    assert np.all((step > 0.01) & (step < 0.1))


def _gap_beyond_rail_numpy(wt, shifts, side):
    """The numpy form :func:`rigid_wheel_gap_beyond_rail` had before its compiled kernel
    (``min_gap_kernel.gap_rows_no_yaw`` with ``beyond_rail``): every wheel point placed on the full
    (shift, point) grid again, the rail's end faces continued, and the reference gap taken as
    the median over the points with rail below of their gap less rigid_wheel_gap's."""
    import wearcast.physics.contact.geometry as geo

    y_wheel, gap, roll = rigid_wheel_gap(wt, shifts, side)
    shift, yaw = geo._pose_arrays(shifts, 0.0)
    chosen = geo._prepare(wt)[0 if side == "left" else 1]
    _, y, z = geo._points(chosen, shift, roll, yaw, wt.nominal_radius_mm, chosen.y_ws,
                          -chosen.z_ws, grid=True)
    ry, rz = chosen.rail_y, chosen.rail_z
    lo = int(np.searchsorted(ry, ry[0] + geo._END_FACE_MM))
    hi = int(np.searchsorted(ry, ry[-1] - geo._END_FACE_MM)) - 1
    slope_lo = (rz[lo] - rz[0]) / (ry[lo] - ry[0])
    slope_hi = (rz[-1] - rz[hi]) / (ry[-1] - ry[hi])
    z_rail = np.where(y < ry[0], rz[0] + slope_lo * (y - ry[0]),
                      np.where(y > ry[-1], rz[-1] + slope_hi * (y - ry[-1]),
                               np.interp(y, ry, rz)))
    reference = np.where(np.isfinite(gap), (z - z_rail) - gap, np.nan)
    gap0 = np.nanmedian(reference, axis=1)
    extended = np.where(np.isfinite(gap), gap, z - z_rail - gap0[:, None])
    return y_wheel, extended, roll, np.minimum(y - ry[0], ry[-1] - y)


@pytest.mark.parametrize("right_rail", [None, "60E2"])
@pytest.mark.parametrize("side", ["left", "right"])
def test_gap_beyond_the_rail_kernel_equals_its_numpy_form(right_rail, side):
    # the compiled pass (gap, end faces and distance inside the rail in one loop, referred to
    # the roll solve's gap) gives the numpy form's numbers: bit for bit over the rail and for
    # the distance, to rounding (1e-12 mm) beyond the rail, where the numpy form took its
    # reference gap as a median of (z - z_rail) - gap over the points; on S1002/60E1 and on
    # a track whose right rail is another profile (60E2), both wheels, shifts to the flange
    # climbing on either side and the table's coarse-start roll solve (N > 32)
    from wearcast.physics.profiles.measured import rail_curve

    wt = s1002_60e1()
    if right_rail is not None:
        wt = replace(wt, rail_right=rail_curve(right_rail), _cache={})
    shifts = np.arange(-12.0, 12.0 + 1e-9, 0.1)
    y, ext, roll, inside = rigid_wheel_gap_beyond_rail(wt, shifts, side)
    y_ref, ext_ref, roll_ref, inside_ref = _gap_beyond_rail_numpy(wt, shifts, side)
    assert np.array_equal(y, y_ref) and np.array_equal(roll, roll_ref)
    assert np.array_equal(inside, inside_ref)
    on = inside >= 0.0
    assert (~on).any() and on.any()
    assert np.array_equal(ext[on], ext_ref[on])
    np.testing.assert_allclose(ext[~on], ext_ref[~on], rtol=0.0, atol=1e-12)


@pytest.mark.parametrize("right_rail", [None, "60E2"])
def test_masked_contact_table_equals_its_numpy_and_scipy_form(right_rail, monkeypatch):
    # the curving contact table with the masked gap smoothing (the default), built from the
    # compiled gap beyond the rail and the compiled Gaussian filters, is the one built from
    # their numpy and scipy forms (the computation before them) to 1e-9 mm (1e-9 /mm for g'';
    # bit for bit on x86-64): S1002 on 60E1 at 1:40, and with a 60E2 right rail (both wheels'
    # tables)
    import wearcast.physics.curving_table as ct
    from tests.physics.test_gap_smoothing_kernel import _masked_gaussian_scipy
    from wearcast.physics import gap_smoothing as gs

    new = ct.build_contact_table(None, "60E1", 1.0 / 40.0, rail_right=right_rail,
                                 gap_smoothing="masked")
    monkeypatch.setattr(ct, "rigid_wheel_gap_beyond_rail", _gap_beyond_rail_numpy)
    monkeypatch.setattr(gs, "masked_gaussian", _masked_gaussian_scipy)
    old = ct.build_contact_table(None, "60E1", 1.0 / 40.0, rail_right=right_rail,
                                 gap_smoothing="masked")
    pairs = [(new, old)] if right_rail is None else [(new, old), (new.right, old.right)]
    for got, ref in pairs:
        assert got is not None and ref is not None
        for name in ("gap_mm", "gap2_per_mm", "rigid_rise_mm", "shift_mm"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=0.0,
                                       atol=1e-9, err_msg=name)
