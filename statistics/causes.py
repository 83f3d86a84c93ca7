"""The discrepancy finder's catalogue of causes: one estimator per cause code.

Every cause is a physically meaningful extension of the hybrid model of seed 001
(A_r = c_s,r P_r s per region r) written as a log rate factor g_r(theta) per measurement:
the extended model predicts A_r exp(b_r + g_r(theta)), b_r a free log-scale per region (the
null extension fits b_r alone, so no cause gains from merely re-estimating c_s).

============================  ===========================================================
``traction``                  tread rate x m on motor bogies (seed 001 §5: traction/braking)
``running_direction``         leading share p per running mode: P = p P_lead + (1-p) P_trail
``curve_asymmetry``           share q of the curved length bending left, per route
``flange_lubrication``        flange rate x m on routes or rows marked lubricated
``wear_measure``              P = P_model^(1-w) P_other^w: a blend of tau_max and T_gamma
``nonlinear_progression``     A = c P s_ref (s / s_ref)^beta per region (seed 003 §6)
``seasonal_friction``         rate x (1 + a cos wt + b sin wt) integrated over the calendar
                              days of every interval between measurements
``vehicle_load``              rate x (load / load_ref)^gamma
``profile_misalignment``      per-instrument wear-curve signature of a lateral scale error,
                              a flange-tread offset and a lateral shift (seed 000 §IV.A)
============================  ===========================================================

Each cause is ONE object in the scikit-learn estimator pattern: ``fit(data, rows)`` returns a
fitted copy (``theta_``, ``log_scale_``, ``cov_``), ``predict(data)`` the extended model's
areas and ``describe()`` the plain-language result; the saved extended model predicts by
the very same ``predict`` (``discrepancy.ExtendedModel``), so fitting and prediction cannot
disagree.

Fitting works on the log residual e = log((A_meas + a0) / (A_pred + a0)) linearised in the
log rate: e ~ phi (b + g(theta)), phi = A_pred / (A_pred + a0) (``residuals``). Causes whose
g is linear in theta are solved in closed form; the others (running direction, curve
asymmetry) by Gauss-Newton from the nominal value, with g evaluated exactly.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics.residuals import REGIONS, weighted_measure
from wearcast.statistics.wear_tables import MEASURES

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
OMEGA_PER_DAY = 2.0 * np.pi / 365.25


@dataclass(frozen=True)
class FinderData:
    """Everything the causes read, per measurement (n rows).

    frame : validated measurements with residual columns (see ``residuals.ModelResiduals``)
    measured, base : (n, 2) measured and model-predicted areas [mm²] (flange, tread)
    floor : (2,) area floor [mm²]; mileage_km : (n,) [km]
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
    cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def n(self) -> int:
        return int(self.measured.shape[0])

    def column(self, name: str) -> pd.Series | None:
        return self.frame[name] if name in self.frame.columns else None

    @property
    def e(self) -> Array:
        """(n, 2) log residual of the measured against the base model's areas."""
        if "e" not in self.cache:
            m = np.clip(self.measured, 0.0, None)
            p = np.clip(self.base, 0.0, None)
            self.cache["e"] = np.asarray(np.log((m + self.floor) / (p + self.floor)))
        return np.asarray(self.cache["e"])

    @property
    def phi(self) -> Array:
        """(n, 2) d e / d log(rate) at the base prediction: A_pred / (A_pred + a0)."""
        if "phi" not in self.cache:
            p = np.clip(self.base, 0.0, None)
            self.cache["phi"] = np.asarray(p / (p + self.floor[None, :]))
        return np.asarray(self.cache["phi"])

    def season(self) -> Array | None:
        """``season_features`` of the data, computed once."""
        if "season" not in self.cache:
            self.cache["season"] = season_features(self.frame, self.mileage_km)
        return self.cache["season"]  # type: ignore[no-any-return]


# --- linear algebra of the working residual -----------------------------------------------

def solve(data: FinderData, target: Array, features: Array, rows: Mask,
          weights: Array | None = None) -> tuple[Array, Array]:
    """Least squares of ``target`` (n, 2) on phi (b_r + x theta) over ``rows``.

    features : (n, 2, k). Returns (b (2,), theta (k,)).
    """
    n, _, k = features.shape
    ph = data.phi
    design = np.zeros((n, 2, 2 + k))
    design[:, 0, 0] = 1.0
    design[:, 1, 1] = 1.0
    design[:, :, 2:] = features
    design = design * ph[:, :, None]
    x = design[rows].reshape(-1, 2 + k)
    y = target[rows].reshape(-1)
    if weights is not None:
        w = np.sqrt(weights[rows].reshape(-1))
        x, y = x * w[:, None], y * w
    keep = np.any(x != 0, axis=1)
    coef, *_ = np.linalg.lstsq(x[keep], y[keep], rcond=None)
    return coef[:2], coef[2:]


