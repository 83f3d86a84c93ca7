"""Fleets that record only the flange parameters Sd, Sh, qR (no profiles).

Each parameter p of a wheel or vehicle is regressed linearly on mileage since reprofiling,
p(s) = p_0 + b s. Seed 003 §5.2 reports that on the Aosta line FT (Sd) and QR (qR) "decrease
almost linearly" while FH (Sh) "remains approximately constant" (Table 2).

Intercept: by default it is FIXED at the new-profile value (S1002: Sd 32.5, Sh 28.0,
qR 10.8 mm, docs/conventions.md), because each series starts at reprofiling, where the profile is
the
nominal one (seed 003 Table 2 starts every vehicle at exactly these values), and because with
the three or four points a vehicle typically has, a free intercept roughly doubles the
slope's variance. Rows at mileage 0 then carry no information and are left out of the fit
and its degrees of freedom. ``intercept='fitted'`` estimates it instead (use it when the
series does not start at a reprofiling or the reference profile is unknown).

The limit-crossing mileage s* = (L - p_0) / b is given as P10/P50/P90 from the slope's
Student-t uncertainty (fixed intercept: exact quantiles of L/b_q) or by the delta method on
(p_0, b) (fitted intercept). The governing limit is the one with the smallest P50 mileage.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.stats import t as student_t

from wearcast.statistics.json_values import finite_or_none
from wearcast.statistics.profile_parameters import DEFAULT_LIMITS, WheelLimits

#: S1002 new-profile values [mm] (docs/conventions.md "Profile parameters and limits"; EN 13715).
NEW_PROFILE_VALUES = {"sd_mm": 32.5, "sh_mm": 28.0, "qr_mm": 10.8}
PARAMETERS = ("sd_mm", "sh_mm", "qr_mm")
LIMIT_NAME = {"sd_mm": "sd", "sh_mm": "sh", "qr_mm": "qr"}


def _limit_for(parameter: str, limits: WheelLimits) -> tuple[float, int]:
    """(limit [mm], direction): -1 = minimum limit (reached when falling), +1 = maximum."""
    if parameter == "sd_mm":
        return limits.sd_min_mm, -1
    if parameter == "sh_mm":
        return limits.sh_max_mm, +1
    if parameter == "qr_mm":
        return limits.qr_min_mm, -1
    raise ValueError(f"parameter: must be one of {PARAMETERS}, got {parameter!r}")


@dataclass(frozen=True)
class ParameterTrend:
    """Linear trend p(s) = intercept + slope s of one flange parameter.

    Attributes
    ----------
    parameter : 'sd_mm', 'sh_mm' or 'qr_mm'
    intercept_mm, slope_mm_per_km : fitted line [mm], [mm/km]
    intercept_std_error_mm, slope_std_error_mm_per_km : standard errors (0 for a fixed
        intercept)
    covariance : covariance of (intercept, slope)
    residual_std_mm : residual standard deviation [mm]
    n, dof : points used, residual degrees of freedom
    intercept_fixed : whether the intercept was fixed at the new-profile value
    """

    parameter: str
    intercept_mm: float
    slope_mm_per_km: float
    intercept_std_error_mm: float
    slope_std_error_mm_per_km: float
    covariance: float
    residual_std_mm: float
    n: int
    dof: int
    intercept_fixed: bool

    def value_mm(self, mileage_km: ArrayLike) -> np.ndarray:
        return self.intercept_mm + self.slope_mm_per_km * np.asarray(mileage_km, dtype=float)

    def to_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ParameterTrend:
        return cls(**{k: data[k] for k in cls.__dataclass_fields__})


def fit_parameter_trend(mileage_km: ArrayLike, values_mm: ArrayLike, *, parameter: str,
                        intercept: str = "fixed",
                        new_value_mm: float | None = None) -> ParameterTrend:
    """Least-squares line of one parameter over mileage (module docstring for the choice).

    Parameters
    ----------
    mileage_km : mileage since reprofiling [km]
    values_mm : the parameter's measured values [mm]
    parameter : 'sd_mm', 'sh_mm' or 'qr_mm'
    intercept : 'fixed' (at ``new_value_mm``, default the S1002 value) or 'fitted'
    """
    if parameter not in PARAMETERS:
        raise ValueError(f"parameter: must be one of {PARAMETERS}, got {parameter!r}")
    if intercept not in ("fixed", "fitted"):
        raise ValueError(f"intercept: must be 'fixed' or 'fitted', got {intercept!r}")
    s = np.asarray(mileage_km, dtype=float).ravel()
    p = np.asarray(values_mm, dtype=float).ravel()
    if s.shape != p.shape:
        raise ValueError("mileage_km/values: must have the same length")
    ok = np.isfinite(s) & np.isfinite(p)
    if np.any(s[ok] < 0):
        raise ValueError("mileage_km: must be >= 0")
    s, p = s[ok], p[ok]
    if intercept == "fixed":
        p0 = NEW_PROFILE_VALUES[parameter] if new_value_mm is None else float(new_value_mm)
        use = s > 0
        s, p = s[use], p[use]
        n = s.size
        if n < 1:
            raise ValueError(f"{parameter}: need at least one measurement with mileage > 0")
        sxx = float(np.sum(s * s))
        b = float(np.sum(s * (p - p0)) / sxx)
        dof = n - 1
        rss = float(np.sum((p - p0 - b * s) ** 2))
        sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
        se_b = sigma / math.sqrt(sxx) if dof > 0 else math.nan
        return ParameterTrend(parameter, p0, b, 0.0, se_b, 0.0, sigma, n, dof, True)
    n = s.size
    if n < 2 or np.ptp(s) == 0:
        raise ValueError(f"{parameter}: a fitted intercept needs two different mileages")
    x = np.column_stack([np.ones(n), s])
    coef, *_ = np.linalg.lstsq(x, p, rcond=None)
    dof = n - 2
    rss = float(np.sum((p - x @ coef) ** 2))
    sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
    cov = np.linalg.inv(x.T @ x) * (sigma**2 if dof > 0 else math.nan)
    return ParameterTrend(parameter, float(coef[0]), float(coef[1]), math.sqrt(cov[0, 0]),
                          math.sqrt(cov[1, 1]), float(cov[0, 1]), sigma, n, dof, False)


@dataclass(frozen=True)
class LimitMileage:
    """Mileage [km] at which a parameter reaches its limit (inf: never, at this trend)."""

    parameter: str
    limit_mm: float
    mileage_p10_km: float
    mileage_p50_km: float
    mileage_p90_km: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "parameter": self.parameter,
            "limit_mm": self.limit_mm,
            "mileage_p10_km": finite_or_none(self.mileage_p10_km),
            "mileage_p50_km": finite_or_none(self.mileage_p50_km),
            "mileage_p90_km": finite_or_none(self.mileage_p90_km),
        }


def limit_mileage(trend: ParameterTrend, limits: WheelLimits = DEFAULT_LIMITS) -> LimitMileage:
    """P10/P50/P90 mileage [km] at which the trend reaches the parameter's limit."""
    limit, direction = _limit_for(trend.parameter, limits)
    gap = limit - trend.intercept_mm  # <0 for a min limit still satisfied

    def crossing(slope: float) -> float:
        if gap * direction <= 0:  # limit already reached at s = 0
            return 0.0
        if slope * direction <= 0:
            return math.inf
        return gap / slope

    b = trend.slope_mm_per_km
    p50 = crossing(b)
    if trend.dof < 1 or not math.isfinite(trend.slope_std_error_mm_per_km):
        return LimitMileage(trend.parameter, limit, p50, p50, p50)
    t90 = float(student_t.ppf(0.9, trend.dof))
    if trend.intercept_fixed:
        fast = crossing(b + direction * t90 * trend.slope_std_error_mm_per_km)
        slow = crossing(b - direction * t90 * trend.slope_std_error_mm_per_km)
        return LimitMileage(trend.parameter, limit, fast, p50, slow)
    if not math.isfinite(p50) or p50 == 0.0:
        return LimitMileage(trend.parameter, limit, p50, p50, p50)
    var = (trend.intercept_std_error_mm**2 + 2 * p50 * trend.covariance
           + p50**2 * trend.slope_std_error_mm_per_km**2) / b**2
    sd = math.sqrt(max(var, 0.0))
    return LimitMileage(trend.parameter, limit, max(0.0, p50 - t90 * sd), p50, p50 + t90 * sd)


