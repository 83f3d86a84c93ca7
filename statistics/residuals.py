"""Residuals of a calibrated hybrid model (seed 001) per measurement, region and wear curve.

The hybrid model predicts a wheel's wear area in region r after ``s`` km since reprofiling as
A_r = c_s,r P_r s (seed 001 eqs. 2–4), P_r the weighted wear measure of its route. Wear grows
about linearly in mileage and wheel-to-wheel scatter is multiplicative, so the natural
residual of one measurement is the log ratio of measured to predicted area,

    e_r = log((A_meas,r + a0_r) / (A_pred,r + a0_r)),

with a small area floor a0_r [mm²] (a tenth of the median positive measured area of the
region) that keeps regions which barely wear (flanges on tangent track) from dominating.
For wear-curve SHAPE the residual is d(y) = w_meas(y) - w_model(y; A_meas): the measured wear
curve minus the model's wear-state curve at the measured areas (seed 001 §2.2), which is where
an instrument's geometric error shows (seed 000 §IV.A aligns before comparing).

Everything also returns the pieces the discrepancy finder recombines: per measurement the
route's wear measure split by wheelset position (leading/trailing), curve direction (tangent,
left, right) and measure (tau_max, t_gamma), so that running direction, curve asymmetry and
the wear measure can be changed without touching the table again.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS, RUNNING_MODES, WEAR_MEASURES
from wearcast.statistics.frames import check_frame
from wearcast.statistics.hybrid import HybridModel
from wearcast.statistics.route_measure import leading_shares, route_parts, weighted_measure
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_states import join_regions, wear_curves_at_areas
from wearcast.statistics.wear_tables import WearTable, compile_wear_table

REQUIRED_COLUMNS = ("wheel_id", "bogie_type", "axle", "side", "mileage_km",
                    "flange_area_mm2", "tread_area_mm2")
FLOOR_FRACTION = 0.1


def route_column(measurements: pd.DataFrame) -> str:
    """Name of the column holding each measurement's route name (``route`` or ``route_id``)."""
    for name in ("route", "route_id"):
        if name in measurements.columns:
            return name
    raise ValueError("route: column missing from measurements (need 'route' or 'route_id')")


def check_measurements(measurements: pd.DataFrame) -> pd.DataFrame:
    """Validate the measurement frame and return a clean copy with a 0..n-1 index."""
    check_frame(measurements, REQUIRED_COLUMNS, field="measurements", what="measurements")
    df = measurements.reset_index(drop=True).copy()
    route_column(df)
    df["mileage_km"] = pd.to_numeric(df["mileage_km"], errors="coerce").astype(float)
    if not np.all(np.isfinite(df["mileage_km"])) or (df["mileage_km"] < 0).any():
        raise ValueError("mileage_km: must be finite and >= 0")
    for r in REGIONS:
        df[f"{r}_area_mm2"] = pd.to_numeric(df[f"{r}_area_mm2"], errors="coerce").astype(float)
        if not np.all(np.isfinite(df[f"{r}_area_mm2"])):
            raise ValueError(f"{r}_area_mm2: must be finite")
    df["axle"] = pd.to_numeric(df["axle"], errors="coerce").astype(int)
    if "vehicle_id" not in df.columns:
        df["vehicle_id"] = df["wheel_id"]
    return df


def curve_shares(route: Route) -> tuple[float, float]:
    """(left, right) shares of the route length in curves bending left / right [-]."""
    left = sum(c.share for c in route.classes if c.direction == "left")
    right = sum(c.share for c in route.classes if c.direction == "right")
    return float(left), float(right)