def cluster_covariance(data: FinderData, residual: Array, features: Array,
                       cluster: NDArray[Any]) -> Array:
    """Cluster-robust (vehicle) covariance of (b, theta) of ``solve`` (CR1, Liang-Zeger).

    residual : (n, 2) working residual after the fit; features : (n, 2, k).
    """
    n, _, k = features.shape
    design = np.zeros((n, 2, 2 + k))
    design[:, 0, 0] = 1.0
    design[:, 1, 1] = 1.0
    design[:, :, 2:] = features
    design = design * data.phi[:, :, None]
    x = design.reshape(-1, 2 + k)
    u = residual.reshape(-1)
    codes = np.repeat(pd.factorize(pd.Series(cluster).astype(str))[0], 2)
    g = int(codes.max()) + 1
    bread = np.linalg.pinv(x.T @ x)
    scores = np.zeros((g, 2 + k))
    np.add.at(scores, codes, x * u[:, None])
    meat = scores.T @ scores
    p = 2 + k
    corr = g / max(g - 1, 1) * (x.shape[0] - 1) / max(x.shape[0] - p, 1)
    return np.asarray(corr * bread @ meat @ bread)


# --- the estimator base class -----------------------------------------------------------------

class Cause:
    """Base class: a model extension g(theta) with a plain-language explanation.

    Fitted attributes (set by ``fit`` on a copy): ``theta_`` (k,), ``log_scale_`` (2,),
    ``cov_`` ((2 + k) x (2 + k) cluster-robust covariance of (b, theta) or None),
    ``n_groups_`` (clusters behind ``cov_``).
    """

    code: ClassVar[str] = ""
    needs: ClassVar[tuple[str, ...]] = ()
    explanation: ClassVar[str] = ""
    metric: ClassVar[str] = "area"          # 'area' (log-area residual) or 'shape' (wear curve)
    covariate_name: ClassVar[str] = ""
    linear: ClassVar[bool] = True           # g linear in theta (closed-form fit)
    gauss_newton_steps: ClassVar[int] = 3

    theta_: Array
    log_scale_: Array
    cov_: Array | None = None
    n_groups_: int = 0

    # -- to override
    def skip_reason(self, data: FinderData) -> str | None:
        raise NotImplementedError

    def prepare(self, data: FinderData, rows: Mask) -> None:
        """Set data-derived constants (reference load, mileage, groups) before a fit."""

    def start(self) -> Array:
        """Nominal theta (no effect)."""
        return np.zeros(len(self.param_names()))

    def param_names(self) -> list[str]:
        raise NotImplementedError

    def features(self, data: FinderData, theta: Array) -> Array:
        """(n, 2, k) derivative of the log rate factor by theta (at ``theta``)."""
        raise NotImplementedError

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        """(n, 2) exact log rate factor g(theta) (default: linear, features @ theta)."""
        return np.asarray(np.einsum("nrk,k->nr", self.features(data, theta), theta))

    def clip(self, theta: Array) -> Array:
        return theta

    def public(self) -> dict[str, Any]:
        """JSON-able fitted parameters (what the saved extension carries)."""
        return {k: float(v) for k, v in zip(self.param_names(), self.theta_, strict=True)}

    def intervals(self) -> dict[str, dict[str, float]]:
        """95 % intervals of the effect sizes: {name: {value, ci95_low, ci95_high}}."""
        return {k: _interval(v, self._se(i), self.n_groups_)
                for i, (k, v) in enumerate(zip(self.param_names(), self.theta_, strict=True))}

    def describe(self) -> str:
        return ""

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        """A fitted copy from saved public parameters (inverse of ``public``)."""
        raise NotImplementedError

    # -- shared
    def covariate(self, data: FinderData) -> NDArray[Any]:
        """The covariate the residuals are plotted against."""
        col = data.column(self.covariate_name)
        return np.asarray(col if col is not None else np.zeros(data.n))

    def _se(self, i: int) -> float:
        if self.cov_ is None:
            return float("nan")
        return float(np.sqrt(max(self.cov_[2 + i, 2 + i], 0.0)))

    def fit(self, data: FinderData, rows: Mask, offset: Array | None = None,
            cluster: NDArray[Any] | None = None) -> Cause:
        """Fit on ``rows``; ``offset`` (n, 2) is the log factor of causes already in the
        model (forward selection). ``cluster`` (n,) gives the cluster-robust ``cov_``."""
        est = copy.copy(self)
        est.prepare(data, rows)
        target = data.e - data.phi * (0.0 if offset is None else offset)
        theta = est.start()
        steps = 1 if est.linear else est.gauss_newton_steps
        b = np.zeros(2)
        for _ in range(steps):
            x = est.features(data, theta)
            g = est.log_factor(data, theta) if not est.linear else 0.0
            b, delta = solve(data, target - data.phi * g, x, rows)
            theta = est.clip(theta + delta if not est.linear else delta)
        if not est.linear:  # final scale at the clipped theta
            b, _ = solve(data, target - data.phi * est.log_factor(data, theta),
                         np.zeros((data.n, 2, 0)), rows)
        est.theta_, est.log_scale_ = np.asarray(theta, dtype=float), b
        if cluster is not None:
            x = est.features(data, theta)
            res = (target - data.phi * (b[None, :] + est.log_factor(data, theta)))
            res = np.where(rows[:, None], res, 0.0)
            xr = np.where(rows[:, None, None], x, 0.0)
            est.cov_ = cluster_covariance(data, res, xr, cluster)
            est.n_groups_ = int(pd.Series(np.asarray(cluster)[rows]).nunique())
        return est

    def predict(self, data: FinderData) -> Array:
        """Predicted (n, 2) areas [mm²] of the extended model, scales included."""
        g = self.log_factor(data, self.theta_)
        return np.asarray(data.base * np.exp(self.log_scale_[None, :] + g))


