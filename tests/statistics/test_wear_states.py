import json

import numpy as np
import pytest

from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM, wear_areas_mm2
from wearcast.statistics.wear_states import (
    WearStates,
    build_wear_states,
    join_regions,
    region_area_mm2,
    wear_curve_at_area,
    wear_curves_at_areas,
)

Y = np.asarray(DEFAULT_GRID_Y_MM)
SPLIT = -30.0


def _bump(centre, width):
    return np.exp(-0.5 * ((Y - centre) / width) ** 2)


def _fleet(n=200, seed=0):
    """Curves whose shape changes with area: the tread bump widens as it grows."""
    rng = np.random.default_rng(seed)
    a_f = rng.uniform(1, 30, n)
    a_t = rng.uniform(5, 150, n)
    curves = np.empty((n, Y.size))
    for i in range(n):
        f = _bump(-40, 3)
        t = _bump(0, 6 + a_t[i] / 15)
        f *= a_f[i] / region_area_mm2(Y, f, SPLIT, "flange")
        t *= a_t[i] / region_area_mm2(Y, t, SPLIT, "tread")
        curves[i] = f + t
    return curves, a_f, a_t


def test_region_area_matches_wear_curves_integral():
    rng = np.random.default_rng(4)
    w = rng.uniform(0, 1, (3, Y.size))
    w[1, 5] = np.nan
    for i in range(3):
        ref = wear_areas_mm2(Y, w[i], SPLIT)
        assert region_area_mm2(Y, w[i], SPLIT, "flange") == pytest.approx(ref.flange_mm2)
        assert region_area_mm2(Y, w[i], SPLIT, "tread") == pytest.approx(ref.tread_mm2)
    y_off = np.linspace(-58, 50, 100)  # split between grid points
    ref = wear_areas_mm2(y_off, np.sin(y_off) + 2, SPLIT)
    assert region_area_mm2(y_off, np.sin(y_off) + 2, SPLIT, "flange") == \
        pytest.approx(ref.flange_mm2)


def test_states_are_ordered_by_area_and_area_is_exact_when_interpolating():
    curves, a_f, a_t = _fleet()
    states = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT, n_states=8)
    for region in ("flange", "tread"):
        areas = states.region(region).areas_mm2
        assert areas.size == 8 and np.all(np.diff(areas) > 0)
        for target in (0.5, areas[0], 0.5 * (areas[2] + areas[3]), areas[-1]):
            curve, extrapolated = wear_curve_at_area(states, region, target)
            assert not extrapolated
            assert region_area_mm2(Y, curve, SPLIT, region) == pytest.approx(target, rel=1e-9)


def test_interpolation_between_states_and_zero_area():
    curves, a_f, a_t = _fleet()
    states = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT, n_states=5)
    tread = states.tread
    mid = 0.5 * (tread.areas_mm2[1] + tread.areas_mm2[2])
    curve, _ = wear_curve_at_area(states, "tread", mid)
    assert np.allclose(curve, 0.5 * (tread.curves_mm[1] + tread.curves_mm[2]))
    zero, extrapolated = wear_curve_at_area(states, "tread", 0.0)
    assert not extrapolated and np.all(zero == 0.0)
    # shapes really change with area: the tread state widens (seed 001 Fig. 9)
    mask = Y >= SPLIT
    first = tread.curves_mm[0][mask] / tread.areas_mm2[0]
    last = tread.curves_mm[-1][mask] / tread.areas_mm2[-1]
    assert first.max() > 1.3 * last.max()


def test_beyond_the_last_state_scales_its_shape_and_flags_it():
    curves, a_f, a_t = _fleet()
    states = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT, n_states=4)
    last_area = states.flange.areas_mm2[-1]
    curve, extrapolated = wear_curve_at_area(states, "flange", 2 * last_area)
    assert extrapolated
    assert np.allclose(curve, 2 * states.flange.curves_mm[-1])
    batch, flags = wear_curves_at_areas(states, "flange", [0.0, last_area, 3 * last_area])
    assert flags.tolist() == [False, False, True]
    with pytest.raises(ValueError, match="area_mm2"):
        wear_curve_at_area(states, "flange", -1.0)


def test_shape_outliers_do_not_enter_the_state():
    curves, a_f, a_t = _fleet(n=100)
    clean = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT, n_states=1)
    bad = curves.copy()
    for i in range(5):  # misaligned: tread wear moved to the field side
        t = _bump(35, 3)
        bad[i] = np.where(Y < SPLIT, bad[i], t * a_t[i] / region_area_mm2(Y, t, SPLIT, "tread"))
    dirty = build_wear_states(Y, bad, a_f, a_t, split_y_mm=SPLIT, n_states=1)
    assert dirty.tread.counts[0] <= 95
    at_35 = np.argmin(np.abs(Y - 35.0))
    naive = bad[:, at_35].mean()
    assert naive - clean.tread.curves_mm[0][at_35] > 0.3  # what averaging everything gives
    assert abs(dirty.tread.curves_mm[0][at_35] - clean.tread.curves_mm[0][at_35]) < 0.03


def test_round_trip_and_input_validation():
    curves, a_f, a_t = _fleet(n=40)
    states = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT)
    back = WearStates.from_dict(json.loads(json.dumps(states.to_dict())))
    assert np.array_equal(back.tread.curves_mm, states.tread.curves_mm)
    assert np.array_equal(back.flange.areas_mm2, states.flange.areas_mm2)
    with pytest.raises(ValueError, match="wear_curves_mm"):
        build_wear_states(Y, curves[:, :10], a_f, a_t)
    with pytest.raises(ValueError, match="flange_areas_mm2"):
        build_wear_states(Y, curves, a_f[:5], a_t)


def test_region_without_wear_has_no_states():
    curves, a_f, a_t = _fleet(n=30)
    states = build_wear_states(Y, curves, np.zeros(30), a_t, split_y_mm=SPLIT)
    assert states.flange.areas_mm2.size == 0
    curve, extrapolated = wear_curve_at_area(states, "flange", 0.0)
    assert not extrapolated and not curve.any()


def test_join_regions_only_touches_the_split_zone():
    flange = np.full((2, Y.size), 1.0)
    tread = np.full((2, Y.size), 3.0)
    joined = join_regions(Y, flange, tread, SPLIT, window_mm=4.0)
    assert np.all(joined[:, Y < SPLIT - 2.01] == 1.0)
    assert np.all(joined[:, Y > SPLIT + 2.01] == 3.0)
    near = np.abs(Y - SPLIT) <= 2.0
    assert np.all(np.diff(joined[0, near]) >= 0)  # monotone ramp instead of a step
    assert np.max(np.abs(np.diff(joined[0]))) < 2.0 / 2
