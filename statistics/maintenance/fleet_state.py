"""Fleet state: each wheel's latest measurement, remaining kilometres to each limit, dates.

For every wheel, from its measurements (cumulative mileage ``mileage_km``):

1. **Since turning.** A turning shows as a jump back towards the new profile between two
   consecutive measurements (Sd up by more than ``TURNING_JUMP_MM["sd"]``, Sh down, qR up,
   or the diameter down by more than the wear of a whole cycle); the wheel's history is its
   measurements since the last such jump.
2. **Remaining kilometres per limit** (Sd, Sh, qR and the scrap diameter), P10/P50/P90:
   with at least two measurements of the quantity since turning, from the wheel's own
   history: the least-squares wear rate r [mm/km] of the quantity against mileage and its
   standard error (the residual scatter when there are three or more points, never below
   the instrument repeatability ``REPEATABILITY_MM``), the quantiles of r from Student's t
   (normal for two points, whose scatter is the repeatability alone), and remaining =
   margin / rate, the margin taken from the latest measurement itself (a measurement is
   never moved by the fit). P10 uses the high rate, P90 the low one; a rate that does not
   move towards the limit gives an infinite remaining mileage. Otherwise from a calibrated
   model (``model_forecast``, supplied by the caller), else unknown.
   A wheel already past a limit has 0 km remaining for it, with the excess reported.
3. **Dates.** A limit is reached on the latest measurement's date plus the remaining
   kilometres over the vehicle's mileage per day: its attribute, or estimated from the dates
   and mileages of its wheels' measurements (kilometres over days between each wheel's first
   and last dated measurement, pooled over the vehicle's wheels).
4. **Diameter differences** of the latest measured diameters within each axle, bogie
   (vehicle and bogie type) and vehicle, against the fleet's limits.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from wearcast.statistics.maintenance.limits import (
    FLANGE_LIMITS,
    LIMIT_DIRECTIONS,
    FleetLimits,
)

QUANTITIES = ("sd", "sh", "qr", "diameter")
#: Jumps [mm] between consecutive measurements that only a turning explains.
TURNING_JUMP_MM = {"sd": 0.5, "sh": 0.5, "qr": 1.0}
#: Diameter drop [mm] between consecutive measurements that only a turning explains.
TURNING_DIAMETER_DROP_MM = 2.0
#: Assumed repeatability (1 sigma) [mm] of a profile instrument's Sd, Sh, qR and of a
#: diameter gauge; the floor of a wear rate's uncertainty.
REPEATABILITY_MM = {"sd": 0.05, "sh": 0.05, "qr": 0.08, "diameter": 0.1}
Z90 = float(stats.norm.ppf(0.9))


@dataclass(frozen=True)
class Remaining:
    """Remaining kilometres to one limit, P10/P50/P90 (inf: not reached; None: unknown)."""

    p10: float | None
    p50: float | None
    p90: float | None
    source: str  # "history", "model", "crossed" or "unknown"
    rate_mm_per_1000km: float | None = None
    margin_mm: float | None = None
    n_points: int = 0
    reason: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {k: _plain(v) for k, v in self.__dict__.items()}


def _plain(value: Any) -> Any:
    if isinstance(value, float) and math.isinf(value):
        return None if value != value else ("inf" if value > 0 else "-inf")
    return value


@dataclass
class WheelState:
    """One wheel's latest state and forecast."""

    wheel_id: str
    vehicle_id: str
    bogie_type: str
    axle: int
    side: str
    measurement_id: int | None
    mileage_km: float
    measured_on: dt.date | None
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    diameter_mm: float | None
    turned_at_km: float | None
    n_since_turning: int
    remaining: dict[str, Remaining]
    km_per_day: float | None
    km_per_day_source: str
    crossed: dict[str, float] = field(default_factory=dict)
    dates: dict[str, dict[str, dt.date | None]] = field(default_factory=dict)

    def first(self, quantile: str = "p10") -> tuple[float | None, str | None]:
        """Remaining km to the first limit at a quantile and its name (None if unknown)."""
        best, name = math.inf, None
        for limit, rem in self.remaining.items():
            value = getattr(rem, quantile)
            if value is None:
                continue
            if value < best or name is None:
                best, name = value, limit
        return (None, None) if name is None else (best, name)

    def urgency(self, today: dt.date | None, soon_days: float = 90.0) -> str:
        """``crossed``, ``due`` (P10 within 30 days), ``soon`` (within ``soon_days``), ``ok``
        or ``unknown``."""
        if self.crossed:
            return "crossed"
        km, _ = self.first("p10")
        if km is None:
            return "unknown"
        if self.km_per_day is None or not self.km_per_day > 0:
            return "ok" if math.isinf(km) else "unknown"
        days = km / self.km_per_day
        if self.measured_on is not None and today is not None:
            days -= (today - self.measured_on).days
        return "due" if days <= 30 else ("soon" if days <= soon_days else "ok")

    def to_dict(self, today: dt.date | None = None) -> dict[str, Any]:
        p10, gov10 = self.first("p10")
        p50, gov50 = self.first("p50")
        p90, _ = self.first("p90")
        return {
            "wheel_id": self.wheel_id, "vehicle_id": self.vehicle_id,
            "bogie_type": self.bogie_type, "axle": self.axle, "side": self.side,
            "measurement_id": self.measurement_id, "mileage_km": self.mileage_km,
            "measured_on": _iso(self.measured_on), "sd_mm": self.sd_mm, "sh_mm": self.sh_mm,
            "qr_mm": self.qr_mm, "diameter_mm": self.diameter_mm,
            "turned_at_km": self.turned_at_km, "n_since_turning": self.n_since_turning,
            "km_per_day": self.km_per_day, "km_per_day_source": self.km_per_day_source,
            "remaining_km": {k: v.to_dict() for k, v in self.remaining.items()},
            "first_limit": {"p10": _plain(p10) if p10 is not None else None,
                            "p50": _plain(p50) if p50 is not None else None,
                            "p90": _plain(p90) if p90 is not None else None,
                            "governing_p10": gov10, "governing_p50": gov50},
            "crossed": dict(self.crossed),
            "dates": {k: {q: _iso(d) for q, d in v.items()} for k, v in self.dates.items()},
            "urgency": self.urgency(today),
        }