def _interval(value: float, se: float, groups: int, transform: Any = None) -> dict[str, float]:
    from scipy import stats

    t = float(stats.t.ppf(0.975, max(groups - 1, 1))) if groups else float("nan")
    lo, hi = value - t * se, value + t * se
    f = transform or (lambda v: v)
    a, b = float(f(lo)), float(f(hi))
    return {"value": float(f(value)), "ci95_low": min(a, b), "ci95_high": max(a, b),
            "std_error": float(se)}


def _levels(values: NDArray[Any]) -> list[str]:
    return sorted({str(v) for v in values if pd.notna(v) and str(v) != ""})


class NullArea(Cause):
    """No extension: the model with its per-region scale refitted (the comparison baseline)."""

    code = "none"

    def skip_reason(self, data: FinderData) -> str | None:
        return None

    def param_names(self) -> list[str]:
        return []

    def features(self, data: FinderData, theta: Array) -> Array:
        return np.zeros((data.n, 2, 0))

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_, est.log_scale_ = np.zeros(0), np.zeros(2)
        return est


class Traction(Cause):
    code = "traction"
    needs = ("bogie_type",)
    covariate_name = "bogie_type"
    explanation = ("Powered (and braked) bogies wear their treads faster than the curve-radius "
                   "table says: traction and braking creep add tread wear (seed 001 §5).")

    def skip_reason(self, data: FinderData) -> str | None:
        levels = _levels(data.frame["bogie_type"].to_numpy())
        if "motor" not in levels or len(levels) < 2:
            return "needs motor and non-motor bogies in the data (bogie_type)"
        return None

    def param_names(self) -> list[str]:
        return ["log_tread_multiplier_motor"]

    def features(self, data: FinderData, theta: Array) -> Array:
        x = np.zeros((data.n, 2, 1))
        col = data.column("bogie_type")
        if col is not None:
            x[:, 1, 0] = (col.astype(str) == "motor").to_numpy()
        return x

    def public(self) -> dict[str, Any]:
        return {"tread_multiplier_motor": float(np.exp(self.theta_[0]))}

    def intervals(self) -> dict[str, dict[str, float]]:
        return {"tread_multiplier_motor": _interval(self.theta_[0], self._se(0), self.n_groups_,
                                                    np.exp)}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([np.log(float(params["tread_multiplier_motor"]))])
        return est

    def describe(self) -> str:
        return (f"motor-bogie treads wear {self.public()['tread_multiplier_motor']:.2f} x the "
                "rate of the other bogies' treads")


class VehicleLoad(Cause):
    code = "vehicle_load"
    needs = ("load_t",)
    covariate_name = "load_t"
    explanation = ("Heavier vehicles wear faster: the wear rate scales as (load / load_ref)^gamma "
                   "(Archard-type laws are proportional to the normal load, seeds 000/002).")
    load_ref_t: float = 14.0

    @staticmethod
    def _load(data: FinderData) -> Array | None:
        col = data.column("load_t")
        if col is None:
            return None
        return np.asarray(pd.to_numeric(col, errors="coerce").to_numpy(dtype=float))

    def skip_reason(self, data: FinderData) -> str | None:
        load = self._load(data)
        if load is None or not np.all(np.isfinite(load)) or np.any(load <= 0):
            return "needs a positive load_t on every measurement"
        if load.max() / load.min() < 1.05:
            return "load_t is (nearly) constant: less than 5 % spread"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        load = self._load(data)
        assert load is not None
        self.load_ref_t = float(np.median(load[rows]))

    def param_names(self) -> list[str]:
        return ["gamma"]

    def features(self, data: FinderData, theta: Array) -> Array:
        load = self._load(data)
        x = np.zeros((data.n, 2, 1))
        if load is not None:
            ok = np.isfinite(load) & (load > 0)
            x[ok, :, 0] = np.log(load[ok] / self.load_ref_t)[:, None]
        return x

    def public(self) -> dict[str, Any]:
        return {"gamma": float(self.theta_[0]), "load_ref_t": self.load_ref_t}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([float(params["gamma"])])
        est.load_ref_t = float(params["load_ref_t"])
        return est

    def describe(self) -> str:
        return f"wear rate ~ (load / {self.load_ref_t:.1f} t)^{self.theta_[0]:.2f}"


