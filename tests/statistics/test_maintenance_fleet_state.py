"""Fleet state: turning detection, remaining km from a wheel's own history, dates, spreads."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics.maintenance.fleet_state import (
    Remaining,
    estimate_km_per_day,
    fleet_state,
    history_remaining,
)
from wearcast.statistics.maintenance.limits import FleetLimits

D0 = dt.date(2026, 1, 1)


def _rows(wheel, vehicle, axle, side, mileages, sd, sh, qr, diam=None, days_per_km=0.002):
    out = []
    for i, s in enumerate(mileages):
        out.append({"wheel_id": wheel, "vehicle_id": vehicle, "bogie_type": "motor",
                    "axle": axle, "side": side, "mileage_km": float(s),
                    "measured_on": D0 + dt.timedelta(days=round(s * days_per_km)),
                    "sd_mm": sd[i], "sh_mm": sh[i], "qr_mm": qr[i],
                    "diameter_mm": None if diam is None else diam[i], "measurement_id": i})
    return out


def test_remaining_from_own_history_exact_on_noise_free_wear():
    s = np.array([120_000.0, 150_000.0, 180_000.0, 210_000.0])
    sd = 31.0 - 2e-5 * (s - 100_000.0)
    rem = history_remaining(s, sd, "sd", FleetLimits())
    assert rem.source == "history" and rem.n_points == 4
    assert rem.p50 == pytest.approx((sd[-1] - 22.0) / 2e-5, rel=1e-9)
    assert rem.p10 < rem.p50 < rem.p90
    # two points: the spread is the instrument repeatability alone
    two = history_remaining(s[:2], sd[:2], "sd", FleetLimits())
    assert two.p10 < two.p50 < two.p90
    # Sh grows towards a maximum
    sh = 28.0 + 1e-5 * (s - 100_000.0)
    rem_sh = history_remaining(s, sh, "sh", FleetLimits())
    assert rem_sh.p50 == pytest.approx((36.0 - sh[-1]) / 1e-5, rel=1e-9)


def test_crossed_and_no_trend():
    s = np.array([1.0e5, 1.2e5])
    crossed = history_remaining(s, np.array([22.5, 21.7]), "sd", FleetLimits())
    assert (crossed.p10, crossed.p50, crossed.source) == (0.0, 0.0, "crossed")
    assert crossed.margin_mm == pytest.approx(-0.3)
    flat = history_remaining(s, np.array([30.0, 30.0]), "sd", FleetLimits())
    assert math.isinf(flat.p50)


def test_turning_detected_history_restarts_and_dates():
    s_old = [50_000, 100_000, 150_000]
    s_new = [170_000, 200_000, 230_000]
    sd = [30.0, 27.0, 24.0, 32.4, 31.8, 31.2]  # turned between 150,000 and 170,000
    sh = [28.3, 28.8, 29.3, 28.0, 28.2, 28.4]
    qr = [10.0, 9.5, 9.0, 10.8, 10.6, 10.4]
    rows = _rows("W1", "V1", 1, "left", s_old + s_new, sd, sh, qr,
                 diam=[900, 899.5, 899.0, 893.0, 892.8, 892.6])
    state = fleet_state(pd.DataFrame(rows))
    w = state.wheels[0]
    assert w.turned_at_km == 170_000 and w.n_since_turning == 3
    assert w.remaining["sd"].p50 == pytest.approx((31.2 - 22.0) / 2e-5, rel=1e-6)
    assert w.km_per_day == pytest.approx(500.0, rel=0.01) and w.km_per_day_source == "estimated"
    p50 = w.remaining["sd"].p50
    assert w.dates["sd"]["p50"] == w.measured_on + dt.timedelta(days=p50 / w.km_per_day)
    assert w.remaining["diameter"].source == "history"


def test_vehicle_attribute_model_forecast_and_spreads():
    rows = _rows("A", "V2", 1, "left", [10_000], [32.0], [28.1], [10.7], diam=[900.0])
    rows += _rows("B", "V2", 1, "right", [10_000], [32.0], [28.1], [10.7], diam=[898.5])
    seen = []

    def model(state):
        seen.append(state.wheel_id)
        return {"sd": Remaining(1e5, 2e5, 3e5, "model")}

    state = fleet_state(pd.DataFrame(rows), km_per_day={"V2": 400.0}, model_forecast=model)
    assert sorted(seen) == ["A", "B"]
    a = state.wheels[0]
    assert a.remaining["sd"].source == "model" and a.km_per_day == 400.0
    assert a.remaining["sh"].source == "unknown"
    assert a.first("p10") == (1e5, "sd")
    [spread] = [d for d in state.diameter_spreads if d.scope == "axle"]
    assert spread.spread_mm == pytest.approx(1.5) and spread.wheel_ids == ("A", "B")
    assert not fleet_state(pd.DataFrame(rows), FleetLimits(axle_diameter_difference_mm=2.0)
                           ).diameter_spreads


def test_km_per_day_needs_two_dates():
    frame = pd.DataFrame(_rows("A", "V", 1, "left", [1000], [32.0], [28.0], [10.8]))
    assert estimate_km_per_day(frame) is None
    with pytest.raises(ValueError, match="limits.sd_min_mm"):
        FleetLimits.from_overrides({"sd_min_mm": -1})
