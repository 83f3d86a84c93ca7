"""Tests of wearcast.statistics.processing: the per-profile pipeline end to end."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.processing import ProcessedProfile, process_profile, process_profiles
from wearcast.statistics.profile_parameters import flange_parameters
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM, wear_areas_mm2


def _worn(y):
    """Known wear: 1.0 mm hollow tread wear and 0.6 mm on the flange face [mm]."""
    return 1.0 * np.exp(-0.5 * ((y - 5.0) / 11.0) ** 2) + 0.6 * np.exp(
        -0.5 * ((y + 38.0) / 3.0) ** 2
    )


def _measured(rng, n=400, noise_mm=0.01):
    """A worn S1002 as an instrument gives it: moved, noisy, field side first."""
    y = np.linspace(-70.0, 60.0, n)
    z = s1002_height_mm(y) - _worn(y)
    theta, dy, dz = rng.normal(0.0, 0.003), rng.normal(0.0, 1.0), rng.normal(0.0, 0.5)
    c, s = np.cos(theta), np.sin(theta)
    ym, zm = c * y - s * z + dy, s * y + c * z + dz + rng.normal(0.0, noise_mm, n)
    return ym[::-1], zm[::-1]


def test_new_s1002_gives_no_wear_and_its_parameters():
    y = np.linspace(-70.0, 60.0, 400)
    p = process_profile(y, s1002_height_mm(y))
    assert isinstance(p, ProcessedProfile)
    assert np.nanmax(np.abs(p.wear_mm)) < 0.01  # chords of 0.33 mm samples on R >= 12 mm
    assert abs(p.areas.flange_mm2) < 0.05 and abs(p.areas.tread_mm2) < 0.05
    assert (p.parameters.sd_mm, p.parameters.sh_mm, p.parameters.qr_mm) == pytest.approx(
        (32.5, 28.0, 10.8), abs=0.01
    )
    assert p.rms_residual_mm < 1e-3
    np.testing.assert_array_equal(p.grid_y_mm, DEFAULT_GRID_Y_MM)


def test_worn_moved_noisy_profile_gives_its_true_wear():
    # The truth: wear curve and areas of the worn profile before it was moved and noised.
    rng = np.random.default_rng(11)
    grid = DEFAULT_GRID_Y_MM
    true_wear = _worn(grid)
    true_areas = wear_areas_mm2(grid, true_wear)
    y_true = np.linspace(-70.0, 60.0, 4001)
    true_params = flange_parameters(y_true, s1002_height_mm(y_true) - _worn(y_true))
    for _ in range(5):
        p = process_profile(*_measured(rng))
        # 10 um noise; on the steep flank a 5 um lateral error is 15 um vertically
        assert np.nanmax(np.abs(p.wear_mm - true_wear)) < 0.06
        assert np.sqrt(np.nanmean((p.wear_mm - true_wear) ** 2)) < 0.02
        assert p.areas.tread_mm2 == pytest.approx(true_areas.tread_mm2, abs=0.3)  # of ~27
        assert p.areas.flange_mm2 == pytest.approx(true_areas.flange_mm2, abs=0.3)  # of ~5
        assert p.parameters.sd_mm == pytest.approx(true_params.sd_mm, abs=0.05)
        assert p.parameters.sh_mm == pytest.approx(true_params.sh_mm, abs=0.05)
        assert p.parameters.qr_mm == pytest.approx(true_params.qr_mm, abs=0.1)
        assert p.rms_residual_mm == pytest.approx(0.01, rel=0.5)


def test_orientation_notes_travel_with_the_result():
    rng = np.random.default_rng(5)
    y, z = _measured(rng)
    p = process_profile(-y, -z)
    assert any("downward" in note for note in p.notes)
    assert any("mirrored" in note for note in p.notes)
    assert p.areas.tread_mm2 > 20.0


def test_unusable_profile_raises_and_batch_keeps_going():
    rng = np.random.default_rng(3)
    good = _measured(rng)
    y = np.linspace(-0.07, 0.06, 400)  # metres
    with pytest.raises(ValueError, match="looks like metres"):
        process_profile(y, s1002_height_mm(y * 1000.0) / 1000.0)
    results = process_profiles([good, (y, y), good])
    assert isinstance(results[0], ProcessedProfile)
    assert isinstance(results[1], ValueError)
    assert isinstance(results[2], ProcessedProfile)
    assert results[0].areas == results[2].areas


def test_custom_grid_and_split_are_used():
    rng = np.random.default_rng(4)
    grid = np.linspace(-50.0, 40.0, 91)
    p = process_profile(*_measured(rng), grid_y_mm=grid, split_y_mm=-20.0)
    assert p.wear_mm.shape == grid.shape
    assert p.areas == wear_areas_mm2(grid, p.wear_mm, -20.0)
