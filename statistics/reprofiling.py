"""Reprofiling mileage from the hybrid model (DESIGN.md "The hybrid model" 7).

The wheel's region areas grow as A_r(s) = A_r,0 + k_r s (seed 001 eq. 4, k_r = c_s,r P_s,r);
the wear states turn areas into a worn profile, whose Sd, Sh and qR are compared with the
limits (Sd >= 22, Sh <= 36, qR >= 6.5 mm by default). The reprofiling mileage is the first
mileage at which any limit is crossed: found on a geometric mileage grid, then refined with
Brent's method on the smallest limit margin.

P10/P50/P90 come from the rate uncertainty of the calibration: the P10 mileage uses the
high (90 %) rates, the P90 mileage the low (10 %) rates. When the wheel starts from a
measured state, ``start_areas`` gives its measured areas; the remaining mileage counts from
there (the wheel's equivalent mileage per region is A_r,0 / k_r).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import brentq
from wearcast.statistics.hybrid import HybridModel, profile_at_areas, region_rates
from wearcast.statistics.profile_parameters import DEFAULT_LIMITS, WheelLimits
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import REGIONS, WearTable

LIMIT_NAMES = ("sd", "sh", "qr")
DEFAULT_HORIZON_KM = 3_000_000.0


def _margins(params: np.ndarray, limits: WheelLimits) -> np.ndarray:
    """(M, 3) signed margins to the limits [mm]; negative = crossed; NaN parameter = crossed."""
    m = np.column_stack([
        params[:, 0] - limits.sd_min_mm,
        limits.sh_max_mm - params[:, 1],
        params[:, 2] - limits.qr_min_mm,
    ])
    return np.where(np.isfinite(m), m, -np.inf)


def _as_limits(limits: WheelLimits | Mapping[str, float] | None) -> WheelLimits:
    if limits is None:
        return DEFAULT_LIMITS
    if isinstance(limits, WheelLimits):
        return limits
    allowed = {"sd_min_mm", "sh_max_mm", "qr_min_mm"}
    for key, value in limits.items():
        if key not in allowed:
            raise ValueError(f"limits.{key}: unknown limit (allowed: {sorted(allowed)})")
        if value is None or not math.isfinite(float(value)):
            raise ValueError(f"limits.{key}: must be a finite number")
    return WheelLimits(**{k: float(v) for k, v in limits.items()})


@dataclass(frozen=True)
class LimitCrossing:
    """First limit crossing for one set of rates."""

    mileage_km: float
    governing_limit: str | None
    sd_mm: float
    sh_mm: float
    qr_mm: float
    extrapolated: bool


def _first_crossing(model: HybridModel, start: Mapping[str, float], rates: Mapping[str, float],
                    limits: WheelLimits, horizon_km: float, n_grid: int) -> LimitCrossing:
    def evaluate(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        _, _, params, extra = profile_at_areas(
            model, start["flange"] + rates["flange"] * s, start["tread"] + rates["tread"] * s
        )
        return params, _margins(params, limits), extra

    grid = np.concatenate([[0.0], np.geomspace(horizon_km / 1e5, horizon_km, n_grid)])
    params, margins, extra = evaluate(grid)
    worst = margins.min(axis=1)
    crossed = np.flatnonzero(worst < 0)
    if crossed.size == 0:
        nan = float("nan")
        return LimitCrossing(math.inf, None, nan, nan, nan, bool(extra.any()))
    j = int(crossed[0])
    if j == 0:
        p = [float(v) for v in params[0]]
        return LimitCrossing(0.0, LIMIT_NAMES[int(np.argmin(margins[0]))], *p, bool(extra[0]))

    def worst_margin(s: float) -> float:
        return float(evaluate(np.array([s]))[1].min())

    lo, hi = float(grid[j - 1]), float(grid[j])
    f_hi = worst_margin(hi)
    if np.isfinite(f_hi):
        root = brentq(worst_margin, lo, hi, xtol=1e-6 * hi, rtol=1e-10)
    else:  # a parameter disappears (NaN): bisect on the sign only
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if worst_margin(mid) >= 0 else (lo, mid)
        root = hi
    p, m, e = evaluate(np.array([root, root * (1 + 1e-9) + 1e-9]))
    governing = LIMIT_NAMES[int(np.argmin(m[1]))]
    return LimitCrossing(float(root), governing, *(float(v) for v in p[0]), bool(e[0]))


@dataclass(frozen=True)
class ReprofilingResult:
    """When a wheel reaches a limit (mileages in km from its start state; inf = not reached).

    ``mileage_p10_km`` is the early (high-rate) estimate, ``mileage_p90_km`` the late one.
    The governing limit and the parameter values are those of the median (P50) crossing.
    """

    mileage_p10_km: float
    mileage_p50_km: float
    mileage_p90_km: float
    governing_limit: str | None
    sd_mm: float
    sh_mm: float
    qr_mm: float
    extrapolated: bool
    reason: str | None
    rates_mm2_per_km: dict[str, float] = field(default_factory=dict)
    equivalent_mileage_km: dict[str, float] = field(default_factory=dict)
    limits: dict[str, float] = field(default_factory=dict)

    @property
    def reached(self) -> bool:
        return math.isfinite(self.mileage_p50_km)

    def to_dict(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {
            "mileage_p10_km": num(self.mileage_p10_km),
            "mileage_p50_km": num(self.mileage_p50_km),
            "mileage_p90_km": num(self.mileage_p90_km),
            "governing_limit": self.governing_limit,
            "sd_mm": num(self.sd_mm),
            "sh_mm": num(self.sh_mm),
            "qr_mm": num(self.qr_mm),
            "extrapolated": self.extrapolated,
            "reason": self.reason,
            "rates_mm2_per_km": {k: num(v) for k, v in self.rates_mm2_per_km.items()},
            "equivalent_mileage_km": {k: num(v) for k, v in self.equivalent_mileage_km.items()},
            "limits": dict(self.limits),
        }


def reprofiling_mileage(
    model: HybridModel,
    route: Route,
    table: pd.DataFrame | WearTable,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    limits: WheelLimits | Mapping[str, float] | None = DEFAULT_LIMITS,
    start_areas: Mapping[str, float] | None = None,
    horizon_km: float = DEFAULT_HORIZON_KM,
    n_grid: int = 80,
) -> ReprofilingResult:
    """First mileage at which Sd, Sh or qR crosses its limit, as P10/P50/P90.

    Parameters
    ----------
    model, route, table : calibrated hybrid model, the route and the curve-radius table
    bogie_type, axle (1|2), side ('left'|'right') : the wheel's position
    limits : WheelLimits or a mapping with ``sd_min_mm``, ``sh_max_mm``, ``qr_min_mm`` [mm]
    start_areas : measured areas {'flange', 'tread'} [mm²] of the wheel's latest measurement
        (default: new profile)
    horizon_km : search horizon [km]; beyond it the limit counts as not reached
    n_grid : points of the geometric search grid before Brent refinement

    Returns
    -------
    ReprofilingResult; mileages are inf with a ``reason`` when no limit is reached within the
    horizon (e.g. tangent track where the flange does not wear and the tread alone never
    crosses a limit).
    """
    lim = _as_limits(limits)
    if not (math.isfinite(horizon_km) and horizon_km > 0):
        raise ValueError("horizon_km: must be finite and > 0")
    start = {r: 0.0 for r in REGIONS}
    for r, v in (start_areas or {}).items():
        if r not in REGIONS:
            raise ValueError(f"start_areas.{r}: unknown region (flange, tread)")
        if v is None or not math.isfinite(float(v)) or float(v) < 0:
            raise ValueError(f"start_areas.{r}: must be finite and >= 0")
        start[r] = float(v)
    _, rates = region_rates(model, route, table, bogie_type=bogie_type, axle=axle, side=side,
                            quantiles=(0.9, 0.5, 0.1))
    crossings = [
        _first_crossing(model, start, {r: float(rates[r][i]) for r in REGIONS}, lim,
                        horizon_km, n_grid)
        for i in range(3)
    ]
    median = crossings[1]
    reason = None
    if not math.isfinite(median.mileage_km):
        if rates["flange"][1] == 0 and rates["tread"][1] == 0:
            reason = "the route gives zero wear rate in both regions"
        else:
            reason = f"no limit is crossed within the horizon of {horizon_km:g} km"
    elif median.mileage_km == 0.0:
        reason = "a limit is already crossed at the start state"
    equivalent = {
        r: (start[r] / float(rates[r][1]) if rates[r][1] > 0 else (0.0 if start[r] == 0
                                                                  else math.inf))
        for r in REGIONS
    }
    return ReprofilingResult(
        mileage_p10_km=crossings[0].mileage_km,
        mileage_p50_km=median.mileage_km,
        mileage_p90_km=crossings[2].mileage_km,
        governing_limit=median.governing_limit,
        sd_mm=median.sd_mm,
        sh_mm=median.sh_mm,
        qr_mm=median.qr_mm,
        extrapolated=median.extrapolated,
        reason=reason,
        rates_mm2_per_km={r: float(rates[r][1]) for r in REGIONS},
        equivalent_mileage_km=equivalent,
        limits={"sd_min_mm": lim.sd_min_mm, "sh_max_mm": lim.sh_max_mm,
                "qr_min_mm": lim.qr_min_mm},
    )
