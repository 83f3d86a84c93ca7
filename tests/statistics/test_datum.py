"""Datum placement of measured wheels and the lateral-datum-preserving wear alignment
(synthetic profiles; the real MiniProf files: tests/service/test_measured_wheels.py)."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import align_vertically
from wearcast.statistics.datum import MAX_TILT_RAD, place_on_datum
from wearcast.statistics.processing import process_profile


def _wheel(back_face: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """S1002 sampled like a MiniProf: a vertical back-face run at y = -70 from z = -20 up to
    the flange back, then the profile to the field side."""
    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y)
    if not back_face:
        return y[20:], z[20:]
    zb = np.linspace(-20.0, float(z[0]) - 0.3, 60)
    return np.r_[np.full(zb.size, -70.0), y], np.r_[zb, z]


def _rotate(y: np.ndarray, z: np.ndarray, theta: float) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.cos(theta), np.sin(theta)
    return c * y - s * z, s * y + c * z


def test_an_untilted_wheel_keeps_its_points_and_finds_its_back_face() -> None:
    y, z = _wheel()
    placed = place_on_datum(y, z)
    assert placed.back_face_found
    assert placed.back_face_y_mm == pytest.approx(-70.0, abs=1e-6)
    assert placed.tilt_applied_rad == 0.0
    np.testing.assert_array_equal(placed.y_mm, y)
    np.testing.assert_array_equal(placed.z_mm, z)
    assert placed.tape_circle_z_mm == pytest.approx(0.0, abs=1e-9)
    assert any(n.startswith("datum found") for n in placed.notes)


@pytest.mark.parametrize("theta", [3e-3, -4e-3])
def test_a_tilt_both_windows_prove_is_corrected(theta: float) -> None:
    y, z = _rotate(*_wheel(), -theta)  # the instrument sat tilted by -theta
    placed = place_on_datum(y, z)
    assert placed.tilt_applied_rad == pytest.approx(theta, abs=3e-4)
    order = np.argsort(placed.y_mm[60:])
    p = flange_parameters(placed.y_mm[60:][order], placed.z_mm[60:][order])
    assert (p.sd_mm, p.sh_mm, p.qr_mm) == pytest.approx((32.5, 28.0, 10.8), abs=0.03)


def test_a_large_tilt_is_corrected_only_up_to_its_bound() -> None:
    y, z = _rotate(*_wheel(), -20e-3)
    placed = place_on_datum(y, z)
    assert placed.tilt_applied_rad == pytest.approx(MAX_TILT_RAD)
    assert placed.tilt_back_face_rad == pytest.approx(20e-3, abs=1e-3)


def test_a_tilt_only_one_window_shows_is_not_corrected() -> None:
    y, z = _wheel()
    y = y.copy()
    y[:60] += np.linspace(0.0, 0.25, 60)[::-1]  # back face leans, profile does not
    placed = place_on_datum(y, z)
    assert abs(placed.tilt_back_face_rad) > 5e-3
    assert placed.tilt_applied_rad == 0.0
    assert any("do not both prove" in n for n in placed.notes)


def test_a_profile_without_back_face_says_its_datum_is_guessed() -> None:
    placed = place_on_datum(*_wheel(back_face=False))
    assert not placed.back_face_found
    assert any(n.startswith("datum guessed") for n in placed.notes)


def test_vertical_alignment_moves_only_vertically_and_keeps_sd_sh_qr() -> None:
    y = np.linspace(-70.0, 60.0, 651)
    worn = s1002_height_mm(y) - 0.8 * np.exp(-((y - 5.0) / 15.0) ** 2)  # tread wear
    z = worn - 0.8 * np.exp(-((0.0 - 5.0) / 15.0) ** 2) * 0 + 0.35  # instrument offset
    aligned = align_vertically(y, z)
    assert aligned.lateral_shift_mm == 0.0 and aligned.rotation_rad == 0.0
    assert aligned.vertical_shift_mm == pytest.approx(-0.35, abs=0.01)
    np.testing.assert_array_equal(aligned.y_mm, y)
    before, after = flange_parameters(y, z), flange_parameters(aligned.y_mm, aligned.z_mm)
    assert (after.sd_mm, after.sh_mm, after.qr_mm) == pytest.approx(
        (before.sd_mm, before.sh_mm, before.qr_mm), abs=1e-9)


def test_datum_processing_recovers_the_wear_and_reports_the_measured_parameters() -> None:
    y = np.linspace(-70.0, 60.0, 651)
    wear = 0.8 * np.exp(-((y - 5.0) / 15.0) ** 2)
    z_true = s1002_height_mm(y) - wear
    z_instr = z_true - float(np.interp(0.0, y, z_true))  # the instrument zeroes the tape circle
    p = process_profile(y, z_instr, alignment="datum")
    assert p.alignment == "datum" and p.lateral_shift_mm == 0.0 and p.rotation_rad == 0.0
    grid_wear = 0.8 * np.exp(-((p.grid_y_mm - 5.0) / 15.0) ** 2)
    assert np.nanmax(np.abs(p.wear_mm - grid_wear)) < 0.01
    raw = flange_parameters(y, z_instr)
    assert (p.parameters.sd_mm, p.parameters.sh_mm) == pytest.approx((raw.sd_mm, raw.sh_mm))
    assert p.reference_check is not None and p.reference_check.fits