@dataclass(frozen=True)
class ModelResiduals:
    """Residuals of a calibrated model on a set of measurements.

    Arrays over the n measurements (rows of ``frame``, which is the validated input with the
    columns below added); (n, 2) arrays have regions in ``REGIONS`` order (flange, tread).

    frame : measurements plus ``p_flange, p_tread`` (weighted wear measure), ``pred_*_area_mm2``,
        ``logres_*`` (log residual), ``rate_res_*`` (rate residual [mm²/km]) and
        ``in_calibration``
    parts : (n, 2 measures, 2 regions, 2 wheelsets, 3 parts) route wear measures by part
    mode : (n,) running mode used for each row (the row's own when given, else the model's)
    measured_mm2, predicted_mm2 : (n, 2) wear areas [mm²]
    floor_mm2 : (2,) area floor a0 per region [mm²]
    left_right_shares : (n, 2) the route's left / right curve shares
    history : ``route_history_weights`` (None when no wheel changed route): when a wheel's
        route changed within a life, its parts and shares are the mileage-weighted mix of
        the routes of its intervals
    """

    frame: pd.DataFrame
    parts: NDArray[np.float64]
    mode: NDArray[Any]
    measured_mm2: NDArray[np.float64]
    predicted_mm2: NDArray[np.float64]
    floor_mm2: NDArray[np.float64]
    left_right_shares: NDArray[np.float64]
    history: Any = None

    @property
    def log_residual(self) -> NDArray[np.float64]:
        return log_residual(self.measured_mm2, self.predicted_mm2, self.floor_mm2)


def area_floor_mm2(measured_mm2: ArrayLike) -> NDArray[np.float64]:
    """Area floor a0 per region [mm²]: a tenth of the median positive measured area (>= 0.1)."""
    a = np.asarray(measured_mm2, dtype=float)
    floors = []
    for j in range(a.shape[1]):
        pos = a[:, j][a[:, j] > 0]
        floors.append(max(0.1, FLOOR_FRACTION * float(np.median(pos))) if pos.size else 1.0)
    return np.asarray(floors)


def log_residual(measured_mm2: ArrayLike, predicted_mm2: ArrayLike,
                 floor_mm2: ArrayLike) -> NDArray[np.float64]:
    """e = log((A_meas + a0) / (A_pred + a0)); negative measured areas count as 0."""
    m = np.clip(np.asarray(measured_mm2, dtype=float), 0.0, None)
    p = np.clip(np.asarray(predicted_mm2, dtype=float), 0.0, None)
    f = np.asarray(floor_mm2, dtype=float)
    return np.log((m + f) / (p + f))