def _iso(value: dt.date | None) -> str | None:
    return None if value is None else value.isoformat()


@dataclass(frozen=True)
class DiameterSpread:
    """Diameter difference within one axle, bogie or vehicle that exceeds its limit."""

    scope: str  # "axle", "bogie" or "vehicle"
    key: str
    spread_mm: float
    limit_mm: float
    wheel_ids: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"scope": self.scope, "key": self.key, "spread_mm": self.spread_mm,
                "limit_mm": self.limit_mm, "wheel_ids": list(self.wheel_ids)}


@dataclass
class FleetState:
    wheels: list[WheelState]
    diameter_spreads: list[DiameterSpread]
    limits: FleetLimits

    def to_dict(self, today: dt.date | None = None) -> dict[str, Any]:
        return {"limits": self.limits.to_dict(),
                "wheels": [w.to_dict(today) for w in self.wheels],
                "diameter_spreads": [d.to_dict() for d in self.diameter_spreads]}


#: What a model forecast returns for a wheel: remaining km per limit name.
ModelForecast = Callable[["WheelState"], Mapping[str, Remaining]]


Columns = Mapping[str, np.ndarray]


def _columns(frame: pd.DataFrame | Columns) -> Columns:
    if isinstance(frame, pd.DataFrame):
        return {c: frame[c].to_numpy() for c in frame.columns}
    return frame


def _floats(cols: Columns, name: str) -> np.ndarray:
    n = len(cols["mileage_km"])
    if name not in cols:
        return np.full(n, np.nan)
    values = np.asarray(cols[name])
    if values.dtype.kind == "f":
        return values
    return pd.to_numeric(pd.Series(values), errors="coerce").to_numpy(dtype=float)


def turning_starts(frame: pd.DataFrame | Columns) -> np.ndarray:
    """Boolean per row (sorted by mileage) of one wheel: True where a turning happened just
    before the measurement (the row starts a new life)."""
    cols = _columns(frame)
    n = len(cols["mileage_km"])
    out = np.zeros(n, dtype=bool)
    for name, jump in TURNING_JUMP_MM.items():
        if f"{name}_mm" not in cols:
            continue
        d = np.diff(_floats(cols, f"{name}_mm")) * LIMIT_DIRECTIONS[name]  # > 0: back to new
        out[1:] |= np.nan_to_num(d, nan=0.0) > jump
    if "diameter_mm" in cols:
        d = -np.diff(_floats(cols, "diameter_mm"))
        out[1:] |= np.nan_to_num(d, nan=0.0) > TURNING_DIAMETER_DROP_MM
    return out


@lru_cache(maxsize=256)
def _t90(dof: int) -> float:
    return float(stats.t.ppf(0.9, dof))


