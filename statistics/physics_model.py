"""The physics wear model: a whole-vehicle wear-loop run with a calibrated wear-coefficient scale.

The run is :func:`wearcast.physics.vehicle_wear_simulation.simulate_vehicle_wear` (every wheel
of every bogie, both running directions, averaged as measured; seed 003 §4-5). Its wheels'
Sd (FT), Sh (FH) and qR per step are kept as a :class:`VehicleSeries`. The model is that run
and one wear-coefficient scale c: scaling every wear rate by c is a change of the loop's
mileage variable (``statistics.physics_diagnosis``), so the model's parameter P at mileage m
is the run's at c m.

* Calibration: measured per-wheel Sd/Sh/qR (profile or parameter measurements) are averaged
  per vehicle and mileage over the wheels measured there (:func:`measured_vehicle_means`, as
  seed 003 Table 2 averages all wheels of a unit), and c is the least-squares scale of
  :func:`wearcast.statistics.physics_diagnosis.fit_wear_scale` (the diagnosis's null fit).
* Spread: c fitted per vehicle; the P10/P90 scales are c exp(∓1.2816 s) with s the standard
  deviation of log c over the vehicles (a log-normal vehicle-to-vehicle spread of the wear
  rate). With one vehicle there is no spread (P10 = P50 = P90, said in ``method``).
* Beyond the run's end a series is continued linearly with the slope of its last quarter
  (flagged ``extrapolated``).
* Reprofiling: the first mileage at which Sd, Sh or qR crosses a limit
  (``statistics.profile_parameters.WheelLimits``, EN 15313 / EBO defaults), linear between
  evaluation points; from a measured start the model's change is added to the measured
  values (as ``statistics.reprofiling`` does for the hybrid model).

Units: mm, km.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vehicle_wheel_series import VehicleWheelSeries
from wearcast.statistics.physics_comparison import compare_with_measured
from wearcast.statistics.physics_diagnosis import SERIES, ScaleFit, fit_wear_scale
from wearcast.statistics.profile_parameters import DEFAULT_LIMITS, WheelLimits

QUANTITIES = ("sd_mm", "sh_mm", "qr_mm")
#: z of the 10th/90th percentile of a normal distribution.
Z90 = 1.2815515655446004
#: Share of a run (its last part) whose slope continues it beyond its end.
TAIL_SHARE = 0.25


@dataclass(frozen=True)
class VehicleSeries(VehicleWheelSeries):
    """Per-wheel Sd/Sh/qR of a whole-vehicle run (:class:`VehicleWheelSeries`: mileage_km
    (n,), wheels ``<bogie><i>-<axle><L|R>``, weights summing to 1, sd_mm/sh_mm/qr_mm (n, w)),
    as stored with a physics model."""

    @classmethod
    def from_simulation(cls, sim: VehicleWheelSeries) -> VehicleSeries:
        return cls(*(getattr(sim, f.name) for f in fields(VehicleWheelSeries)))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> VehicleSeries:
        values: dict[str, Any] = {f.name: np.asarray(d[f.name], float)
                                  for f in fields(VehicleWheelSeries) if f.name != "wheels"}
        return cls(wheels=tuple(d["wheels"]), **values)

    def to_dict(self) -> dict[str, Any]:
        return {f.name: list(self.wheels) if f.name == "wheels"
                else getattr(self, f.name).tolist() for f in fields(VehicleWheelSeries)}

    def wheel_columns(self, bogie_type: str, axle: int, side: str) -> list[int]:
        """Columns of the wheels at a position (one per bogie of that type in the run)."""
        suffix = f"-{int(axle)}{side[0].upper()}"
        return [i for i, w in enumerate(self.wheels)
                if w.startswith(bogie_type) and w.endswith(suffix)]

    def bogie_types(self) -> list[str]:
        return sorted({w.split("-")[0].rstrip("0123456789") for w in self.wheels})

    def position(self, quantity: str, bogie_type: str, axle: int, side: str) -> NDArray:
        """A wheel position's series per step (mean over the bogies of that type) [mm]."""
        cols = self.wheel_columns(bogie_type, axle, side)
        if not cols:
            raise ValueError(f"bogie_type: the run has no {bogie_type} bogie (it has "
                             f"{', '.join(self.bogie_types())})")
        return np.asarray(getattr(self, quantity))[:, cols].mean(axis=1)


def continued(km: NDArray, values: NDArray, at_km: NDArray) -> tuple[NDArray, NDArray]:
    """A series at mileages, linear between steps and beyond its end with the slope of its
    last ``TAIL_SHARE`` (least squares); returns (values, extrapolated flags)."""
    at = np.asarray(at_km, float)
    end = float(km[-1])
    tail = km >= end * (1.0 - TAIL_SHARE)
    if tail.sum() < 2:
        tail = np.zeros(km.size, bool)
        tail[-2:] = True
    slope = float(np.polyfit(km[tail], values[tail], 1)[0]) if km.size > 1 else 0.0
    out = np.where(at <= end, np.interp(at, km, values), values[-1] + slope * (at - end))
    return out, at > end + 1e-9