class NonlinearProgression(Cause):
    code = "nonlinear_progression"
    needs = ("mileage_km",)
    covariate_name = "mileage_km"
    explanation = ("The wear rate changes with mileage as profiles conform or harden: "
                   "A = c P s_ref (s / s_ref)^beta per region instead of linear growth "
                   "(seed 003 §6, seed 001 §2.3).")
    reference_mileage_km: float = 100_000.0

    def skip_reason(self, data: FinderData) -> str | None:
        s = data.mileage_km[data.mileage_km > 0]
        if s.size < 4 or s.max() / s.min() < 2.0:
            return "needs mileages spanning at least a factor 2"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        s = data.mileage_km[rows & (data.mileage_km > 0)]
        self.reference_mileage_km = float(np.median(s)) if s.size else 100_000.0

    def param_names(self) -> list[str]:
        return ["beta_flange_minus_1", "beta_tread_minus_1"]

    def features(self, data: FinderData, theta: Array) -> Array:
        s = data.mileage_km
        x = np.where(s > 0, np.log(np.maximum(s, 1e-9) / self.reference_mileage_km), 0.0)
        out = np.zeros((data.n, 2, 2))
        out[:, 0, 0] = x
        out[:, 1, 1] = x
        return out

    def public(self) -> dict[str, Any]:
        return {"beta_flange": 1.0 + float(self.theta_[0]),
                "beta_tread": 1.0 + float(self.theta_[1]),
                "reference_mileage_km": self.reference_mileage_km}

    def intervals(self) -> dict[str, dict[str, float]]:
        return {f"beta_{r}": _interval(self.theta_[i], self._se(i), self.n_groups_,
                                       lambda v: 1.0 + v) for i, r in enumerate(REGIONS)}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([float(params["beta_flange"]) - 1.0,
                               float(params["beta_tread"]) - 1.0])
        est.reference_mileage_km = float(params["reference_mileage_km"])
        return est

    def describe(self) -> str:
        p = self.public()
        return (f"wear area grows as mileage^{p['beta_flange']:.2f} (flange) and "
                f"^{p['beta_tread']:.2f} (tread) instead of linearly")


def _day_numbers(values: pd.Series) -> Array | None:
    dates = pd.to_datetime(values, errors="coerce")
    if dates.isna().any():
        return None
    return np.asarray((dates - pd.Timestamp("1970-01-01")).dt.total_seconds().to_numpy()
                      / 86400.0, dtype=float)


def life_ids(frame: pd.DataFrame, mileage_km: Array) -> NDArray[Any]:
    """Per measurement, the wheel's life since its last reprofiling: ``wheel_id`` plus a
    counter that increases whenever the mileage since reprofiling falls (a reprofiling in
    the middle of a series; rows ordered by date when dated, else by mileage)."""
    wheel = frame["wheel_id"].astype(str).to_numpy()
    day = _day_numbers(frame["measured_on"]) if "measured_on" in frame.columns else None
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
    if "measured_on" not in frame.columns:
        return None
    day = _day_numbers(frame["measured_on"])
    if day is None:
        return None
    s = np.asarray(mileage_km, dtype=float)
    life = life_ids(frame, s)
    reprofiled = _day_numbers(frame["reprofiled_on"]) if "reprofiled_on" in frame.columns \
        else None
    groups = pd.Series(np.arange(len(frame))).groupby(life).indices
    speeds: dict[Any, float] = {}
    for key, idx in groups.items():
        idx = idx[np.lexsort((s[idx], day[idx]))]
        dd, ds = np.diff(day[idx]), np.diff(s[idx])
        ok = (dd > 0) & (ds > 0)
        if ok.any():
            speeds[key] = float(np.median(ds[ok] / dd[ok]))
    fleet_v = float(np.median(list(speeds.values()))) if speeds else 500.0
    w = OMEGA_PER_DAY
    out = np.zeros((len(frame), 2))
    for key, idx in groups.items():
        idx = idx[np.lexsort((s[idx], day[idx]))]
        v = speeds.get(key, fleet_v)
        t_end = day[idx]
        start = t_end[0] - s[idx[0]] / max(v, 1e-9)
        if reprofiled is not None and np.isfinite(reprofiled[idx[0]]):
            start = float(reprofiled[idx[0]])
        t_start = np.concatenate([[start], t_end[:-1]])
        inc = np.diff(np.concatenate([[0.0], s[idx]]))
        inc = np.maximum(inc, 0.0)
        dur = t_end - t_start
        long_ = dur >= 1.0
        cos_m = np.where(long_, (np.sin(w * t_end) - np.sin(w * t_start))
                         / (w * np.where(long_, dur, 1.0)), np.cos(w * t_end))
        sin_m = np.where(long_, (np.cos(w * t_start) - np.cos(w * t_end))
                         / (w * np.where(long_, dur, 1.0)), np.sin(w * t_end))
        total = np.cumsum(inc)
        safe = np.where(total > 0, total, 1.0)
        out[idx, 0] = np.where(total > 0, np.cumsum(inc * cos_m) / safe, 0.0)
        out[idx, 1] = np.where(total > 0, np.cumsum(inc * sin_m) / safe, 0.0)
    return out