def history_remaining(mileage_km: np.ndarray, values: np.ndarray, name: str,
                      limits: FleetLimits) -> Remaining:
    """Remaining km to the limit of quantity ``name`` from the wheel's own points since
    turning (module docstring, step 2); ``values`` [mm] at ``mileage_km`` [km]."""
    ok = np.isfinite(values) & np.isfinite(mileage_km)
    s, v = mileage_km[ok], values[ok]
    n = int(s.size)
    if n == 0:
        return Remaining(None, None, None, "unknown", reason="not measured since turning")
    order = np.argsort(s, kind="stable")
    s, v = s[order], v[order]
    margin = limits.margin(name, float(v[-1]))
    if margin <= 0:
        return Remaining(0.0, 0.0, 0.0, "crossed", margin_mm=margin, n_points=n,
                         reason=f"{name} limit crossed by {-margin:.3g} mm")
    if n < 2 or float(s[-1] - s[0]) <= 0:
        return Remaining(None, None, None, "unknown", margin_mm=margin, n_points=n,
                         reason="fewer than 2 measurements since turning")
    sxx = float(((s - s.mean()) ** 2).sum())
    slope = float(((s - s.mean()) * (v - v.mean())).sum() / sxx)
    rate = -LIMIT_DIRECTIONS[name] * slope  # mm/km of margin consumed
    floor = REPEATABILITY_MM[name] / math.sqrt(sxx)
    if n >= 3:
        resid = v - (v.mean() + slope * (s - s.mean()))
        se_fit = math.sqrt(float((resid ** 2).sum()) / (n - 2) / sxx)
        se = math.hypot(se_fit, floor)
        t = _t90(n - 2)
    else:
        se, t = floor, Z90
    hi, lo = rate + t * se, rate - t * se

    def km(r: float) -> float:
        return margin / r if r > 0 else math.inf

    return Remaining(km(hi), km(rate), km(lo), "history", rate_mm_per_1000km=rate * 1000.0,
                     margin_mm=margin, n_points=n,
                     reason=None if rate > 0 else f"{name} shows no wear towards its limit")


def estimate_km_per_day(frame: pd.DataFrame | Columns) -> float | None:
    """Mileage per day of one vehicle from its wheels' dated measurements: the sum of each
    wheel's mileage between its first and last dated measurement over the sum of the days
    between them (None without two dates a day apart)."""
    cols = _columns(frame)
    if "measured_on" not in cols:
        return None
    km = days = 0.0
    first: dict[str, tuple[dt.date, float]] = {}
    last: dict[str, tuple[dt.date, float]] = {}
    for wid, day, s in zip(cols["wheel_id"].tolist(), cols["measured_on"].tolist(),
                           cols["mileage_km"].tolist(), strict=True):
        if day is None or pd.isna(day):
            continue
        if wid not in first or day < first[wid][0]:
            first[wid] = (day, float(s))
        if wid not in last or day >= last[wid][0]:
            last[wid] = (day, float(s))
    for wid, (d0, s0) in first.items():
        d1, s1 = last[wid]
        d = (d1 - d0).days
        if d >= 1 and s1 - s0 >= 0:
            km, days = km + (s1 - s0), days + d
    return km / days if days > 0 and km > 0 else None


def _maybe(value: Any) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def wheel_state(frame: pd.DataFrame | Columns, limits: FleetLimits,
                km_per_day: float | None, km_per_day_source: str,
                model_forecast: ModelForecast | None = None) -> WheelState:
    """The state of one wheel from its measurements (columns of :func:`fleet_state`)."""
    raw = _columns(frame)
    order = np.argsort(np.asarray(raw["mileage_km"], dtype=float), kind="stable")
    cols = {k: np.asarray(v)[order] for k, v in raw.items()}
    starts = np.flatnonzero(turning_starts(cols))
    first = int(starts[-1]) if starts.size else 0
    mileage = np.asarray(cols["mileage_km"], dtype=float)
    s = mileage[first:]
    remaining: dict[str, Remaining] = {}
    crossed: dict[str, float] = {}
    latest: dict[str, float | None] = {}
    for name in QUANTITIES:
        values = _floats(cols, f"{name}_mm")
        latest[name] = _maybe(values[-1])
        rem = history_remaining(s, values[first:], name, limits)
        remaining[name] = rem
        if rem.source == "crossed" and rem.margin_mm is not None:
            crossed[name] = -rem.margin_mm
    day = cols["measured_on"][-1] if "measured_on" in cols else None
    mid = cols["measurement_id"][-1] if "measurement_id" in cols else None
    state = WheelState(
        wheel_id=str(cols["wheel_id"][-1]), vehicle_id=str(cols["vehicle_id"][-1]),
        bogie_type=str(cols["bogie_type"][-1]), axle=int(cols["axle"][-1]),
        side=str(cols["side"][-1]),
        measurement_id=None if mid is None or pd.isna(mid) else int(mid),
        mileage_km=float(mileage[-1]),
        measured_on=None if day is None or pd.isna(day) else day,
        sd_mm=latest["sd"], sh_mm=latest["sh"], qr_mm=latest["qr"],
        diameter_mm=latest["diameter"],
        turned_at_km=float(mileage[first]) if starts.size else None,
        n_since_turning=len(s), remaining=remaining, km_per_day=km_per_day,
        km_per_day_source=km_per_day_source, crossed=crossed)
    if model_forecast is not None and any(remaining[n].source == "unknown"
                                          for n in FLANGE_LIMITS):
        for name, rem in model_forecast(state).items():
            if name in FLANGE_LIMITS and remaining[name].source == "unknown":
                remaining[name] = rem
    state.dates = _dates(state)
    return state


