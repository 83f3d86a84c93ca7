import dataclasses
import json

import numpy as np
import pytest

from tests.statistics import _reprofiling_helpers as fixtures
from wearcast.statistics.hybrid_prediction import start_areas
from wearcast.statistics.profile_parameters import WheelLimits
from wearcast.statistics.reprofiling import reprofiling_mileage

Y, SPLIT, ROUTE, TANGENT = fixtures.Y, fixtures.SPLIT, fixtures.ROUTE, fixtures.TANGENT
_table, _model = fixtures.table, fixtures.model


KW = {"bogie_type": "motor", "axle": 1, "side": "right"}


def test_quantiles_are_ordered_and_the_governing_limit_is_met():
    res = reprofiling_mileage(_model(), ROUTE, _table(), **KW)
    assert res.reached and res.reason is None
    assert 0 < res.mileage_p10_km < res.mileage_p50_km < res.mileage_p90_km
    value = {"sd": res.sd_mm - 22.0, "sh": 36.0 - res.sh_mm, "qr": res.qr_mm - 6.5}
    assert value[res.governing_limit] == pytest.approx(0.0, abs=1e-3)
    assert all(v >= -1e-3 for v in value.values())
    json.dumps(res.to_dict())


def test_mileage_is_inversely_proportional_to_the_rate():
    # areas grow as c_s P s, and the profile depends on areas only: doubling every c_s must
    # halve the reprofiling mileage exactly
    base = reprofiling_mileage(_model(), ROUTE, _table(), **KW)
    previous = base.mileage_p50_km
    for factor in (1.5, 2.0, 4.0):
        res = reprofiling_mileage(_model(2e-5 * factor, 5e-6 * factor), ROUTE, _table(), **KW)
        assert res.mileage_p50_km == pytest.approx(base.mileage_p50_km / factor, rel=1e-5)
        assert res.mileage_p50_km < previous
        assert res.governing_limit == base.governing_limit
        previous = res.mileage_p50_km


def test_no_wear_gives_infinity_with_a_reason():
    res = reprofiling_mileage(_model(), TANGENT, _table(tread_tangent=0.0), **KW)
    assert not res.reached and res.mileage_p10_km == np.inf
    assert "zero wear rate" in res.reason
    assert res.to_dict()["mileage_p50_km"] is None
    slow = reprofiling_mileage(_model(), TANGENT, _table(), horizon_km=1_000.0, **KW)
    assert not slow.reached and "horizon" in slow.reason


def test_remaining_mileage_starts_from_the_measured_state():
    model = _model()
    full = reprofiling_mileage(model, ROUTE, _table(), **KW)
    s0 = 0.4 * full.mileage_p50_km
    start = {r: full.rates_mm2_per_km[r] * s0 for r in ("flange", "tread")}
    rest = reprofiling_mileage(model, ROUTE, _table(), start_areas=start, **KW)
    assert rest.mileage_p50_km == pytest.approx(full.mileage_p50_km - s0, rel=1e-5)
    assert rest.equivalent_mileage_km["flange"] == pytest.approx(s0)
    worn = {"flange": 1e4, "tread": 0.0}
    done = reprofiling_mileage(model, ROUTE, _table(), start_areas=worn, **KW)
    assert done.mileage_p50_km == 0.0 and "already" in done.reason


def test_limits_are_configurable_and_validated():
    strict = reprofiling_mileage(_model(), ROUTE, _table(), limits=WheelLimits(qr_min_mm=9.5),
                                 **KW)
    loose = reprofiling_mileage(_model(), ROUTE, _table(), **KW)
    assert strict.mileage_p50_km <= loose.mileage_p50_km
    with pytest.raises(ValueError, match="limits.sd_max_mm"):
        reprofiling_mileage(_model(), ROUTE, _table(), limits={"sd_max_mm": 30.0}, **KW)
    with pytest.raises(ValueError, match="start_areas.web"):
        reprofiling_mileage(_model(), ROUTE, _table(), start_areas={"web": 1.0}, **KW)
    with pytest.raises(ValueError, match="start_areas.tread: must be finite"):
        reprofiling_mileage(_model(), ROUTE, _table(), start_areas={"tread": -1.0}, **KW)