class SeasonalFriction(Cause):
    code = "seasonal_friction"
    needs = ("measured_on",)
    covariate_name = "measured_on"
    explanation = ("Rail-wheel friction, and with it the wear rate, follows the season (leaves, "
                   "moisture, temperature): rate x (1 + a cos wt + b sin wt), integrated over "
                   "the calendar days of every interval between measurements, "
                   "w = 2 pi / 365.25 days.")

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
        x = data.season()
        if x is None:
            return np.zeros((data.n, 2, 2))
        return np.repeat(x[:, None, :], 2, axis=1)

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
            se = float(np.sqrt(max(grad @ self.cov_[2:4, 2:4] @ grad, 0.0)))
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


def lubrication_flags(frame: pd.DataFrame, route: NDArray[Any],
                      route_attributes: Mapping[str, Mapping[str, Any]] | None
                      ) -> NDArray[np.bool_] | None:
    """Per-measurement flange-lubrication flag from a column or the route's attributes.

    Looks for a column, else a route attribute, whose name contains ``lubric`` (e.g.
    ``flange_lubrication``, ``lubricated``); truthy values are true/yes/on/1/y/lubricated
    (any case). None when neither is known. The one reader of the attribute: the fit and
    the saved extension's prediction both go through it.
    """
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


def truthy(v: Any) -> bool:
    if isinstance(v, str):
        return v.strip().lower() in ("true", "yes", "on", "1", "y", "lubricated")
    try:
        return bool(v) if pd.notna(v) else False
    except (TypeError, ValueError):
        return bool(v)


class FlangeLubrication(Cause):
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
        flags = data.lubricated if data.lubricated is not None else np.zeros(data.n, bool)
        return np.where(flags, "lubricated", "dry")

    def param_names(self) -> list[str]:
        return ["log_flange_multiplier_lubricated"]

    def features(self, data: FinderData, theta: Array) -> Array:
        x = np.zeros((data.n, 2, 1))
        if data.lubricated is not None:
            x[:, 0, 0] = data.lubricated
        return x

    def public(self) -> dict[str, Any]:
        return {"flange_multiplier_lubricated": float(np.exp(self.theta_[0]))}

    def intervals(self) -> dict[str, dict[str, float]]:
        return {"flange_multiplier_lubricated": _interval(self.theta_[0], self._se(0),
                                                          self.n_groups_, np.exp)}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([np.log(float(params["flange_multiplier_lubricated"]))])
        return est

    def describe(self) -> str:
        m = self.public()["flange_multiplier_lubricated"]
        return f"flanges on lubricated routes wear {m:.2f} x the dry rate"