def _dates(state: WheelState) -> dict[str, dict[str, dt.date | None]]:
    out: dict[str, dict[str, dt.date | None]] = {}
    day, kpd = state.measured_on, state.km_per_day
    for name, rem in state.remaining.items():
        out[name] = {}
        for q in ("p10", "p50", "p90"):
            km = getattr(rem, q)
            ok = km is not None and math.isfinite(km) and kpd is not None and kpd > 0
            out[name][q] = (day + dt.timedelta(days=km / kpd)
                            if ok and day is not None and kpd is not None else None)
    return out


def diameter_spreads(wheels: list[WheelState], limits: FleetLimits) -> list[DiameterSpread]:
    """Axles, bogies and vehicles whose latest measured diameters differ beyond the limit."""
    scopes: list[tuple[str, Callable[[WheelState], str], float]] = [
        ("axle", lambda w: f"{w.vehicle_id}/{w.bogie_type}/{w.axle}",
         limits.axle_diameter_difference_mm),
        ("bogie", lambda w: f"{w.vehicle_id}/{w.bogie_type}",
         limits.bogie_diameter_difference_mm),
        ("vehicle", lambda w: w.vehicle_id, limits.vehicle_diameter_difference_mm),
    ]
    out = []
    for scope, key_of, limit in scopes:
        groups: dict[str, list[WheelState]] = {}
        for w in wheels:
            if w.diameter_mm is not None:
                groups.setdefault(key_of(w), []).append(w)
        for key, members in sorted(groups.items()):
            d = [w.diameter_mm for w in members if w.diameter_mm is not None]
            spread = max(d) - min(d)
            if len(d) >= 2 and spread > limit:
                out.append(DiameterSpread(scope, key, round(spread, 4), limit,
                                          tuple(sorted(w.wheel_id for w in members))))
    return out


REQUIRED_COLUMNS = ("wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km")


def fleet_state(measurements: pd.DataFrame, limits: FleetLimits | None = None,
                km_per_day: Mapping[str, float | None] | None = None,
                model_forecast: ModelForecast | None = None) -> FleetState:
    """The state of every wheel of ``measurements``.

    Parameters
    ----------
    measurements : one row per measurement: ``wheel_id, vehicle_id, bogie_type, axle,
        side, mileage_km`` [km] and any of ``measurement_id, measured_on`` (date),
        ``sd_mm, sh_mm, qr_mm, diameter_mm`` [mm] (NaN where not measured)
    limits : the fleet's limits (defaults: :data:`DEFAULT_FLEET_LIMITS`)
    km_per_day : vehicle id -> its mileage per day [km/day] where it is an attribute
    model_forecast : remaining km per flange limit for a wheel whose own history cannot
        give it (fewer than two measurements since turning)
    """
    limits = limits or FleetLimits()
    missing = [c for c in REQUIRED_COLUMNS if c not in measurements]
    if missing:
        raise ValueError(f"measurements.{missing[0]}: column is missing")
    frame = measurements.sort_values(["vehicle_id", "wheel_id", "mileage_km"],
                                     kind="stable")
    cols = {c: frame[c].to_numpy() for c in frame.columns}
    for col in ("sd_mm", "sh_mm", "qr_mm", "diameter_mm"):
        cols[col] = _floats(cols, col)
    attrs = dict(km_per_day or {})
    wheels: list[WheelState] = []
    vehicle, wheel = cols["vehicle_id"], cols["wheel_id"]
    n = len(wheel)
    if n == 0:
        return FleetState([], [], limits)
    v_starts = np.flatnonzero(np.r_[True, vehicle[1:] != vehicle[:-1]])
    v_ends = np.r_[v_starts[1:], n]
    for a, b in zip(v_starts.tolist(), v_ends.tolist(), strict=True):
        vcols = {k: v[a:b] for k, v in cols.items()}
        given = attrs.get(str(vehicle[a]))
        kpd: float | None
        if given is not None and given > 0:
            kpd, source = float(given), "attribute"
        else:
            kpd = estimate_km_per_day(vcols)
            source = "estimated" if kpd is not None else "unknown"
        w = vcols["wheel_id"]
        w_starts = np.flatnonzero(np.r_[True, w[1:] != w[:-1]])
        w_ends = np.r_[w_starts[1:], b - a]
        for c, d in zip(w_starts.tolist(), w_ends.tolist(), strict=True):
            wheels.append(wheel_state({k: v[c:d] for k, v in vcols.items()}, limits, kpd,
                                      source, model_forecast))
    return FleetState(wheels, diameter_spreads(wheels, limits), limits)