def model_residuals(
    model: HybridModel,
    measurements: pd.DataFrame,
    routes_by_name: Mapping[str, Route],
    table: pd.DataFrame | WearTable,
    *,
    calibration_wheel_ids: Collection[Any] = (),
) -> ModelResiduals:
    """Area residuals of a calibrated model for any measurements (seed 001 eqs. 2–4).

    Parameters
    ----------
    model : calibrated hybrid model
    measurements : one row per measurement: ``wheel_id, bogie_type, axle (1|2), side,
        mileage_km`` [km since reprofiling], ``route`` or ``route_id`` (a key of
        ``routes_by_name``), ``flange_area_mm2, tread_area_mm2`` [mm²]; optional
        ``vehicle_id, running_mode, measured_on, load_t, instrument_id`` and other covariates
    routes_by_name : Route per route name
    table : curve-radius table; needs the model's measure (both measures for
        ``wear_measure``)
    calibration_wheel_ids : wheels the model was calibrated on (flagged ``in_calibration``;
        their residuals are in-sample)

    The running mode of a row is its ``running_mode`` when given ('lead'|'mixed'), else the
    model's.
    """
    df = check_measurements(measurements)
    wt = compile_wear_table(table)
    rcol = route_column(df)
    if model.measure not in wt.measures:
        raise ValueError(f"table: has no {model.measure!r} rows (the model's measure)")
    n = len(df)
    mode = np.full(n, model.running_mode, dtype=object)
    if "running_mode" in df.columns:
        given = df["running_mode"].astype(str).str.strip().str.lower().to_numpy()
        ok = np.isin(given, RUNNING_MODES)
        mode[ok] = given[ok]
    parts = np.zeros((n, 2, 2, 2, 3))
    shares = np.zeros((n, 2))
    keys = list(zip(df[rcol].astype(str), df["bogie_type"].astype(str), df["side"].astype(str),
                    strict=True))
    cache: dict[tuple[str, str, str], tuple[NDArray[np.float64], tuple[float, float]]] = {}
    for i, key in enumerate(keys):
        if key not in cache:
            route_name, bogie, side = key
            if route_name not in routes_by_name:
                raise ValueError(f"route: measurement row {i} names unknown route {route_name!r}")
            route = routes_by_name[route_name]
            if bogie not in wt.bogie_types:
                raise ValueError(f"bogie_type: {bogie!r} (row {i}) is not in the wear table")
            block = np.zeros((2, 2, 2, 3))
            for m, measure in enumerate(WEAR_MEASURES):
                if measure not in wt.measures:
                    block[m] = np.nan
                    continue
                for r, region in enumerate(REGIONS):
                    block[m, r] = route_parts(route, wt, bogie_type=bogie, side=side,
                                              region=region, measure=measure)
            cache[key] = (block, curve_shares(route))
        parts[i], shares[i] = cache[key][0], cache[key][1]
    history = route_history_weights(df, df["mileage_km"].to_numpy(dtype=float))
    if history is not None:   # wear accrued on the routes of the life's earlier intervals
        parts = np.asarray(history @ parts.reshape(n, -1)).reshape(parts.shape)
        shares = np.asarray(history @ shares)
    lead = leading_shares(df["axle"].to_numpy(), mode)
    p = weighted_measure(parts, lead, WEAR_MEASURES.index(model.measure))
    mileage = df["mileage_km"].to_numpy()
    c_s = np.array([model.flange.c_s, model.tread.c_s])
    predicted = c_s[None, :] * p * mileage[:, None]
    measured = df[["flange_area_mm2", "tread_area_mm2"]].to_numpy(dtype=float)
    floor = area_floor_mm2(measured)
    res = log_residual(measured, predicted, floor)
    calib = set(calibration_wheel_ids)
    frame = df.assign(
        p_flange=p[:, 0], p_tread=p[:, 1],
        pred_flange_area_mm2=predicted[:, 0], pred_tread_area_mm2=predicted[:, 1],
        logres_flange=res[:, 0], logres_tread=res[:, 1],
        rate_res_flange=np.where(mileage > 0, (measured[:, 0] - predicted[:, 0])
                                 / np.maximum(mileage, 1e-9), 0.0),
        rate_res_tread=np.where(mileage > 0, (measured[:, 1] - predicted[:, 1])
                                / np.maximum(mileage, 1e-9), 0.0),
        in_calibration=df["wheel_id"].isin(calib).to_numpy(),
    )
    return ModelResiduals(frame, parts, mode, measured, predicted, floor, shares, history)


def day_numbers(values: pd.Series) -> NDArray[np.float64] | None:
    """Days since 1970-01-01 of parseable dates; None when any date is missing."""
    dates = pd.to_datetime(values, errors="coerce")
    if dates.isna().any():
        return None
    return np.asarray((dates - pd.Timestamp("1970-01-01")).dt.total_seconds().to_numpy()
                      / 86400.0, dtype=float)


def life_ids(frame: pd.DataFrame, mileage_km: NDArray[np.float64]) -> NDArray[Any]:
    """Per measurement, the wheel's life since its last reprofiling: ``wheel_id`` plus a
    counter that increases whenever the mileage since reprofiling falls (a reprofiling in
    the middle of a series; rows ordered by date when dated, else by mileage)."""
    wheel = frame["wheel_id"].astype(str).to_numpy()
    day = day_numbers(frame["measured_on"]) if "measured_on" in frame.columns else None
    key = day if day is not None else np.arange(len(frame), dtype=float)
    order = np.lexsort((mileage_km, key, wheel))
    life = np.zeros(len(frame), dtype=np.int64)
    prev_w, prev_s, count = None, -1.0, 0
    for i in order:
        if wheel[i] != prev_w:
            prev_w, prev_s, count = wheel[i], -1.0, 0
        elif mileage_km[i] < prev_s - 1e-6:
            count += 1
        life[i] = count
        prev_s = mileage_km[i]
    return np.array([f"{w}#{c}" for w, c in zip(wheel, life, strict=True)], dtype=object)