class RunningDirection(Cause):
    code = "running_direction"
    needs = ("axle", "running_mode")
    covariate_name = "axle"
    linear = False
    explanation = ("The real leading/trailing mix differs from the model's: axle 1 leads a "
                   "share p of the distance, P = p P_lead + (1 - p) P_trail (seed 001 §4).")
    modes: tuple[str, ...] = ()

    def skip_reason(self, data: FinderData) -> str | None:
        axles = set(data.frame["axle"].astype(int))
        if not {1, 2} <= axles:
            return "needs wheels on both axles (1 and 2)"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        self.modes = tuple(sorted({str(m) for m in data.mode}))

    def param_names(self) -> list[str]:
        return [f"axle1_leading_share_{m}" for m in self.modes]

    def start(self) -> Array:
        return np.array([1.0 if m == "lead" else 0.5 for m in self.modes])

    def clip(self, theta: Array) -> Array:
        return np.clip(theta, 0.0, 1.0)

    def _per_wheelset(self, data: FinderData) -> tuple[Array, Array]:
        block = data.parts[:, data.measure_index].sum(axis=3)   # (n, region, wheelset)
        return block[:, :, 0], block[:, :, 1]

    def _lead(self, data: FinderData, theta: Array) -> Array:
        axle = data.frame["axle"].to_numpy()
        lead = data.lead_share.copy()
        for m, p in zip(self.modes, theta, strict=True):
            sel = np.asarray(data.mode == m)
            lead[sel] = np.where(axle[sel] == 1, p, 1.0 - p)
        return lead

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        lp, tp = self._per_wheelset(data)
        lead = self._lead(data, theta)[:, None]
        new = lp * lead + tp * (1.0 - lead)
        nominal = lp * data.lead_share[:, None] + tp * (1.0 - data.lead_share[:, None])
        return np.asarray(np.where((new > 0) & (nominal > 0),
                                   np.log(np.maximum(new, 1e-300) / np.maximum(nominal, 1e-300)),
                                   0.0))

    def features(self, data: FinderData, theta: Array) -> Array:
        lp, tp = self._per_wheelset(data)
        lead = self._lead(data, theta)[:, None]
        p_now = lp * lead + tp * (1.0 - lead)
        axle = data.frame["axle"].to_numpy()
        sign = np.where(axle == 1, 1.0, -1.0)[:, None]
        d = np.where(p_now > 0, sign * (lp - tp) / np.where(p_now > 0, p_now, 1.0), 0.0)
        x = np.zeros((data.n, 2, len(self.modes)))
        for j, m in enumerate(self.modes):
            sel = np.asarray(data.mode == m)
            x[sel, :, j] = d[sel]
        return x

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        pre = "axle1_leading_share_"
        est.modes = tuple(k[len(pre):] for k in params if k.startswith(pre))
        est.theta_ = np.array([float(params[pre + m]) for m in est.modes])
        return est

    def describe(self) -> str:
        return "; ".join(f"in {m} mode axle 1 leads {100 * p:.0f} % of the distance"
                         for m, p in zip(self.modes, self.theta_, strict=True))


class CurveAsymmetry(Cause):
    code = "curve_asymmetry"
    needs = ("side", "route with left and right curves")
    covariate_name = "side"
    linear = False
    explanation = ("Left and right wheels see a different mix of curve directions than the "
                   "route description says: a share q of the curved length bends left.")
    routes: tuple[str, ...] = ()
    nominal: tuple[float, ...] = ()

    def _eligible(self, data: FinderData) -> list[str]:
        ok = (data.left_right[:, 0] > 0) & (data.left_right[:, 1] > 0)
        return sorted({str(r) for r in data.route[ok]})

    def skip_reason(self, data: FinderData) -> str | None:
        if set(data.frame["side"].astype(str)) != {"left", "right"}:
            return "needs wheels on both sides"
        if not self._eligible(data):
            return "no route has both left- and right-hand curves"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        self.routes = tuple(self._eligible(data))
        lr = data.left_right
        self.nominal = tuple(float((lr[:, 0] / (lr[:, 0] + lr[:, 1]))[data.route == r][0])
                             for r in self.routes)

    def param_names(self) -> list[str]:
        return [f"left_curve_share_{r}" for r in self.routes]

    def start(self) -> Array:
        return np.array(self.nominal, dtype=float)

    def clip(self, theta: Array) -> Array:
        return np.clip(theta, 0.0, 1.0)

    def _p(self, data: FinderData, lr: Array) -> Array:
        return weighted_measure(data.parts, data.lead_share, data.measure_index, lr)

    def _weights(self, data: FinderData, theta: Array) -> Array:
        lr = np.ones((data.n, 2))
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        total = left + right
        for name, q in zip(self.routes, theta, strict=True):
            sel = np.asarray(data.route == name)
            lr[sel, 0] = q * total[sel] / left[sel]
            lr[sel, 1] = (1.0 - q) * total[sel] / right[sel]
        return lr

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        new = self._p(data, self._weights(data, theta))
        nominal = self._p(data, np.ones((data.n, 2)))
        return np.asarray(np.where((new > 0) & (nominal > 0),
                                   np.log(np.maximum(new, 1e-300) / np.maximum(nominal, 1e-300)),
                                   0.0))

    def features(self, data: FinderData, theta: Array) -> Array:
        p_now = self._p(data, self._weights(data, theta))
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        total = left + right
        x = np.zeros((data.n, 2, len(self.routes)))
        only_left = weighted_measure(data.parts, data.lead_share, data.measure_index,
                                     np.column_stack([np.ones(data.n), np.zeros(data.n)]))
        only_right = weighted_measure(data.parts, data.lead_share, data.measure_index,
                                      np.column_stack([np.zeros(data.n), np.ones(data.n)]))
        tangent = weighted_measure(data.parts, data.lead_share, data.measure_index,
                                   np.zeros((data.n, 2)))
        lpart, rpart = only_left - tangent, only_right - tangent
        for j, name in enumerate(self.routes):
            sel = np.asarray(data.route == name)
            dp = (total[sel] / left[sel])[:, None] * lpart[sel] \
                - (total[sel] / right[sel])[:, None] * rpart[sel]
            x[sel, :, j] = np.where(p_now[sel] > 0, dp / np.where(p_now[sel] > 0,
                                                                   p_now[sel], 1.0), 0.0)
        return x

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        pre = "left_curve_share_"
        est.routes = tuple(k[len(pre):] for k in params if k.startswith(pre))
        est.theta_ = np.array([float(params[pre + r]) for r in est.routes])
        return est

    def describe(self) -> str:
        return "; ".join(f"on {r} {100 * v:.0f} % of the curved length bends left"
                         for r, v in zip(self.routes, self.theta_, strict=True))