@dataclass(frozen=True)
class ScaledVehicle:
    """The run seen at scale c (wheel km = run km / c), continued linearly to ``until_km``:
    what :func:`~wearcast.statistics.physics_comparison.compare_with_measured` reads."""

    series: VehicleSeries
    scale: float
    until_km: float = 0.0

    @property
    def mileage_km(self) -> NDArray:
        km = self.series.mileage_km / self.scale
        return np.append(km, self.until_km) if self.until_km > km[-1] else km

    def mean(self, quantity: str) -> NDArray:
        km = self.series.mileage_km / self.scale
        values = self.series.mean(quantity)
        if self.until_km > km[-1]:
            return np.append(values, continued(km, values, np.array([self.until_km]))[0])
        return values

    def mean_at(self, quantity: str, mileage_km: Any) -> NDArray:
        return np.interp(np.asarray(mileage_km, float), self.mileage_km, self.mean(quantity))


def measured_vehicle_means(frame: pd.DataFrame) -> pd.DataFrame:
    """Per-wheel measurements (``vehicle_id, mileage_km, sd_mm, sh_mm, qr_mm``, one row per
    wheel and mileage) averaged per vehicle and mileage (rounded to 0.1 km) over the wheels
    measured there: columns ``vehicle, distance_km, FT_mm, FH_mm, QR_mm, n_wheels`` (what
    ``physics_diagnosis`` and ``physics_comparison`` read)."""
    need = {"vehicle_id", "mileage_km", "sd_mm", "qr_mm"}
    if not need <= set(frame.columns):
        raise ValueError(f"measurements need {', '.join(sorted(need))}")
    rows = frame.dropna(subset=["sd_mm", "qr_mm"]).copy()
    if "sh_mm" not in rows:
        rows["sh_mm"] = np.nan
    rows["distance_km"] = rows["mileage_km"].astype(float).round(1)
    grouped = rows.groupby([rows["vehicle_id"].astype(str), "distance_km"], sort=True)
    out = grouped.agg(FT_mm=("sd_mm", "mean"), FH_mm=("sh_mm", "mean"),
                      QR_mm=("qr_mm", "mean"), n_wheels=("sd_mm", "size")).reset_index()
    return out.rename(columns={"vehicle_id": "vehicle"})


@dataclass(frozen=True)
class Calibration:
    """The fitted scale, its spread over vehicles and the error against the measurements."""

    fit: ScaleFit
    per_vehicle: dict[str, float]
    log_sigma: float
    method: str
    comparison: Any

    @property
    def scale_p10_p50_p90(self) -> tuple[float, float, float]:
        c, s = self.fit.wear_scale, self.log_sigma
        return c * math.exp(-Z90 * s), c, c * math.exp(Z90 * s)

    def to_dict(self) -> dict[str, Any]:
        lo, mid, hi = self.scale_p10_p50_p90
        return {"wear_scale": mid, "rms_mm": self.fit.rms_mm, "n_points": self.fit.n_points,
                "reach": self.fit.reach, "at_reach": self.fit.at_reach,
                "spread": {"method": self.method, "log_sigma": self.log_sigma,
                           "per_vehicle_scale": self.per_vehicle,
                           "scale_p10": lo, "scale_p90": hi},
                "errors": {"per_vehicle": _records(self.comparison.per_vehicle),
                           "overall": _records(self.comparison.overall)}}


def _records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    out = []
    for rec in frame.to_dict(orient="records"):
        out.append({str(k): (None if isinstance(v, float) and not math.isfinite(v) else v)
                    for k, v in rec.items()})
    return out


def calibrate_scale(series: VehicleSeries, measured: pd.DataFrame) -> Calibration:
    """Fit c on all vehicles, per vehicle for the spread, and compare the scaled run with the
    measured series (error per vehicle and quantity, ``physics_comparison``)."""
    fit = fit_wear_scale(series, measured)
    per_vehicle: dict[str, float] = {}
    for vehicle, rows in measured.groupby("vehicle"):
        if (rows["distance_km"] > 0).any():
            per_vehicle[str(vehicle)] = fit_wear_scale(series, rows).wear_scale
    if len(per_vehicle) >= 2:
        log_sigma = float(np.std(np.log(list(per_vehicle.values())), ddof=1))
        method = (f"log-normal over {len(per_vehicle)} vehicles' own scales (vehicle-to-"
                  "vehicle spread of the wear rate)")
    else:
        log_sigma = 0.0
        method = "one vehicle: no spread can be derived (p10 = p50 = p90)"
    cols = [c for c in SERIES if c in measured and measured[c].notna().any()]
    view = ScaledVehicle(series, fit.wear_scale, float(measured["distance_km"].max()))
    comparison = compare_with_measured(view, measured[["vehicle", "distance_km", *cols]]
                                       .dropna(subset=cols))
    return Calibration(fit, per_vehicle, log_sigma, method, comparison)


