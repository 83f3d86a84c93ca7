"""The physics model's pure parts: measured vehicle means, the scale and its spread, the
prediction at a scale and the first limit crossing, on series whose answers are known."""

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics.physics_model import (
    VehicleSeries,
    calibrate_scale,
    continued,
    first_crossing,
    measured_vehicle_means,
    predict_position,
)
from wearcast.statistics.profile_parameters import WheelLimits

WHEELS = ("motor0-1L", "motor0-1R", "motor0-2L", "motor0-2R",
          "trailer1-1L", "trailer1-1R", "trailer1-2L", "trailer1-2R")


def _series(km_end: float = 4000.0) -> VehicleSeries:
    """Linear wear: every wheel loses Sd and qR at 1 mm / 1,000 km (leading axles 1.5x),
    Sh grows at 0.1 mm / 1,000 km."""
    km = np.linspace(0.0, km_end, 41)
    rate = np.array([1.5 if w[-2] == "1" else 1.0 for w in WHEELS]) * 1e-3
    sd = 32.5 - np.outer(km, rate)
    qr = 10.8 - np.outer(km, rate)
    sh = 28.0 + np.outer(km, np.full(8, 1e-4))
    return VehicleSeries(km, WHEELS, np.full(8, 1 / 8), sd, sh, qr)


def _measured(series: VehicleSeries, scales: dict[str, float]) -> pd.DataFrame:
    rows = []
    for vehicle, c in scales.items():
        for km in (0.0, 500.0, 1000.0, 1500.0):
            for j, _ in enumerate(WHEELS):
                rows.append({"vehicle_id": vehicle, "mileage_km": km,
                             **{q: float(np.interp(c * km, series.mileage_km,
                                                   getattr(series, q)[:, j]))
                                for q in ("sd_mm", "sh_mm", "qr_mm")}})
    return pd.DataFrame(rows)


def test_wheels_are_averaged_per_vehicle_and_mileage():
    frame = pd.DataFrame({"vehicle_id": ["A", "A", "A", "B"], "mileage_km": [100.0, 100.04, 200,
                                                                            100],
                          "sd_mm": [32.0, 31.0, 30.0, 29.0], "sh_mm": [28.0] * 4,
                          "qr_mm": [10.0, 9.0, 8.0, np.nan]})
    means = measured_vehicle_means(frame)
    assert list(means["vehicle"]) == ["A", "A"]        # B's only row has no qR
    assert means["FT_mm"].tolist() == [31.5, 30.0] and means["n_wheels"].tolist() == [2, 1]


def test_the_scale_and_its_spread_are_recovered():
    series = _series()
    measured = measured_vehicle_means(_measured(series, {"A": 1.0, "B": 1.5, "C": 2.0}))
    cal = calibrate_scale(series, measured)
    assert cal.per_vehicle == pytest.approx({"A": 1.0, "B": 1.5, "C": 2.0}, rel=1e-3)
    lo, mid, hi = cal.scale_p10_p50_p90
    assert lo < 1.5 < hi and mid == pytest.approx(1.5, rel=0.15)
    assert cal.log_sigma == pytest.approx(np.std(np.log([1.0, 1.5, 2.0]), ddof=1), rel=1e-3)
    one = calibrate_scale(series, measured[measured["vehicle"] == "B"])
    assert one.log_sigma == 0.0 and "no spread" in one.method


def test_prediction_follows_the_position_at_the_scale_and_from_a_measured_start():
    series = _series()
    pred = predict_position(series, [1.0, 2.0], np.array([1000.0]), bogie_type="motor",
                            axle=1, side="right")
    assert pred["sd_mm"][:, 0] == pytest.approx([32.5 - 1.5, 32.5 - 3.0])
    assert pred["vehicle_sd_mm"][0] == pytest.approx(32.5 - 1.25 * 2.0)
    start = predict_position(series, [1.0], np.array([1000.0]), bogie_type="trailer", axle=2,
                             side="left", start_km=500.0, start={"sd_mm": 30.0,
                                                                  "sh_mm": 28.0,
                                                                  "qr_mm": 9.0})
    assert start["sd_mm"][0, 0] == pytest.approx(30.0 - 1.0)
    with pytest.raises(ValueError, match="bogie_type"):
        predict_position(series, [1.0], np.array([1.0]), bogie_type="tender", axle=1,
                         side="left")


def test_past_the_run_the_series_goes_on_linearly_and_says_so():
    km = np.array([0.0, 1000.0, 2000.0, 3000.0, 4000.0])
    values, extrapolated = continued(km, 10.0 - km / 1000.0, np.array([2000.0, 6000.0]))
    assert values == pytest.approx([8.0, 4.0]) and extrapolated.tolist() == [False, True]


def test_the_first_limit_crossing_is_where_the_series_reaches_it():
    series = _series()
    # qR 10.8 -> 6.5 at 1.5 mm / 1,000 km on the leading motor wheel: 2,866.7 km at scale 1
    crossing = first_crossing(series, 1.0, bogie_type="motor", axle=1, side="left")
    assert crossing.governing_limit == "qr" and not crossing.extrapolated
    assert crossing.remaining_km == pytest.approx(4300.0 / 1.5, rel=1e-3)
    assert crossing.values["qr_mm"] == pytest.approx(6.5, abs=1e-6)
    # twice the scale: half the mileage; Sd governs with a high Sd limit
    assert first_crossing(series, 2.0, bogie_type="motor", axle=1, side="left",
                          ).remaining_km == pytest.approx(4300.0 / 3.0, rel=1e-3)
    sd = first_crossing(series, 1.0, bogie_type="trailer", axle=2, side="right",
                        limits=WheelLimits(sd_min_mm=30.0))
    assert sd.governing_limit == "sd" and sd.remaining_km == pytest.approx(2500.0, rel=1e-3)
    # beyond the run (4,000 km): extrapolated
    far = first_crossing(series, 1.0, bogie_type="trailer", axle=2, side="right")
    assert far.extrapolated and far.remaining_km == pytest.approx(4300.0, rel=1e-3)
    # a measured start already past a limit: 0 km
    past = first_crossing(series, 1.0, bogie_type="motor", axle=1, side="left", start_km=100.0,
                          start={"sd_mm": 21.0, "sh_mm": 28.0, "qr_mm": 9.0})
    assert past.remaining_km == 0.0 and past.governing_limit == "sd"