def route_history_weights(frame: pd.DataFrame, mileage_km: NDArray[np.float64]) -> Any:
    """Sparse (n, n) matrix H with rows summing to 1: measurement k's wear accrued over its
    life's intervals (``life_ids``), interval i (between the life's measurements i-1 and i,
    in mileage order) on the route recorded at measurement i; H[k, i] = Delta s_i / s_k.

    A vehicle that changed route between reprofiling and a measurement wore partly on its
    earlier route; route-dependent quantities of row k are H[k] @ (per-row values). None
    when no life changes route (H would be the identity).
    """
    from scipy import sparse

    rcol = route_column(frame)
    route = frame[rcol].astype(str).to_numpy()
    lives = life_ids(frame, mileage_km)
    groups = pd.Series(np.arange(len(frame))).groupby(lives).indices
    if all(len(set(route[idx])) == 1 for idx in groups.values()):
        return None
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    for idx in groups.values():
        idx = np.asarray(idx)[np.argsort(mileage_km[idx], kind="stable")]
        s = mileage_km[idx]
        inc = np.diff(np.concatenate([[0.0], s]))
        for j, k in enumerate(idx):
            if s[j] <= 0:
                rows.append(int(k))
                cols.append(int(k))
                vals.append(1.0)
                continue
            rows += [int(k)] * (j + 1)
            cols += [int(i) for i in idx[:j + 1]]
            vals += list(inc[:j + 1] / s[j])
    n = len(frame)
    return sparse.csr_matrix((vals, (rows, cols)), shape=(n, n))


def model_wear_curves(model: HybridModel, areas_mm2: ArrayLike) -> NDArray[np.float64]:
    """Model wear curves (n, g) [mm] on the model's grid at given (n, 2) flange/tread areas."""
    a = np.clip(np.asarray(areas_mm2, dtype=float), 0.0, None)
    wf, _ = wear_curves_at_areas(model.states, "flange", a[:, 0])
    wt_, _ = wear_curves_at_areas(model.states, "tread", a[:, 1])
    return join_regions(model.grid_y_mm, wf, wt_, model.split_y_mm, model.join_window_mm)


def shape_residuals(model: HybridModel, measured_areas_mm2: ArrayLike,
                    wear_curves_mm: ArrayLike) -> NDArray[np.float64]:
    """Wear-curve shape residual d = w_meas - w_model(A_meas) (n, g) [mm]; NaN where no data."""
    curves = np.asarray(wear_curves_mm, dtype=float)
    grid = model.grid_y_mm
    if curves.ndim != 2 or curves.shape[1] != grid.size:
        raise ValueError(f"wear_curves: must have shape (n, {grid.size}) on the model's grid")
    return curves - model_wear_curves(model, measured_areas_mm2)


def geometric_basis(grid_y_mm: ArrayLike, split_y_mm: float) -> NDArray[np.float64]:
    """Wear-curve signatures of an instrument's geometric errors (3, g) [mm per unit].

    Rows: a lateral scale error y -> (1 + e) y about the tape circle gives w = e y z'(y);
    an offset delta of the flange part against the tread gives w = delta z'(y) on y < split;
    a residual lateral shift gives w = delta z'(y) everywhere. z = S1002 (seed 000 §IV.A).
    """
    y = np.asarray(grid_y_mm, dtype=float)
    slope = np.gradient(s1002_height_mm(y), y)
    slope = np.where(np.isfinite(slope), slope, 0.0)
    return np.vstack([y * slope, np.where(y < split_y_mm, slope, 0.0), slope])


def residual_structure(frame: pd.DataFrame, covariate: str) -> pd.DataFrame:
    """Mean log residual per region and level of a covariate (n, mean, std error)."""
    g = frame.groupby(frame[covariate].astype(str))
    out = pd.DataFrame({
        "n": g.size(),
        "mean_logres_flange": g["logres_flange"].mean(),
        "mean_logres_tread": g["logres_tread"].mean(),
        "se_flange": g["logres_flange"].std(ddof=1) / np.sqrt(g.size()),
        "se_tread": g["logres_tread"].std(ddof=1) / np.sqrt(g.size()),
    })
    return out.reset_index().rename(columns={covariate: "level"})
