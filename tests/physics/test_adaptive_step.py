"""The adaptive discrete step (seed 003 eq. 2-4): D_step bounds the depth normal to the profile."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wearcast.physics.adaptive_step import adaptive_step, deepest_normal_depth
from wearcast.physics.wear_distribution import apply_normal_wear


def test_step_removes_the_threshold_at_the_deepest_point() -> None:
    rate = np.array([0.0, 0.1, 0.4, 0.25])  # mm/km
    ds = adaptive_step(rate, 0.2)
    assert ds == pytest.approx(0.5)
    assert deepest_normal_depth(rate * ds) == pytest.approx(0.2)


def test_nothing_wears_means_no_bound() -> None:
    assert math.isinf(adaptive_step(np.zeros(5), 0.2))
    # a negative rate (a smoothing undershoot) removes nothing: it does not set the step
    assert math.isinf(adaptive_step(np.array([-0.1, 0.0]), 0.2))
    assert deepest_normal_depth(np.array([])) == 0.0


@pytest.mark.parametrize("bad", [0.0, -0.2, float("nan")])
def test_threshold_must_be_positive(bad: float) -> None:
    with pytest.raises(ValueError, match="depth_per_step_mm"):
        adaptive_step(np.ones(3), bad)


def test_a_steep_flank_is_bounded_normal_not_vertical() -> None:
    """On a 80 deg flank a normal depth d lowers z by d / cos 80 deg: the step is the one that
    removes D_step normal to the profile (seed 003 §4.3 removes the material in the normal
    direction), so the vertical change there is ~5.8 D_step, and the step is not shortened
    by the flank's slope."""
    y = np.linspace(-10.0, 10.0, 2001)
    slope = math.tan(math.radians(80.0))
    z = slope * y  # a straight flank
    rate = np.full_like(y, 0.1)  # mm/km, uniform normal wear
    ds = adaptive_step(rate, 0.2)
    assert ds == pytest.approx(2.0)
    worn = apply_normal_wear(y, z, rate * ds)
    inner = np.abs(y) < 5.0
    vertical = float(np.max((z - worn)[inner]))
    assert vertical == pytest.approx(0.2 / math.cos(math.radians(80.0)), rel=1e-3)


def test_one_step_for_a_whole_vehicle() -> None:
    """Wheels that share a step: the deepest point of any of them sets it."""
    rates = np.array([[0.1, 0.2], [0.05, 0.8]])
    assert adaptive_step(rates, 0.4) == pytest.approx(0.5)


def test_depth_below_is_normal_to_the_profile() -> None:
    """A flank worn 1 mm sideways (normal) at 80 deg differs by ~5.8 mm at a fixed y; its
    depth below the new profile is the 1 mm (wear_distribution.depth_below_mm), and a point
    above the profile has none."""
    from wearcast.physics.wear_distribution import depth_below_mm

    y = np.linspace(-10.0, 10.0, 201)
    z = math.tan(math.radians(80.0)) * y
    worn = apply_normal_wear(y, z, np.full_like(y, 1.0))
    inner = np.abs(y) < 5.0
    assert np.max((z - worn)[inner]) == pytest.approx(1.0 / math.cos(math.radians(80.0)),
                                                      rel=1e-3)
    assert depth_below_mm(y, z, worn)[inner] == pytest.approx(np.ones(inner.sum()), abs=0.02)
    assert np.all(depth_below_mm(y, z, z + 0.5) == 0.0)


def test_the_vertical_change_is_bounded_on_a_near_vertical_flank() -> None:
    """On z(y) a wheel step changes z by at most MAX_VERTICAL_STEP_FACTOR D_step (the
    representation's numerical bound); below acos(1 / factor) only the normal bound acts."""
    from wearcast.physics.adaptive_step import MAX_VERTICAL_STEP_FACTOR

    rate = np.full(5, 0.1)
    gentle = np.full(5, math.tan(math.radians(70.0)))   # slope factor 2.9 < 4
    steep = np.full(5, math.tan(math.radians(85.0)))    # slope factor 11.5 > 4
    assert adaptive_step(rate, 0.2, gentle) == pytest.approx(adaptive_step(rate, 0.2))
    ds = adaptive_step(rate, 0.2, steep)
    assert ds == pytest.approx(MAX_VERTICAL_STEP_FACTOR * 0.2 * math.cos(math.radians(85.0))
                               / 0.1)
    assert ds < adaptive_step(rate, 0.2)
