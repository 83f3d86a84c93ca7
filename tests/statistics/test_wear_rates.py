import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.statistics.hybrid import RegionCalibration
from wearcast.statistics.wear_rates import WearRate, fit_ratio, fit_wear_rate, predictive_std


def _fan(rng, n, rate=2e-3, rel_spread=0.15):
    s = rng.uniform(5_000, 200_000, n)
    return s, rate * s * (1 + rel_spread * rng.standard_normal(n))


def test_recovers_a_known_rate_with_a_consistent_standard_error():
    rng = np.random.default_rng(0)
    s, a = _fan(rng, 400)
    fit = fit_wear_rate(s, a)
    assert fit.n == 400
    assert abs(fit.rate_mm2_per_km - 2e-3) < 3 * fit.std_error_mm2_per_km
    # spread of individual rates: 15 % of 2e-3, estimated from 400 points to ~10 %
    assert fit.spread_mm2_per_km == pytest.approx(0.15 * 2e-3, rel=0.12)
    assert fit.std_error_mm2_per_km == pytest.approx(fit.spread_mm2_per_km / 20, rel=0.2)


def test_corridor_holds_the_stated_fraction_of_new_measurements():
    # seed 001 Fig. 11: the corridor is where new measurements fall
    rng = np.random.default_rng(1)
    fit = fit_wear_rate(*_fan(rng, 500))
    s_new, a_new = _fan(rng, 5000)
    inside = (a_new >= fit.corridor(s_new, 0.05)) & (a_new <= fit.corridor(s_new, 0.95))
    # nominal 90 %; the MAD spread from 500 points is uncertain by ~5 %, which moves the
    # coverage by about +-1.5 points, and 5000 new points add +-0.5
    assert 0.86 < inside.mean() < 0.95
    assert fit.corridor(0.0, 0.9) == 0.0
    assert fit.corridor(1e5, 0.9) > fit.area_mm2(1e5) > fit.corridor(1e5, 0.1)


def test_huber_fit_resists_outliers():
    rng = np.random.default_rng(2)
    s, a = _fan(rng, 200, rel_spread=0.05)
    a[:10] *= 4.0  # 5 % grossly misaligned profiles
    fit = fit_wear_rate(s, a)
    naive = np.mean(a / s)
    assert abs(fit.rate_mm2_per_km - 2e-3) / 2e-3 < 0.02
    assert abs(naive - 2e-3) / 2e-3 > 0.10


def test_zero_mileage_rows_are_ignored_and_too_few_points_raise():
    fit = fit_wear_rate([0, 0, 1000, 2000, 3000], [5.0, 0.0, 1.0, 2.0, 3.0])
    assert fit.n == 3 and fit.rate_mm2_per_km == pytest.approx(1e-3)
    assert fit.spread_mm2_per_km == 0.0
    with pytest.raises(ValueError, match="mileage_km"):
        fit_wear_rate([0, 1000], [0, 1])


def test_round_trip_through_json():
    fit = fit_wear_rate(*_fan(np.random.default_rng(3), 50))
    assert WearRate.from_dict(json.loads(json.dumps(fit.to_dict()))) == fit


@settings(max_examples=30, deadline=None)
@given(scale=st.floats(1e-3, 1e3), seed=st.integers(0, 1000))
def test_fit_is_scale_equivariant(scale, seed):
    s, a = _fan(np.random.default_rng(seed), 30)
    base, scaled = fit_ratio(s, a), fit_ratio(s, a * scale)
    assert scaled.slope == pytest.approx(base.slope * scale, rel=1e-6)
    assert scaled.spread == pytest.approx(base.spread * scale, rel=1e-6)


def test_predictive_std_is_one_rule_for_rates_and_calibration_factors():
    # sqrt(spread² + se²): 3-4-5, absolute for a WearRate, relative for a region's c_s
    assert predictive_std(3.0, 4.0) == 5.0
    rate = WearRate(rate_mm2_per_km=1.0, std_error_mm2_per_km=0.4, spread_mm2_per_km=0.3, n=9)
    assert rate.predictive_std_mm2_per_km == pytest.approx(0.5, rel=1e-15)
    cal = RegionCalibration(c_s=2.0, c_s_rel_std_error=0.04, c_s_rel_spread=0.03, p_m=1.0,
                            rate=rate)
    assert cal.c_s_rel_predictive == pytest.approx(0.05, rel=1e-15)