def predict_position(series: VehicleSeries, scales: Sequence[float], mileage_km: NDArray, *,
                     bogie_type: str, axle: int, side: str,
                     start_km: float = 0.0, start: Mapping[str, float] | None = None
                     ) -> dict[str, Any]:
    """Sd/Sh/qR of a wheel position at wheel mileages for each scale (P10, P50, P90 scale
    order); from a measured start (``start`` values at ``start_km``) the model's change since
    ``start_km`` is added to the measured values. Returns {quantity: (n_scales, n)} arrays,
    ``vehicle_<quantity>`` the vehicle means at the middle scale and ``extrapolated`` (n,)."""
    km = np.asarray(mileage_km, float)
    run_km = series.mileage_km
    out: dict[str, Any] = {}
    extrapolated = np.zeros(km.size, bool)
    for q in QUANTITIES:
        values = series.position(q, bogie_type, axle, side)
        rows = []
        for c in scales:
            v, e = continued(run_km, values, c * (start_km + km))
            if start is not None and start.get(q) is not None:
                v0, _ = continued(run_km, values, np.array([c * start_km]))
                v = start[q] + v - v0[0]
            rows.append(v)
            extrapolated |= e
        out[q] = np.array(rows)
        mid = scales[len(scales) // 2]
        out[f"vehicle_{q}"] = continued(run_km, series.mean(q), mid * (start_km + km))[0]
    out["extrapolated"] = extrapolated
    return out


@dataclass(frozen=True)
class Crossing:
    """First limit crossing of one scale: wheel mileage from the start [km] (inf: none within
    the horizon), the governing limit, the parameters there, whether extrapolated."""

    remaining_km: float
    governing_limit: str | None
    values: dict[str, float]
    extrapolated: bool


def _margins(values: dict[str, NDArray], limits: WheelLimits) -> NDArray:
    return np.column_stack([values["sd_mm"] - limits.sd_min_mm,
                            limits.sh_max_mm - values["sh_mm"],
                            values["qr_mm"] - limits.qr_min_mm])


def first_crossing(series: VehicleSeries, scale: float, *, bogie_type: str, axle: int,
                   side: str, limits: WheelLimits = DEFAULT_LIMITS, start_km: float = 0.0,
                   start: Mapping[str, float] | None = None,
                   horizon_km: float = 3_000_000.0, n_grid: int = 4000) -> Crossing:
    """The first wheel mileage (from ``start_km``) at which Sd < sd_min, Sh > sh_max or
    qR < qr_min, on a grid over the horizon refined by linear interpolation of the margin."""
    names = ("sd", "sh", "qr")
    end_run_km = float(series.mileage_km[-1]) / scale
    grid = np.unique(np.concatenate([
        np.linspace(0.0, max(end_run_km - start_km, 0.0), 400),
        np.geomspace(1.0, horizon_km, n_grid)]))
    pred = predict_position(series, [scale], grid, bogie_type=bogie_type, axle=axle,
                            side=side, start_km=start_km, start=start)
    values = {q: pred[q][0] for q in QUANTITIES}
    margins = _margins(values, limits)
    crossed = margins < 0
    if crossed[0].any():  # already past a limit at the start
        j = int(np.argmin(margins[0]))
        return Crossing(0.0, names[j], {q: float(values[q][0]) for q in QUANTITIES}, False)
    hit = np.flatnonzero(crossed.any(axis=1))
    if hit.size == 0:
        return Crossing(math.inf, None, {q: math.nan for q in QUANTITIES},
                        bool(pred["extrapolated"][-1]))
    i = int(hit[0])
    cand = []
    for j in range(3):
        if crossed[i, j]:
            a, b = margins[i - 1, j], margins[i, j]
            t = a / (a - b) if a != b else 1.0
            cand.append((grid[i - 1] + t * (grid[i] - grid[i - 1]), j))
    mileage, j = min(cand)
    at = predict_position(series, [scale], np.array([mileage]), bogie_type=bogie_type,
                          axle=axle, side=side, start_km=start_km, start=start)
    return Crossing(float(mileage), names[j], {q: float(at[q][0, 0]) for q in QUANTITIES},
                    bool(at["extrapolated"][0]))