@dataclass(frozen=True)
class ParameterForecast:
    """Trends, limit mileages and the governing limit of one wheel or vehicle."""

    group: Any
    trends: dict[str, ParameterTrend]
    limits: dict[str, LimitMileage]
    governing_limit: str | None
    mileage_p10_km: float
    mileage_p50_km: float
    mileage_p90_km: float
    reason: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "group": self.group,
            "trends": {k: v.to_dict() for k, v in self.trends.items()},
            "limits": {k: v.to_dict() for k, v in self.limits.items()},
            "governing_limit": self.governing_limit,
            "mileage_p10_km": finite_or_none(self.mileage_p10_km),
            "mileage_p50_km": finite_or_none(self.mileage_p50_km),
            "mileage_p90_km": finite_or_none(self.mileage_p90_km),
            "reason": self.reason,
        }


def forecast_parameters(mileage_km: ArrayLike, values: Mapping[str, ArrayLike], *,
                        group: Any = None, intercept: str = "fixed",
                        limits: WheelLimits = DEFAULT_LIMITS,
                        new_values_mm: Mapping[str, float] | None = None) -> ParameterForecast:
    """Fit every given parameter of one wheel/vehicle and find the governing limit.

    Parameters
    ----------
    mileage_km : (n,) mileage since reprofiling [km]
    values : {'sd_mm': (n,), 'sh_mm': (n,), 'qr_mm': (n,)} measured parameters [mm]
        (any subset)
    intercept : 'fixed' (new-profile values) or 'fitted'
    limits : the in-service limits
    new_values_mm : new-profile values overriding the S1002 ones
    """
    trends, crossings = {}, {}
    for name, series in values.items():
        new = (new_values_mm or {}).get(name)
        trends[name] = fit_parameter_trend(mileage_km, series, parameter=name,
                                           intercept=intercept, new_value_mm=new)
        crossings[name] = limit_mileage(trends[name], limits)
    if not crossings:
        raise ValueError("values: give at least one of sd_mm, sh_mm, qr_mm")
    best = min(crossings.values(), key=lambda c: c.mileage_p50_km)
    if not math.isfinite(best.mileage_p50_km):
        return ParameterForecast(group, trends, crossings, None, math.inf, math.inf, math.inf,
                                 reason="no parameter trends towards its limit")
    p10 = min(c.mileage_p10_km for c in crossings.values())
    p90 = min(c.mileage_p90_km for c in crossings.values())
    return ParameterForecast(group, trends, crossings, LIMIT_NAME[best.parameter], p10,
                             best.mileage_p50_km, p90)


def forecast_parameter_fleet(frame: pd.DataFrame, *, group_by: str = "vehicle_id",
                             intercept: str = "fixed",
                             limits: WheelLimits = DEFAULT_LIMITS) -> dict[Any, ParameterForecast]:
    """:func:`forecast_parameters` for every wheel or vehicle of a parameter-only fleet.

    Parameters
    ----------
    frame : rows with ``group_by`` (e.g. ``vehicle_id`` or ``wheel_id``), ``mileage_km`` and
        any of ``sd_mm, sh_mm, qr_mm``
    """
    for column in (group_by, "mileage_km"):
        if column not in frame.columns:
            raise ValueError(f"{column}: column missing")
    present = [p for p in PARAMETERS if p in frame.columns]
    if not present:
        raise ValueError("sd_mm: none of sd_mm, sh_mm, qr_mm is in the frame")
    out = {}
    for key, rows in frame.groupby(group_by, sort=True):
        try:
            out[key] = forecast_parameters(
                rows["mileage_km"].to_numpy(dtype=float),
                {p: rows[p].to_numpy(dtype=float) for p in present},
                group=key, intercept=intercept, limits=limits,
            )
        except ValueError as exc:
            raise ValueError(f"{group_by}={key!r}: {exc}") from exc
    return out