def test_start_areas_are_the_measured_ones_or_the_new_profile():
    # one rule for predict's start_areas_mm2 and reprofiling's start_areas
    assert start_areas(None, "start_areas") == {"flange": 0.0, "tread": 0.0}
    assert start_areas({"tread": 3.5}, "x") == {"flange": 0.0, "tread": 3.5}
    for bad in ({"tread": float("nan")}, {"flange": None}, {"flange": -0.1}):
        with pytest.raises(ValueError, match="start_areas_mm2.(tread|flange): must be finite"):
            start_areas(bad, "start_areas_mm2")
    with pytest.raises(ValueError, match="start_areas_mm2.web: must be one of"):
        start_areas({"web": 1.0}, "start_areas_mm2")


def test_wider_rate_uncertainty_widens_the_band_not_the_median():
    narrow = reprofiling_mileage(_model(rel=0.05), ROUTE, _table(), **KW)
    wide = reprofiling_mileage(_model(rel=0.2), ROUTE, _table(), **KW)
    assert wide.mileage_p50_km == pytest.approx(narrow.mileage_p50_km, rel=1e-6)
    assert wide.mileage_p10_km < narrow.mileage_p10_km
    assert wide.mileage_p90_km > narrow.mileage_p90_km
    assert dataclasses.is_dataclass(wide)


def test_high_rail_wheel_is_governed_by_the_flange_and_tangent_track_by_the_tread():
    # right wheel in a left curve runs on the high rail: flange wear, qR governs; the left
    # (low-rail) wheel lasts longer; on tangent track only the tread wears and Sh governs
    right = reprofiling_mileage(_model(), ROUTE, _table(), **KW)
    left = reprofiling_mileage(_model(), ROUTE, _table(), **{**KW, "side": "left"})
    tangent = reprofiling_mileage(_model(), TANGENT, _table(), **KW)
    assert right.governing_limit == "qr"
    assert left.mileage_p50_km > right.mileage_p50_km
    assert tangent.governing_limit == "sh" and tangent.rates_mm2_per_km["flange"] == 0.0


def test_a_wheel_measured_past_a_limit_has_no_mileage_left():
    measured = {"sd_mm": 30.0, "sh_mm": 28.4, "qr_mm": 5.43}  # qR below 6.5 mm
    res = reprofiling_mileage(_model(), ROUTE, _table(), start_parameters=measured, **KW)
    assert (res.mileage_p10_km, res.mileage_p50_km, res.mileage_p90_km) == (0.0, 0.0, 0.0)
    assert res.governing_limit == "qr"
    assert res.crossed_limits == pytest.approx({"qr": 6.5 - 5.43})
    assert "qR 5.43 mm < 6.5 mm by 1.07 mm" in res.reason
    two = reprofiling_mileage(_model(), ROUTE, _table(),
                              start_parameters={"sd_mm": 21.0, "sh_mm": 36.5, "qr_mm": 7.0},
                              **KW)
    assert set(two.crossed_limits) == {"sd", "sh"} and two.governing_limit == "sd"


def test_the_prediction_follows_the_measured_parameters():
    model = _model()
    base = reprofiling_mileage(model, ROUTE, _table(), **KW)
    # the model's own parameters at the start: the same answer
    from wearcast.statistics.hybrid_profiles import parameters_at_areas

    p0, _ = parameters_at_areas(model, np.array([0.0]), np.array([0.0]))
    same = dict(zip(("sd_mm", "sh_mm", "qr_mm"), p0[0].tolist(), strict=True))
    again = reprofiling_mileage(model, ROUTE, _table(), start_parameters=same, **KW)
    assert again.mileage_p50_km == pytest.approx(base.mileage_p50_km, rel=1e-6)
    # a measured start 2 mm closer to the governing limit reaches it earlier, at a value on it
    closer = dict(same)
    key = {"sd": "sd_mm", "qr": "qr_mm", "sh": "sh_mm"}[base.governing_limit]
    closer[key] += 2.0 if key == "sh_mm" else -2.0
    early = reprofiling_mileage(model, ROUTE, _table(), start_parameters=closer, **KW)
    assert early.mileage_p50_km < base.mileage_p50_km
    limit = {"sd_mm": 22.0, "sh_mm": 36.0, "qr_mm": 6.5}[key]
    assert getattr(early, key) == pytest.approx(limit, abs=0.05)
    with pytest.raises(ValueError, match="start_parameters.qr_mm"):
        reprofiling_mileage(model, ROUTE, _table(), start_parameters={"sd_mm": 30.0,
                                                                      "sh_mm": 28.0}, **KW)