class WearMeasure(Cause):
    code = "wear_measure"
    needs = ("a wear table with both tau_max and t_gamma",)
    covariate_name = "p_tread"
    explanation = ("Wear follows a blend of the two wear measures (seed 001 §3.3): "
                   "P = P_model^(1-w) P_other^w, w = 1 the other measure alone, c_s refitted.")
    other: str = ""

    def skip_reason(self, data: FinderData) -> str | None:
        if not np.all(np.isfinite(data.parts[:, 1 - data.measure_index])):
            return "the wear table has only the model's measure"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        self.other = MEASURES[1 - data.measure_index]

    def param_names(self) -> list[str]:
        return ["share_other_measure"]

    def features(self, data: FinderData, theta: Array) -> Array:
        m = data.measure_index
        if not np.all(np.isfinite(data.parts[:, 1 - m])):
            return np.zeros((data.n, 2, 1))
        own = weighted_measure(data.parts, data.lead_share, m)
        oth = weighted_measure(data.parts, data.lead_share, 1 - m)
        ok = (own > 0) & (oth > 0)
        x = np.where(ok, np.log(np.where(ok, oth, 1.0) / np.where(ok, own, 1.0)), 0.0)
        return np.asarray(x[:, :, None])

    def public(self) -> dict[str, Any]:
        return {"measure": self.other, "share_other_measure": float(self.theta_[0])}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.other = str(params["measure"])
        est.theta_ = np.array([float(params["share_other_measure"])])
        return est

    def describe(self) -> str:
        w = float(self.theta_[0])
        return (f"wear follows {100 * w:.0f} % {self.other} / {100 * (1 - w):.0f} % the model's "
                "measure (geometric blend)")


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
    coefs_: dict[str, Array]
    reference_: str | None = None

    def skip_reason(self, data: FinderData) -> str | None:
        if data.shape_res is None:
            return "no wear curves given"
        col = data.column("instrument_id")
        if col is None or len(_levels(col.to_numpy())) < 2:
            return "needs at least two instruments (instrument_id)"
        return None

    def param_names(self) -> list[str]:
        return []

    def features(self, data: FinderData, theta: Array) -> Array:
        return np.zeros((data.n, 2, 0))

    def instruments(self, data: FinderData) -> NDArray[Any]:
        col = data.column("instrument_id")
        return np.asarray(col.astype(str).to_numpy() if col is not None
                          else np.full(data.n, "?"), dtype=object)

    def _reference(self, data: FinderData, inst: NDArray[Any], rows: Mask) -> str:
        """The instrument the model's wear states came from: the calibration rows' most
        frequent instrument (else the most frequent one overall)."""
        cal = data.frame["in_calibration"].to_numpy(bool) if "in_calibration" in \
            data.frame.columns else np.zeros(data.n, dtype=bool)
        pool = inst[cal & rows] if (cal & rows).any() else inst[rows]
        levels, counts = np.unique(pool.astype(str), return_counts=True)
        return str(levels[np.argmax(counts)])

    def fit(self, data: FinderData, rows: Mask, offset: Array | None = None,
            cluster: NDArray[Any] | None = None) -> Cause:
        assert data.shape_res is not None
        est = copy.copy(self)
        inst = self.instruments(data)
        coef = shape_coefficients(data)
        est.coefs_ = {i: coef[rows & (inst == i)].mean(axis=0) if (rows & (inst == i)).any()
                      else np.zeros(3) for i in _levels(inst)}
        est.reference_ = self._reference(data, inst, rows)
        est.theta_, est.log_scale_ = np.zeros(0), np.zeros(2)
        return est

    def public(self) -> dict[str, Any]:
        params: dict[str, Any] = {
            "instruments": {i: dict(zip(self.basis_names, map(float, c), strict=True))
                            for i, c in self.coefs_.items()}}
        ref = self.reference_
        if ref in self.coefs_:
            params["reference_instrument"] = ref
            params["corrections"] = {
                i: dict(zip(self.basis_names, map(float, c - self.coefs_[ref]), strict=True))
                for i, c in self.coefs_.items()}
        return params

    def intervals(self) -> dict[str, dict[str, float]]:
        return {}

    def correction(self, data: FinderData) -> Array:
        """(n, g) fitted wear-curve signature of each row's instrument [mm]."""
        inst = self.instruments(data)
        out = np.zeros((data.n, data.basis.shape[1]))
        for i, c in self.coefs_.items():
            out[inst == i] = c @ data.basis
        return out

    def predict(self, data: FinderData) -> Array:
        return data.base

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.coefs_ = {i: np.array([v[k] for k in self.basis_names])
                      for i, v in params.get("instruments", {}).items()}
        est.reference_ = params.get("reference_instrument")
        est.theta_, est.log_scale_ = np.zeros(0), np.zeros(2)
        return est

    def describe(self) -> str:
        p = self.public()
        table = p.get("corrections", p["instruments"])
        worst = max(table.items(),
                    key=lambda kv: abs(kv[1]["lateral_scale"]) * 40 + abs(kv[1]["flange_offset_mm"])
                    + abs(kv[1]["lateral_shift_mm"]))
        q = worst[1]
        ref = p.get("reference_instrument")
        return (f"instrument {worst[0]}"
                + (f" (relative to {ref})" if ref is not None else "")
                + f": lateral scale error {1000 * q['lateral_scale']:+.1f} "
                f"per mille, flange offset {q['flange_offset_mm']:+.3f} mm, "
                f"lateral shift {q['lateral_shift_mm']:+.3f} mm")


