"""The discrepancy finder's catalogue of causes: one small model extension per cause code.

Every cause of DESIGN.md "The discrepancy finder" is a physically meaningful extension of the
hybrid model of seed 001 (A_r = c_s,r P_r s per region r) with one to three parameters, fitted
on per-measurement log-area residuals (``wearcast.statistics.residuals``):

============================  ===========================================================
``traction``                  tread rate x m on motor bogies (seed 001 §5: traction/braking)
``running_direction``         leading share p per running mode: P = p P_lead + (1-p) P_trail
``curve_asymmetry``           share q of the curved length bending left, per route
``flange_lubrication``        flange rate x m on routes or rows marked lubricated
``wear_measure``              P from the other measure (tau_max <-> T_gamma), c_s refitted
``nonlinear_progression``     A = c P s_ref (s / s_ref)^beta per region (seed 003 §6)
``seasonal_friction``         rate x exp(a cos wt + b sin wt), w = 2 pi / 365.25 days
``vehicle_load``              rate x (load / load_ref)^gamma
``profile_misalignment``      per-instrument wear-curve signature of a lateral scale error,
                              a flange-tread offset and a lateral shift (seed 000 §IV.A)
============================  ===========================================================

Each cause also fits one free log-scale per region, as does the null extension it is compared
with, so a cause never gains from merely re-estimating c_s. Each cause says which data it
needs and returns a reason instead of a fit when the data cannot support it.

Area causes are fitted in closed form (linearised least squares of the log residual,
e ~ phi (b_r + x theta), phi = A_pred / (A_pred + a0)) or on a 1-D grid with the scales in
closed form; the exact floored log residual is what is scored.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics.residuals import REGIONS, log_residual, weighted_measure

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
OMEGA_PER_DAY = 2.0 * np.pi / 365.25
GRID_01 = np.linspace(0.0, 1.0, 41)


@dataclass(frozen=True)
class FinderData:
    """Everything the causes read, per measurement (n rows).

    frame : validated measurements with residual columns (see ``residuals.ModelResiduals``)
    measured, base : (n, 2) measured and model-predicted areas [mm²] (flange, tread)
    floor : (2,) area floor [mm²]
    mileage_km : (n,) [km]
    c_s : (2,) calibration factors of the model; parts : route measures by part
    measure_index : index of the model's measure in ``wear_tables.MEASURES``
    lead_share : (n,) nominal leading share; mode : (n,) running mode per row
    left_right : (n, 2) the route's left / right curve shares
    route : (n,) route names; lubricated : (n,) bool or None when no attribute is known
    shape_res : (n, g) wear-curve shape residuals [mm] or None; basis : (3, g)
    """

    frame: pd.DataFrame
    measured: Array
    base: Array
    floor: Array
    mileage_km: Array
    c_s: Array
    parts: Array
    measure_index: int
    lead_share: Array
    mode: NDArray[Any]
    left_right: Array
    route: NDArray[Any]
    lubricated: NDArray[np.bool_] | None
    shape_res: Array | None
    basis: Array

    @property
    def n(self) -> int:
        return int(self.measured.shape[0])

    def column(self, name: str) -> pd.Series | None:
        return self.frame[name] if name in self.frame.columns else None


@dataclass(frozen=True)
class Fit:
    """Fitted parameters of one extension: ``params`` (public, JSON-able) and internals."""

    params: dict[str, Any]
    log_scale: Array                      # (2,) per-region log scale b_r
    theta: Any = None


# --- fitting helpers --------------------------------------------------------------------------

def _phi(pred: Array, floor: Array) -> Array:
    p = np.clip(pred, 0.0, None)
    return p / (p + floor[None, :])


def fit_scale(data: FinderData, pred: Array, train: Mask) -> Array:
    """Per-region log scale b_r minimising the linearised squared log residual on ``train``."""
    e0 = log_residual(data.measured, pred, data.floor)[train]
    ph = _phi(pred, data.floor)[train]
    den = np.sum(ph * ph, axis=0)
    return np.where(den > 0, np.sum(ph * e0, axis=0) / np.where(den > 0, den, 1.0), 0.0)


def scaled(pred: Array, log_scale: Array) -> Array:
    return pred * np.exp(log_scale)[None, :]


def row_sse(data: FinderData, pred: Array) -> Array:
    """Exact squared floored log residual per measurement, summed over the two regions."""
    return np.sum(log_residual(data.measured, pred, data.floor) ** 2, axis=1)


def fit_log_linear(data: FinderData, features: Array, train: Mask) -> tuple[Array, Array]:
    """Least squares of e on phi (b_r + x_r theta). features: (n, 2, k). Returns (b, theta)."""
    n, _, k = features.shape
    e0 = log_residual(data.measured, data.base, data.floor)
    ph = _phi(data.base, data.floor)
    design = np.zeros((n, 2, 2 + k))
    design[:, 0, 0] = 1.0
    design[:, 1, 1] = 1.0
    design[:, :, 2:] = features
    design = design * ph[:, :, None]
    x = design[train].reshape(-1, 2 + k)
    y = e0[train].reshape(-1)
    keep = np.any(x != 0, axis=1)
    coef, *_ = np.linalg.lstsq(x[keep], y[keep], rcond=None)
    return coef[:2], coef[2:]


def grid_search(data: FinderData, train: Mask, predict: Any, grid: Array) -> tuple[float, Array]:
    """1-D grid search over theta with the scales in closed form; returns (theta, b)."""
    best = (np.inf, float(grid[0]), np.zeros(2))
    for theta in grid:
        pred = predict(float(theta))
        b = fit_scale(data, pred, train)
        sse = float(np.sum(row_sse(data, scaled(pred, b))[train]))
        if sse < best[0]:
            best = (sse, float(theta), b)
    return best[1], best[2]


# --- the catalogue ----------------------------------------------------------------------------

class Cause:
    """Base class: a model extension with a plain-language explanation."""

    code: ClassVar[str] = ""
    needs: ClassVar[tuple[str, ...]] = ()
    explanation: ClassVar[str] = ""
    metric: ClassVar[str] = "area"          # 'area' (log-area residual) or 'shape' (wear curve)
    covariate_name: ClassVar[str] = ""

    def skip_reason(self, data: FinderData) -> str | None:
        raise NotImplementedError

    def covariate(self, data: FinderData) -> NDArray[Any]:
        """The covariate the residuals are plotted against (and tested at its level)."""
        col = data.column(self.covariate_name)
        return np.asarray(col if col is not None else np.zeros(data.n))

    def fit(self, data: FinderData, train: Mask) -> Fit:
        raise NotImplementedError

    def predict(self, data: FinderData, fit: Fit) -> Array:
        """Predicted (n, 2) areas [mm²] of the extended model, scales included."""
        raise NotImplementedError

    def describe(self, fit: Fit) -> str:
        return ""


class NullArea(Cause):
    """No extension: the model with its per-region scale refitted (the comparison baseline)."""

    code = "none"

    def skip_reason(self, data: FinderData) -> str | None:
        return None

    def fit(self, data: FinderData, train: Mask) -> Fit:
        b = fit_scale(data, data.base, train)
        return Fit({}, b)

    def predict(self, data: FinderData, fit: Fit) -> Array:
        return scaled(data.base, fit.log_scale)


class LogLinearCause(Cause):
    """A cause whose log rate factor is linear in its parameters: log g_r = x_r theta."""

    param_names: ClassVar[tuple[str, ...]] = ()

    def features(self, data: FinderData) -> Array:
        raise NotImplementedError

    def fit(self, data: FinderData, train: Mask) -> Fit:
        b, theta = fit_log_linear(data, self.features(data), train)
        return Fit(self.public(theta), b, theta)

    def public(self, theta: Array) -> dict[str, Any]:
        return {k: float(v) for k, v in zip(self.param_names, theta, strict=True)}

    def predict(self, data: FinderData, fit: Fit) -> Array:
        log_g = np.einsum("nrk,k->nr", self.features(data), np.asarray(fit.theta, dtype=float))
        return scaled(data.base * np.exp(log_g), fit.log_scale)


def _levels(values: NDArray[Any]) -> list[Any]:
    return sorted({str(v) for v in values if pd.notna(v) and str(v) != ""})


class Traction(LogLinearCause):
    code = "traction"
    needs = ("bogie_type",)
    covariate_name = "bogie_type"
    explanation = ("Powered (and braked) bogies wear their treads faster than the curve-radius "
                   "table says: traction and braking creep add tread wear (seed 001 §5).")
    param_names = ("log_tread_multiplier_motor",)

    def skip_reason(self, data: FinderData) -> str | None:
        levels = _levels(data.frame["bogie_type"].to_numpy())
        if "motor" not in levels or len(levels) < 2:
            return "needs motor and non-motor bogies in the data (bogie_type)"
        return None

    def features(self, data: FinderData) -> Array:
        x = np.zeros((data.n, 2, 1))
        x[:, 1, 0] = (data.frame["bogie_type"].astype(str) == "motor").to_numpy()
        return x

    def public(self, theta: Array) -> dict[str, Any]:
        return {"tread_multiplier_motor": float(np.exp(theta[0]))}

    def describe(self, fit: Fit) -> str:
        m = fit.params["tread_multiplier_motor"]
        return f"motor-bogie treads wear {m:.2f} x the rate of the other bogies' treads"


class VehicleLoad(LogLinearCause):
    code = "vehicle_load"
    needs = ("load_t",)
    covariate_name = "load_t"
    explanation = ("Heavier vehicles wear faster: the wear rate scales as (load / load_ref)^gamma "
                   "(Archard-type laws are proportional to the normal load, seeds 000/002).")

    def _load(self, data: FinderData) -> Array | None:
        col = data.column("load_t")
        if col is None:
            return None
        return pd.to_numeric(col, errors="coerce").to_numpy(dtype=float)

    def skip_reason(self, data: FinderData) -> str | None:
        load = self._load(data)
        if load is None or not np.all(np.isfinite(load)) or np.any(load <= 0):
            return "needs a positive load_t on every measurement"
        if load.max() / load.min() < 1.05:
            return "load_t is (nearly) constant: less than 5 % spread"
        return None

    def features(self, data: FinderData) -> Array:
        load = self._load(data)
        assert load is not None
        x = np.log(load / np.median(load))
        return np.repeat(x[:, None, None], 2, axis=1)

    def fit(self, data: FinderData, train: Mask) -> Fit:
        out = super().fit(data, train)
        load = self._load(data)
        assert load is not None
        out.params["load_ref_t"] = float(np.median(load))
        return out

    def public(self, theta: Array) -> dict[str, Any]:
        return {"gamma": float(theta[0])}

    def describe(self, fit: Fit) -> str:
        return (f"wear rate ~ (load / {fit.params['load_ref_t']:.1f} t)^"
                f"{fit.params['gamma']:.2f}")


class NonlinearProgression(LogLinearCause):
    code = "nonlinear_progression"
    needs = ("mileage_km",)
    covariate_name = "mileage_km"
    explanation = ("The wear rate changes with mileage as profiles conform or harden: "
                   "A = c P s_ref (s / s_ref)^beta per region instead of linear growth "
                   "(seed 003 §6, seed 001 §2.3).")

    def skip_reason(self, data: FinderData) -> str | None:
        s = data.mileage_km[data.mileage_km > 0]
        if s.size < 4 or s.max() / s.min() < 2.0:
            return "needs mileages spanning at least a factor 2"
        return None

    def _ref(self, data: FinderData) -> float:
        return float(np.median(data.mileage_km[data.mileage_km > 0]))

    def features(self, data: FinderData) -> Array:
        s = data.mileage_km
        x = np.where(s > 0, np.log(np.maximum(s, 1e-9) / self._ref(data)), 0.0)
        out = np.zeros((data.n, 2, 2))
        out[:, 0, 0] = x
        out[:, 1, 1] = x
        return out

    def fit(self, data: FinderData, train: Mask) -> Fit:
        out = super().fit(data, train)
        out.params["reference_mileage_km"] = self._ref(data)
        return out

    def public(self, theta: Array) -> dict[str, Any]:
        return {"beta_flange": 1.0 + float(theta[0]), "beta_tread": 1.0 + float(theta[1])}

    def describe(self, fit: Fit) -> str:
        p = fit.params
        return (f"wear area grows as mileage^{p['beta_flange']:.2f} (flange) and "
                f"^{p['beta_tread']:.2f} (tread) instead of linearly")


def season_features(frame: pd.DataFrame, mileage_km: Array) -> Array | None:
    """Mileage-weighted mean of cos/sin(w t) since reprofiling, per measurement (n, 2).

    Each wheel's mileage is assumed to accrue uniformly in time; its km/day comes from its
    own dated history (fleet median when it has one measurement) and places its
    reprofiling date. Returns None when dates are missing or unparseable.
    """
    if "measured_on" not in frame.columns:
        return None
    dates = pd.to_datetime(frame["measured_on"], errors="coerce")
    if dates.isna().any():
        return None
    day = ((dates - pd.Timestamp("1970-01-01")).dt.total_seconds() / 86400.0).to_numpy()
    wheel = frame["wheel_id"].astype(str).to_numpy()
    speeds = {}
    for w in np.unique(wheel):
        idx = np.flatnonzero(wheel == w)
        span = day[idx].max() - day[idx].min()
        if span > 0:
            speeds[w] = (mileage_km[idx].max() - mileage_km[idx].min()) / span
    positive = [v for v in speeds.values() if v > 0]
    default = float(np.median(positive)) if positive else 500.0
    out = np.zeros((len(frame), 2))
    for w in np.unique(wheel):
        idx = np.flatnonzero(wheel == w)
        v = speeds.get(w, default)
        v = v if v > 0 else default
        end = day[idx]
        start = end - mileage_km[idx] / v
        dur = np.maximum(end - start, 1e-9)
        wa, wb = OMEGA_PER_DAY * start, OMEGA_PER_DAY * end
        cos_mean = (np.sin(wb) - np.sin(wa)) / (OMEGA_PER_DAY * dur)
        sin_mean = (np.cos(wa) - np.cos(wb)) / (OMEGA_PER_DAY * dur)
        short = (end - start) < 1.0
        out[idx, 0] = np.where(short, np.cos(wb), cos_mean)
        out[idx, 1] = np.where(short, np.sin(wb), sin_mean)
    return out


class SeasonalFriction(LogLinearCause):
    code = "seasonal_friction"
    needs = ("measured_on",)
    covariate_name = "measured_on"
    explanation = ("Rail-wheel friction, and with it the wear rate, follows the season (leaves, "
                   "moisture, temperature): rate x exp(a cos wt + b sin wt) over the days a "
                   "wheel ran, w = 2 pi / 365.25 days.")

    def skip_reason(self, data: FinderData) -> str | None:
        x = season_features(data.frame, data.mileage_km)
        if x is None:
            return "needs a measured_on date on every measurement"
        dates = pd.to_datetime(data.frame["measured_on"])
        if (dates.max() - dates.min()).days < 180 or np.ptp(x[:, 0]) + np.ptp(x[:, 1]) < 0.2:
            return "measurement dates span less than half a year"
        return None

    def features(self, data: FinderData) -> Array:
        x = season_features(data.frame, data.mileage_km)
        assert x is not None
        # centred within each wheel: only the within-wheel seasonal pattern is attributed to
        # the season, so differences between units (start dates) cannot mimic it
        wheel = data.frame["wheel_id"].astype(str)
        x = x - pd.DataFrame(x).groupby(wheel.to_numpy()).transform("mean").to_numpy()
        return np.repeat(x[:, None, :], 2, axis=1)

    def public(self, theta: Array) -> dict[str, Any]:
        amp = float(np.hypot(theta[0], theta[1]))
        peak = (np.degrees(np.arctan2(theta[1], theta[0])) % 360.0) / 360.0 * 365.25
        return {"a_cos": float(theta[0]), "b_sin": float(theta[1]), "amplitude": amp,
                "peak_day_of_year": float(peak)}

    def covariate(self, data: FinderData) -> NDArray[Any]:
        x = season_features(data.frame, data.mileage_km)
        return x[:, 0] if x is not None else np.zeros(data.n)

    def describe(self, fit: Fit) -> str:
        p = fit.params
        return (f"wear rate varies by about +/-{100 * p['amplitude']:.0f} % over the year, "
                f"highest near day {p['peak_day_of_year']:.0f}")


def lubrication_flags(frame: pd.DataFrame, route: NDArray[Any],
                      route_attributes: Mapping[str, Mapping[str, Any]] | None
                      ) -> NDArray[np.bool_] | None:
    """Per-measurement flange-lubrication flag from a column or the route's attributes.

    Looks for a column, else a route attribute, whose name contains ``lubric``; truthy values
    are true/yes/on/1 (any case). None when neither is known.
    """
    def truthy(v: Any) -> bool:
        if isinstance(v, str):
            return v.strip().lower() in ("true", "yes", "on", "1", "y", "lubricated")
        return bool(v) if pd.notna(v) else False

    cols = [c for c in frame.columns if "lubric" in str(c).lower()]
    if cols:
        return np.array([truthy(v) for v in frame[cols[0]]], dtype=bool)
    if not route_attributes:
        return None
    flags: dict[str, bool] = {}
    for name, attrs in route_attributes.items():
        keys = [k for k in (attrs or {}) if "lubric" in str(k).lower()]
        if keys:
            flags[str(name)] = truthy(attrs[keys[0]])
    if not flags:
        return None
    return np.array([flags.get(str(r), False) for r in route], dtype=bool)


class FlangeLubrication(LogLinearCause):
    code = "flange_lubrication"
    needs = ("route attributes (flange_lubrication)",)
    covariate_name = "lubricated"
    explanation = ("Flange lubrication lowers friction at the flange contact: lubricated routes "
                   "wear flanges at a fraction m of the table's rate.")

    def skip_reason(self, data: FinderData) -> str | None:
        if data.lubricated is None:
            return "no route attribute or column says which routes are lubricated"
        if data.lubricated.all() or not data.lubricated.any():
            return "all measurements share one lubrication state"
        return None

    def covariate(self, data: FinderData) -> NDArray[Any]:
        assert data.lubricated is not None
        return np.where(data.lubricated, "lubricated", "dry")

    def features(self, data: FinderData) -> Array:
        assert data.lubricated is not None
        x = np.zeros((data.n, 2, 1))
        x[:, 0, 0] = data.lubricated
        return x

    def public(self, theta: Array) -> dict[str, Any]:
        return {"flange_multiplier_lubricated": float(np.exp(theta[0]))}

    def describe(self, fit: Fit) -> str:
        m = fit.params["flange_multiplier_lubricated"]
        return f"flanges on lubricated routes wear {m:.2f} x the dry rate"


def coordinate_grid_search(data: FinderData, train: Mask, start: Mapping[str, float],
                           predict: Callable[[Mapping[str, float]], Array], *, sweeps: int
                           ) -> tuple[dict[str, float], Array]:
    """Fit one share in [0, 1] per key by grid search, one key at a time, ``sweeps`` times.

    Returns the fitted shares and the region log-scales of the last search.
    """
    theta = dict(start)
    b = np.zeros(2)
    for _ in range(sweeps):
        for key in theta:
            def pred(value: float, key: str = key) -> Array:
                return predict({**theta, key: value})
            theta[key], b = grid_search(data, train, pred, GRID_01)
    return theta, b


class RunningDirection(Cause):
    code = "running_direction"
    needs = ("axle", "running_mode")
    covariate_name = "axle"
    explanation = ("The real leading/trailing mix differs from the model's: axle 1 leads a "
                   "share p of the distance, P = p P_lead + (1 - p) P_trail (seed 001 §4).")

    def _groups(self, data: FinderData) -> list[str]:
        return sorted({str(m) for m in data.mode})

    def skip_reason(self, data: FinderData) -> str | None:
        axles = set(data.frame["axle"].astype(int))
        if not {1, 2} <= axles:
            return "needs wheels on both axles (1 and 2)"
        return None

    def _pred(self, data: FinderData, shares: Mapping[str, float]) -> Array:
        axle = data.frame["axle"].to_numpy()
        lead = data.lead_share.copy()
        for g, p in shares.items():
            sel = data.mode == g
            lead[sel] = np.where(axle[sel] == 1, p, 1.0 - p)
        p_ = weighted_measure(data.parts, lead, data.measure_index)
        return data.c_s[None, :] * p_ * data.mileage_km[:, None]

    def fit(self, data: FinderData, train: Mask) -> Fit:
        start = {g: (1.0 if g == "lead" else 0.5) for g in self._groups(data)}
        shares, b = coordinate_grid_search(data, train, start,
                                           lambda theta: self._pred(data, theta), sweeps=2)
        return Fit({f"axle1_leading_share_{g}": v for g, v in shares.items()}, b, dict(shares))

    def predict(self, data: FinderData, fit: Fit) -> Array:
        return scaled(self._pred(data, fit.theta), fit.log_scale)

    def describe(self, fit: Fit) -> str:
        return "; ".join(f"in {g} mode axle 1 leads {100 * p:.0f} % of the distance"
                         for g, p in fit.theta.items())


class CurveAsymmetry(Cause):
    code = "curve_asymmetry"
    needs = ("side", "route with left and right curves")
    covariate_name = "side"
    explanation = ("Left and right wheels see a different mix of curve directions than the "
                   "route description says: a share q of the curved length bends left.")

    def _routes(self, data: FinderData) -> list[str]:
        ok = (data.left_right[:, 0] > 0) & (data.left_right[:, 1] > 0)
        return sorted({str(r) for r in data.route[ok]})

    def skip_reason(self, data: FinderData) -> str | None:
        if set(data.frame["side"].astype(str)) != {"left", "right"}:
            return "needs wheels on both sides"
        if not self._routes(data):
            return "no route has both left- and right-hand curves"
        return None

    def _pred(self, data: FinderData, q: Mapping[str, float]) -> Array:
        lr = np.ones((data.n, 2))
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        total = left + right
        for name, share in q.items():
            sel = data.route == name
            lr[sel, 0] = share * total[sel] / left[sel]
            lr[sel, 1] = (1.0 - share) * total[sel] / right[sel]
        p_ = weighted_measure(data.parts, data.lead_share, data.measure_index, lr)
        return data.c_s[None, :] * p_ * data.mileage_km[:, None]

    def fit(self, data: FinderData, train: Mask) -> Fit:
        routes = self._routes(data)
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        start = {r: float((left / (left + right))[data.route == r][0]) for r in routes}
        q, b = coordinate_grid_search(data, train, start, lambda theta: self._pred(data, theta),
                                      sweeps=2 if len(start) > 1 else 1)
        return Fit({f"left_curve_share_{r}": v for r, v in q.items()}, b, dict(q))

    def predict(self, data: FinderData, fit: Fit) -> Array:
        return scaled(self._pred(data, fit.theta), fit.log_scale)

    def describe(self, fit: Fit) -> str:
        return "; ".join(f"on {r} {100 * v:.0f} % of the curved length bends left"
                         for r, v in fit.theta.items())


class WearMeasure(Cause):
    code = "wear_measure"
    needs = ("a wear table with both tau_max and t_gamma",)
    covariate_name = "p_tread"
    explanation = ("Wear follows the other wear measure (T_gamma instead of tau_max or the "
                   "reverse, seed 001 §3.3): P from the other measure, c_s refitted.")

    def skip_reason(self, data: FinderData) -> str | None:
        if not np.all(np.isfinite(data.parts[:, 1 - data.measure_index])):
            return "the wear table has only the model's measure"
        return None

    def _other(self, data: FinderData) -> Array:
        p_ = weighted_measure(data.parts, data.lead_share, 1 - data.measure_index)
        return p_ * data.mileage_km[:, None]

    def fit(self, data: FinderData, train: Mask) -> Fit:
        raw = self._other(data)
        # scale so that the fleet means match, then refine by the usual log scale
        ref = data.base[train].sum(axis=0)
        unit = np.where(raw[train].sum(axis=0) > 0, ref / np.maximum(raw[train].sum(axis=0),
                                                                     1e-300), 0.0)
        pred = raw * unit[None, :]
        b = fit_scale(data, pred, train)
        c_s = unit * np.exp(b)
        from wearcast.statistics.wear_tables import MEASURES
        return Fit({"measure": MEASURES[1 - data.measure_index],
                    "c_s_flange": float(c_s[0]), "c_s_tread": float(c_s[1])}, b, unit)

    def predict(self, data: FinderData, fit: Fit) -> Array:
        return scaled(self._other(data) * fit.theta[None, :], fit.log_scale)

    def describe(self, fit: Fit) -> str:
        return f"wear follows {fit.params['measure']} better than the model's measure"


class ProfileMisalignment(Cause):
    """Per-instrument geometric correction of the wear curve (scored on the wear-curve shape)."""

    code = "profile_misalignment"
    needs = ("instrument_id", "wear curves")
    covariate_name = "instrument_id"
    metric = "shape"
    explanation = ("One instrument's profiles carry a systematic geometric error that rigid "
                   "alignment does not remove (a lateral scale error, an offset between flange "
                   "and tread): its wear curves share a mileage-independent signature.")
    basis_names = ("lateral_scale", "flange_offset_mm", "lateral_shift_mm")

    def skip_reason(self, data: FinderData) -> str | None:
        if data.shape_res is None:
            return "no wear curves given"
        col = data.column("instrument_id")
        if col is None or len(_levels(col.to_numpy())) < 2:
            return "needs at least two instruments (instrument_id)"
        return None

    def _coef(self, data: FinderData, rows: Mask) -> Array:
        assert data.shape_res is not None
        d = data.shape_res[rows]
        if d.shape[0] == 0:
            return np.zeros(data.basis.shape[0])
        ok = np.isfinite(d)
        counts = ok.sum(axis=0)
        mean = np.where(counts > 0, np.nansum(np.where(ok, d, 0.0), axis=0)
                        / np.maximum(counts, 1), 0.0)
        x = data.basis.T * np.sqrt(counts)[:, None]
        coef, *_ = np.linalg.lstsq(x, mean * np.sqrt(counts), rcond=None)
        return coef

    def _reference(self, data: FinderData, inst: NDArray[Any], train: Mask) -> str:
        """The instrument the model's wear states came from: the calibration rows' most
        frequent instrument (else the most frequent one overall)."""
        cal = data.frame["in_calibration"].to_numpy(bool) if "in_calibration" in \
            data.frame.columns else np.zeros(data.n, dtype=bool)
        pool = inst[cal & train] if (cal & train).any() else inst[train]
        levels, counts = np.unique(pool.astype(str), return_counts=True)
        return str(levels[np.argmax(counts)])

    def fit(self, data: FinderData, train: Mask) -> Fit:
        inst = data.frame["instrument_id"].astype(str).to_numpy()
        coefs = {i: self._coef(data, train & (inst == i)) for i in _levels(inst)}
        params: dict[str, Any] = {
            "instruments": {i: dict(zip(self.basis_names, map(float, c), strict=True))
                            for i, c in coefs.items()}}
        ref = self._reference(data, inst, train)
        if ref in coefs:
            # the correction that brings each instrument onto the reference instrument
            params["reference_instrument"] = ref
            params["corrections"] = {
                i: dict(zip(self.basis_names, map(float, c - coefs[ref]), strict=True))
                for i, c in coefs.items()}
        return Fit(params, np.zeros(2), coefs)

    def correction(self, data: FinderData, fit: Fit) -> Array:
        inst = data.frame["instrument_id"].astype(str).to_numpy()
        out = np.zeros((data.n, data.basis.shape[1]))
        for i, c in fit.theta.items():
            out[inst == i] = c @ data.basis
        return out

    def predict(self, data: FinderData, fit: Fit) -> Array:
        return data.base

    def describe(self, fit: Fit) -> str:
        table = fit.params.get("corrections", fit.params["instruments"])
        worst = max(table.items(),
                    key=lambda kv: abs(kv[1]["lateral_scale"]) * 40 + abs(kv[1]["flange_offset_mm"])
                    + abs(kv[1]["lateral_shift_mm"]))
        p = worst[1]
        ref = fit.params.get("reference_instrument")
        return (f"instrument {worst[0]}"
                + (f" (relative to {ref})" if ref is not None else "")
                + f": lateral scale error {1000 * p['lateral_scale']:+.1f} "
                f"per mille, flange offset {p['flange_offset_mm']:+.3f} mm, "
                f"lateral shift {p['lateral_shift_mm']:+.3f} mm")


class NullShape(ProfileMisalignment):
    """Shape baseline: one common geometric correction for all instruments."""

    code = "none"

    def skip_reason(self, data: FinderData) -> str | None:
        return None

    def fit(self, data: FinderData, train: Mask) -> Fit:
        return Fit({}, np.zeros(2), self._coef(data, train))

    def correction(self, data: FinderData, fit: Fit) -> Array:
        return np.repeat((fit.theta @ data.basis)[None, :], data.n, axis=0)


def shape_row_sse(data: FinderData, correction: Array) -> Array:
    """Squared wear-curve shape residual per measurement after a correction [mm²·points]."""
    assert data.shape_res is not None
    d = data.shape_res - correction
    return np.nansum(d * d, axis=1)


#: The catalogue, in DESIGN.md order.
CATALOGUE: tuple[Cause, ...] = (
    Traction(), RunningDirection(), CurveAsymmetry(), FlangeLubrication(), WearMeasure(),
    NonlinearProgression(), SeasonalFriction(), VehicleLoad(), ProfileMisalignment(),
)
CAUSE_CODES = tuple(c.code for c in CATALOGUE)


def cause_by_code(code: str) -> Cause:
    for c in CATALOGUE:
        if c.code == code:
            return c
    raise ValueError(f"cause: unknown cause code {code!r}; known: {CAUSE_CODES}")


__all__ = ["CATALOGUE", "CAUSE_CODES", "Cause", "FinderData", "Fit", "NullArea", "NullShape",
           "REGIONS", "cause_by_code", "lubrication_flags", "season_features", "shape_row_sse"]
