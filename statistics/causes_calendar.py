"""Calendar-true seasonal friction: the season of the days each measurement's wear accrued.

Part of the discrepancy finder's catalogue (:mod:`wearcast.statistics.causes`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics.cause_base import Cause, FinderData, _interval
from wearcast.statistics.residuals import day_numbers as _day_numbers
from wearcast.statistics.residuals import life_ids

Array = NDArray[np.float64]
OMEGA_PER_DAY = 2.0 * np.pi / 365.25


def season_features(frame: pd.DataFrame, mileage_km: Array) -> Array | None:
    """Calendar-true season features (n, 2): the mileage-weighted mean of (cos wt, sin wt)
    over the days each measurement's wear accrued, w = 2 pi / 365.25 days.

    For every life of a wheel (``life_ids``) the measurements are taken in date order and
    each interval between consecutive measurements contributes its mileage increment times
    the mean of cos/sin over its own dates (mileage uniform within an interval, so irregular
    intervals and changing daily mileages are followed). The first interval starts at the
    reprofiling: the ``reprofiled_on`` column when given, else its mileage divided by the
    life's median km/day (the fleet's median when the life has a single measurement).
    Repeated measurements (same date and mileage) add nothing. None without dates.
    """
    s = np.asarray(mileage_km, dtype=float)
    x = accrual_season_features(frame, s, s[:, None])
    return None if x is None else np.asarray(x[:, 0, :])


def accrual_season_features(frame: pd.DataFrame, mileage_km: Array, accrued: Array
                            ) -> Array | None:
    """Calendar-true season features (n, m, 2) weighted by what each interval accrued.

    accrued : (n, m) a quantity accrued since the life's reprofiling at each measurement
        (the mileage [km], or the baseline's predicted wear area of each region [mm^2])

    As ``season_features``, but each interval between consecutive measurements of a life
    contributes its increment of ``accrued`` (clipped at 0) times the mean of cos/sin over
    its own dates: the season multiplies the wear *rate*, so the wear a measurement carries
    is the season's mean over the interval dates weighted by the wear each interval added,
    A = sum_i (1 + a cos_i + b sin_i) dA_i. With wear linear in mileage (the hybrid model's
    law) dA_i is proportional to the interval's mileage; with a progression that is not
    (``discrepancy_progression``: the physics' running-in and profile evolution) the early
    intervals carry more of the wear than of the mileage, and mileage weights misplace the
    season. A column whose life accrues nothing gets 0. None without dates.
    """
    if "measured_on" not in frame.columns:
        return None
    day = _day_numbers(frame["measured_on"])
    if day is None:
        return None
    s = np.asarray(mileage_km, dtype=float)
    acc = np.asarray(accrued, dtype=float)
    life = life_ids(frame, s)
    reprofiled = _day_numbers(frame["reprofiled_on"]) if "reprofiled_on" in frame.columns \
        else None
    groups = pd.Series(np.arange(len(frame))).groupby(life).indices
    speeds: dict[Any, float] = {}
    for key, idx in groups.items():
        idx = np.asarray(idx)[np.lexsort((s[idx], day[idx]))]
        dd, ds = np.diff(day[idx]), np.diff(s[idx])
        ok = (dd > 0) & (ds > 0)
        if ok.any():
            speeds[key] = float(np.median(ds[ok] / dd[ok]))
    fleet_v = float(np.median(list(speeds.values()))) if speeds else 500.0
    w = OMEGA_PER_DAY
    out = np.zeros((len(frame), acc.shape[1], 2))
    for key, idx in groups.items():
        idx = np.asarray(idx)[np.lexsort((s[idx], day[idx]))]
        v = speeds.get(key, fleet_v)
        t_end = day[idx]
        start = t_end[0] - s[idx[0]] / max(v, 1e-9)
        if reprofiled is not None and np.isfinite(reprofiled[idx[0]]):
            start = float(reprofiled[idx[0]])
        t_start = np.concatenate([[start], t_end[:-1]])
        dur = t_end - t_start
        long_ = dur >= 1.0
        cos_m = np.where(long_, (np.sin(w * t_end) - np.sin(w * t_start))
                         / (w * np.where(long_, dur, 1.0)), np.cos(w * t_end))
        sin_m = np.where(long_, (np.cos(w * t_start) - np.cos(w * t_end))
                         / (w * np.where(long_, dur, 1.0)), np.sin(w * t_end))
        inc = np.maximum(np.diff(np.concatenate([np.zeros((1, acc.shape[1])), acc[idx]]),
                                 axis=0), 0.0)
        total = np.cumsum(inc, axis=0)
        safe = np.where(total > 0, total, 1.0)
        out[idx, :, 0] = np.where(total > 0, np.cumsum(inc * cos_m[:, None], axis=0) / safe,
                                  0.0)
        out[idx, :, 1] = np.where(total > 0, np.cumsum(inc * sin_m[:, None], axis=0) / safe,
                                  0.0)
    return out


class SeasonalFriction(Cause):
    code = "seasonal_friction"
    needs = ("measured_on",)
    covariate_name = "measured_on"
    # the season's contrast lies within the wheels (every wheel of a unit shares the
    # calendar): amplitude and phase by random-effects GLS (``finder_random_effects``)
    random_effects = True
    # and so within the cars: tested on the held-out error after a random log-scale per
    # vehicle (``finder_scoring.SCORE_METRIC``), where the cars' own rate factors, which no
    # season explains, no longer make most of the error (loop generator, amplitude 0.1, seed
    # 100: adjusted p 0.085 -> 0.03; the wheel-level oracle's t there is 5.6,
    # ``benchmarks/seasonal_oracle.py``)
    within_vehicle = True
    explanation = ("Rail-wheel friction, and with it the wear rate, follows the season (leaves, "
                   "moisture, temperature): rate x (1 + a cos wt + b sin wt), integrated over "
                   "the calendar days of every interval between measurements, each interval "
                   "weighted by the wear the model expects it to add, w = 2 pi / 365.25 days.")

    def skip_reason(self, data: FinderData) -> str | None:
        x = data.season()
        if x is None:
            return "needs a measured_on date on every measurement"
        dates = pd.to_datetime(data.frame["measured_on"])
        if (dates.max() - dates.min()).days < 180 or np.ptp(x[:, 0]) + np.ptp(x[:, 1]) < 0.2:
            return "measurement dates span less than half a year"
        return None

    def param_names(self) -> list[str]:
        return ["a_cos", "b_sin"]

    def features(self, data: FinderData, theta: Array) -> Array:
        """(n, region, 2): the season's (cos, sin) means weighted by the wear the baseline
        expects each interval to add to the region (``accrual_season_features``)."""
        x = data.season_by_region()
        return np.zeros((data.n, 2, 2)) if x is None else x

    def public(self) -> dict[str, Any]:
        a, b = (float(v) for v in self.theta_)
        return {"a_cos": a, "b_sin": b, "amplitude": float(np.hypot(a, b)),
                "peak_day_of_year": float((np.degrees(np.arctan2(b, a)) % 360.0)
                                          / 360.0 * 365.25)}

    def intervals(self) -> dict[str, dict[str, float]]:
        out = super().intervals()
        a, b = self.theta_
        amp = float(np.hypot(a, b))
        if self.cov_ is not None and amp > 0:
            grad = np.array([a, b]) / amp
            se = float(np.sqrt(max(float(grad @ self.cov_[2:4, 2:4] @ grad), 0.0)))
        else:
            se = float("nan")
        out["amplitude"] = _interval(amp, se, self.n_groups_)
        return out

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([float(params["a_cos"]), float(params["b_sin"])])
        return est

    def covariate(self, data: FinderData) -> NDArray[Any]:
        x = data.season()
        return x[:, 0] if x is not None else np.zeros(data.n)

    def describe(self) -> str:
        p = self.public()
        return (f"wear rate varies by about +/-{100 * p['amplitude']:.0f} % over the year, "
                f"highest near day {p['peak_day_of_year']:.0f}")