def shape_coefficients(data: FinderData) -> Array:
    """(n, 3) least-squares coefficients of each row's shape residual on the geometric basis
    (lateral scale, flange offset, lateral shift); NaN points are left out."""
    assert data.shape_res is not None
    d = np.nan_to_num(data.shape_res, nan=0.0)
    coef, *_ = np.linalg.lstsq(data.basis.T, d.T, rcond=None)
    return np.asarray(coef.T)


class Composite(Cause):
    """Several area causes at once (forward selection): g = sum of the members' g, one
    log-scale per region; ``members_`` are the fitted members after ``fit``."""

    code = "composite"

    def __init__(self, members: tuple[Cause, ...]) -> None:
        self.members = members
        self.sizes: list[int] = []

    def skip_reason(self, data: FinderData) -> str | None:
        return None

    @property
    def linear(self) -> bool:  # type: ignore[override]
        return all(m.linear for m in self.members)

    def prepare(self, data: FinderData, rows: Mask) -> None:
        self.members = tuple(copy.copy(m) for m in self.members)
        for m in self.members:
            m.prepare(data, rows)
        self.sizes = [len(m.param_names()) for m in self.members]

    def _split(self, theta: Array) -> list[Array]:
        return np.split(np.asarray(theta, dtype=float), np.cumsum(self.sizes)[:-1]) \
            if self.sizes else []

    def param_names(self) -> list[str]:
        return [f"{m.code}.{k}" for m in self.members for k in m.param_names()]

    def start(self) -> Array:
        parts = [m.start() for m in self.members]
        return np.concatenate(parts) if parts else np.zeros(0)

    def clip(self, theta: Array) -> Array:
        parts = [m.clip(t) for m, t in zip(self.members, self._split(theta), strict=True)]
        return np.concatenate(parts) if parts else np.zeros(0)

    def features(self, data: FinderData, theta: Array) -> Array:
        parts = [m.features(data, t) for m, t in zip(self.members, self._split(theta),
                                                     strict=True)]
        return np.concatenate(parts, axis=2) if parts else np.zeros((data.n, 2, 0))

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        out = np.zeros((data.n, 2))
        for m, t in zip(self.members, self._split(theta), strict=True):
            out += m.log_factor(data, t)
        return out

    def fit(self, data: FinderData, rows: Mask, offset: Array | None = None,
            cluster: NDArray[Any] | None = None) -> Cause:
        est = super().fit(data, rows, offset, cluster)
        assert isinstance(est, Composite)
        fitted = []
        start = 0
        for m, k in zip(est.members, est.sizes, strict=True):
            f = copy.copy(m)
            f.theta_, f.log_scale_ = est.theta_[start:start + k], est.log_scale_
            if est.cov_ is not None:
                idx = np.r_[0, 1, 2 + start + np.arange(k)]
                f.cov_ = est.cov_[np.ix_(idx, idx)]
                f.n_groups_ = est.n_groups_
            fitted.append(f)
            start += k
        est.members = tuple(fitted)
        return est


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


__all__ = ["CATALOGUE", "CAUSE_CODES", "Cause", "Composite", "FinderData", "NullArea", "REGIONS",
           "cause_by_code", "life_ids", "lubrication_flags", "season_features",
           "shape_coefficients", "solve"]
