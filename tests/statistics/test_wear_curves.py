"""Tests of wearcast.statistics.wear_curves: w(y) = z_ref - z_worn and the wear areas."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.wear_curves import (
    DEFAULT_GRID_Y_MM,
    DEFAULT_SPLIT_Y_MM,
    reference_on_grid,
    wear_areas_mm2,
    wear_curve_mm,
)


def test_default_grid_covers_flange_flank_and_tread():
    grid = DEFAULT_GRID_Y_MM
    assert grid[0] <= -57.0 and grid[-1] >= 50.0  # tip (-55) with margin, tread to +50
    np.testing.assert_allclose(np.diff(grid), 0.5)
    assert DEFAULT_SPLIT_Y_MM == -30.0  # seed 001 §3.1
    assert -55.0 in grid and 0.0 in grid and -30.0 in grid


def test_reference_on_grid_is_s1002():
    np.testing.assert_allclose(
        reference_on_grid(DEFAULT_GRID_Y_MM), s1002_height_mm(DEFAULT_GRID_Y_MM), atol=2e-5
    )


def test_unworn_profile_has_zero_wear():
    y = np.linspace(-70.0, 60.0, 1301)
    wear = wear_curve_mm(y, s1002_height_mm(y))
    # linear interpolation of 0.1 mm samples: |w| <= h^2/(8 R_min) ~ 1e-4 mm
    assert np.nanmax(np.abs(wear)) < 2e-4
    assert np.isfinite(wear).all()


def test_known_wear_is_returned_and_nan_outside_data():
    y = np.linspace(-56.0, 40.0, 961)
    w_true = 0.8 * np.exp(-0.5 * ((y - 5.0) / 10.0) ** 2)
    wear = wear_curve_mm(y, s1002_height_mm(y) - w_true)
    grid = DEFAULT_GRID_Y_MM
    covered = (grid >= -56.0) & (grid <= 40.0)
    assert np.isnan(wear[~covered]).all()
    expected = 0.8 * np.exp(-0.5 * ((grid[covered] - 5.0) / 10.0) ** 2)
    np.testing.assert_allclose(wear[covered], expected, atol=2e-4)


def test_constant_wear_areas_are_exact():
    grid = DEFAULT_GRID_Y_MM
    wear = np.full(grid.shape, 0.5)
    areas = wear_areas_mm2(grid, wear)
    assert areas.flange_mm2 == pytest.approx(0.5 * (-30.0 + 58.0))
    assert areas.tread_mm2 == pytest.approx(0.5 * (50.0 + 30.0))
    assert areas.total_mm2 == pytest.approx(0.5 * 108.0)


def test_split_between_grid_points_is_cut_linearly():
    grid = np.array([-40.0, -31.0, -29.0, -20.0])
    wear = np.array([0.0, 1.0, 3.0, 3.0])
    areas = wear_areas_mm2(grid, wear, split_y_mm=-30.0)
    # w(-30) = 2 by linear interpolation
    assert areas.flange_mm2 == pytest.approx(0.5 * 9.0 * 1.0 + 0.5 * (1.0 + 2.0) * 1.0)
    assert areas.tread_mm2 == pytest.approx(0.5 * (2.0 + 3.0) * 1.0 + 3.0 * 9.0)
    assert areas.total_mm2 == pytest.approx(np.trapezoid(wear, grid))


def test_areas_sum_to_the_whole_integral_for_any_split():
    rng = np.random.default_rng(2)
    grid = DEFAULT_GRID_Y_MM
    wear = rng.uniform(0.0, 2.0, grid.size)
    total = np.trapezoid(wear, grid)
    for split in (-70.0, -58.0, -41.3, -30.0, 0.25, 50.0, 80.0):
        areas = wear_areas_mm2(grid, wear, split)
        assert areas.total_mm2 == pytest.approx(total)
    assert wear_areas_mm2(grid, wear, -70.0).flange_mm2 == 0.0
    assert wear_areas_mm2(grid, wear, 80.0).tread_mm2 == 0.0


def test_areas_skip_nan_intervals():
    grid = np.arange(-40.0, -19.0, 1.0)
    wear = np.ones(grid.size)
    wear[[0, 1, 2]] = np.nan  # no data on -40..-38: intervals touching them are left out
    areas = wear_areas_mm2(grid, wear, -30.0)
    assert areas.flange_mm2 == pytest.approx(7.0)  # -37 .. -30
    assert areas.tread_mm2 == pytest.approx(10.0)


def test_negative_wear_lowers_the_area():
    # material added (w < 0, e.g. plastic flow) counts negative: the integral is signed
    grid = DEFAULT_GRID_Y_MM
    areas = wear_areas_mm2(grid, np.full(grid.shape, -0.1))
    assert areas.tread_mm2 < 0.0 and areas.flange_mm2 < 0.0


def test_mismatched_lengths_are_refused():
    with pytest.raises(ValueError, match="differ in length"):
        wear_areas_mm2(np.arange(5.0), np.arange(4.0))
