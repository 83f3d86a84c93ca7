"""Tests of wearcast.statistics.alignment: recovery of shift and rotation, robustness to wear."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import align_to_reference, reference_table


def _move(y, z, dy, dz, theta):
    """Apply the rigid motion the alignment must undo: rotate about the origin, translate."""
    c, s = np.cos(theta), np.sin(theta)
    return c * y - s * z + dy, s * y + c * z + dz


def _worn_s1002(n=400):
    """S1002 with 1.2 mm hollow tread wear and the flange face worn 2 mm laterally."""
    y = np.linspace(-70.0, 60.0, n)
    z_ref = s1002_height_mm(y)
    tread = 1.2 * np.exp(-0.5 * ((y - 5.0) / 11.0) ** 2)
    flank = (y > -55.0) & (y < -30.0)
    flange_face = np.where(flank, z_ref - s1002_height_mm(np.minimum(y + 2.0, 60.0)), 0.0)
    flange_face = np.clip(flange_face, 0.0, None)
    return y, z_ref - tread - flange_face


def _recovered(aligned, dy, dz, theta):
    """Residual motion: the alignment composed with the applied motion should be identity."""
    y0 = np.array([-60.0, 0.0, 50.0])
    z0 = s1002_height_mm(y0)
    y1, z1 = _move(y0, z0, dy, dz, theta)
    c, s = np.cos(aligned.rotation_rad), np.sin(aligned.rotation_rad)
    y2 = c * y1 - s * z1 + aligned.lateral_shift_mm
    z2 = s * y1 + c * z1 + aligned.vertical_shift_mm
    return np.abs(y2 - y0).max(), np.abs(z2 - z0).max(), abs(aligned.rotation_rad + theta)


def test_reference_table_matches_s1002():
    table = reference_table(s1002_height_mm)
    y = np.linspace(-69.0, 60.0, 1001)
    # 0.01 mm tabulation: linear interpolation error <= h^2/(8 R) = 1e-6 mm for R >= 12 mm,
    # up to 1.4e-5 mm in the 0.01 mm cells straddling the slope kinks between sections
    np.testing.assert_allclose(table.height_mm(y), s1002_height_mm(y), atol=2e-5)
    # ... except in the last mm before y = -70, where the flange back turns vertical
    y_back = np.linspace(-70.0, -69.0, 101)
    np.testing.assert_allclose(table.height_mm(y_back), s1002_height_mm(y_back), atol=1e-4)
    assert np.isnan(table.height_mm(np.array([-75.0, 65.0]))).all()


def test_unworn_profile_gives_zero_residual_and_no_motion():
    y = np.linspace(-70.0, 60.0, 400)
    aligned = align_to_reference(y, s1002_height_mm(y))
    assert aligned.rms_residual_mm < 1e-5
    assert abs(aligned.lateral_shift_mm) < 1e-5
    assert abs(aligned.vertical_shift_mm) < 1e-5
    assert abs(aligned.rotation_rad) < 1e-7
    assert aligned.used_windows
    assert aligned.n_used > 50


def test_moved_unworn_profile_is_recovered_exactly():
    y = np.linspace(-70.0, 60.0, 400)
    ym, zm = _move(y, s1002_height_mm(y), 1.7, -0.8, 0.004)
    aligned = align_to_reference(ym, zm)
    err_y, err_z, err_theta = _recovered(aligned, 1.7, -0.8, 0.004)
    assert err_y < 1e-3 and err_z < 1e-3 and err_theta < 1e-5
    assert aligned.rms_residual_mm < 1e-3
    inside = (aligned.y_mm > -69.0) & (aligned.y_mm < 60.0)
    np.testing.assert_allclose(
        aligned.z_mm[inside], s1002_height_mm(aligned.y_mm[inside]), atol=2e-3
    )


def test_worn_moved_noisy_profile_is_recovered():
    # Worn S1002 (1.2 mm tread, flange face -2 mm) moved by 2 mm, 1 mm and 5 mrad, plus
    # 20 um measurement noise (MiniProf resolution class). The fit windows do not wear, so
    # the motion is recovered to the noise: measured errors ~ 5 um, 2e-5 rad.
    rng = np.random.default_rng(7)
    y, z = _worn_s1002()
    ym, zm = _move(y, z, -2.0, 1.0, -0.005)
    zm = zm + rng.normal(0.0, 0.02, zm.size)
    aligned = align_to_reference(ym, zm)
    err_y, err_z, err_theta = _recovered(aligned, -2.0, 1.0, -0.005)
    assert err_y < 0.02 and err_z < 0.02 and err_theta < 1e-4
    assert aligned.rms_residual_mm == pytest.approx(0.02, rel=0.3)


def test_wear_does_not_pull_the_alignment():
    # Without motion, a worn profile must stay where it is: the fit ignores the worn parts.
    y, z = _worn_s1002()
    aligned = align_to_reference(y, z)
    assert abs(aligned.lateral_shift_mm) < 1e-3
    assert abs(aligned.vertical_shift_mm) < 1e-3
    assert abs(aligned.rotation_rad) < 1e-5


def test_outliers_in_the_windows_are_downweighted():
    y = np.linspace(-70.0, 60.0, 400)
    z = s1002_height_mm(y)
    z_bad = z.copy()
    z_bad[(y > 45.0) & (y < 47.0)] += 1.5  # debris on the field-side end
    robust = align_to_reference(y, z_bad)
    plain = align_to_reference(y, z_bad, robust=False)
    assert abs(robust.vertical_shift_mm) < 0.01
    assert abs(plain.vertical_shift_mm) > 2 * abs(robust.vertical_shift_mm)


def test_partial_profile_falls_back_to_all_points():
    y = np.linspace(-50.0, 35.0, 300)
    ym, zm = _move(y, s1002_height_mm(y), 0.5, 0.3, 0.0)
    aligned = align_to_reference(ym, zm)
    assert not aligned.used_windows
    err_y, err_z, _ = _recovered(aligned, 0.5, 0.3, 0.0)
    assert err_y < 1e-3 and err_z < 1e-3


def test_aligned_profile_stays_ascending():
    y = np.linspace(-70.0, 60.0, 400)
    ym, zm = _move(y, s1002_height_mm(y), 0.0, 0.0, 0.02)
    aligned = align_to_reference(ym, zm)
    assert np.all(np.diff(aligned.y_mm) > 0.0)


@settings(max_examples=30, deadline=None)
@given(
    dy=st.floats(-3.0, 3.0),
    dz=st.floats(-2.0, 2.0),
    theta=st.floats(-0.01, 0.01),
)
def test_any_small_motion_is_undone(dy, dz, theta):
    # Property: the alignment inverts any rigid motion of the size met in practice
    # (MiniProf placement: a few mm, < 0.6 degree).
    y, z = _worn_s1002()
    ym, zm = _move(y, z, dy, dz, theta)
    aligned = align_to_reference(ym, zm)
    err_y, err_z, err_theta = _recovered(aligned, dy, dz, theta)
    assert err_y < 0.01 and err_z < 0.01 and err_theta < 1e-4
