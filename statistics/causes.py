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
the very same ``predict`` (``extension.ExtendedModel``), so fitting and prediction cannot
disagree.

Fitting works on the log residual e = log((A_meas + a0) / (A_pred + a0)) linearised in the
log rate: e ~ phi (b + g(theta)), phi = A_pred / (A_pred + a0) (``residuals``). Causes whose
g is linear in theta are solved in closed form; the others (running direction, curve
asymmetry) by Gauss-Newton from the nominal value, with g evaluated exactly.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.cause_base import (
    Array,
    Cause,
    Composite,
    FinderData,
    Mask,
    NullArea,
    _interval,
    _levels,
    cluster_covariance,
    solve,
)
from wearcast.statistics.causes_calendar import (
    OMEGA_PER_DAY,
    SeasonalFriction,
    accrual_season_features,
    season_features,
)
from wearcast.statistics.causes_route import (
    CurveAsymmetry,
    ProfileMisalignment,
    RunningDirection,
    WearMeasure,
    shape_coefficients,
    signature_coefficients,
)
from wearcast.statistics.residuals import life_ids


class Traction(Cause):
    code = "traction"
    needs = ("bogie_type",)
    covariate_name = "bogie_type"
    explanation = ("Powered (and braked) bogies wear their treads faster than the curve-radius "
                   "table says: traction and braking creep add tread wear (seed 001 §5).")
    # the multiplier from the random-effects GLS fit with nested vehicle and wheel effects
    # (``finder_random_effects``): a car's motor and trailer bogies share its load, route
    # and calendar, so the contrast within the cars counts and the cars' own rate factors
    # (between the cars) count with the weight their scatter leaves them
    random_effects = True
    within_vehicle = True

    def skip_reason(self, data: FinderData) -> str | None:
        levels = _levels(data.frame["bogie_type"].to_numpy())
        if "motor" not in levels or len(levels) < 2:
            return "needs motor and non-motor bogies in the data (bogie_type)"
        return None

    def param_names(self) -> list[str]:
        return ["log_tread_multiplier_motor"]

    def features(self, data: FinderData, theta: Array) -> Array:
        if "motor_bogie" not in data.cache:   # theta-independent: compared once
            col = data.column("bogie_type")
            data.cache["motor_bogie"] = np.zeros(data.n) if col is None else \
                (col.astype(str) == "motor").to_numpy(dtype=float)
        x = np.zeros((data.n, 2, 1))
        x[:, 1, 0] = data.cache["motor_bogie"]
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
        if "load_t" not in data.cache:
            col = data.column("load_t")
            data.cache["load_t"] = None if col is None else np.asarray(
                pd.to_numeric(col, errors="coerce").to_numpy(dtype=float))
        return data.cache["load_t"]  # type: ignore[no-any-return]

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
    # exponent - 1 of the expected progression the baseline already carries (per region;
    # ``discrepancy_progression``): theta is the departure from it, public() the total
    expected_offset: tuple[float, float] = (0.0, 0.0)

    def skip_reason(self, data: FinderData) -> str | None:
        s = data.mileage_km[data.mileage_km > 0]
        if s.size < 4 or s.max() / s.min() < 2.0:
            return "needs mileages spanning at least a factor 2"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        s = data.mileage_km[rows & (data.mileage_km > 0)]
        self.reference_mileage_km = float(np.median(s)) if s.size else 100_000.0
        off = data.cache.get("expected_exponent_offset")
        self.expected_offset = (0.0, 0.0) if off is None else (float(off[0]), float(off[1]))

    def param_names(self) -> list[str]:
        return ["beta_flange_minus_1", "beta_tread_minus_1"]

    def features(self, data: FinderData, theta: Array) -> Array:
        """log(s / s_ref) centred within each wheel life (``residuals.life_ids``): the
        exponent is estimated from how each wheel's wear grows, never from differences
        between wheels (wheels turned early for fast wear leave only slow ones at high
        mileage, which would mimic a decelerating wear). The saved extension applies the
        uncentred power law (``ExtendedModel.predict``)."""
        if "life_centred_log_s" not in data.cache:
            s = data.mileage_km
            pos = s > 0
            x = np.where(pos, np.log(np.maximum(s, 1e-9)), 0.0)
            life = life_ids(data.frame, s)
            key = pd.Series(np.where(pos, life, "_"))
            mean = pd.Series(x).groupby(key.to_numpy()).transform("mean").to_numpy()
            data.cache["life_centred_log_s"] = np.where(pos, x - mean, 0.0)
        x = data.cache["life_centred_log_s"]
        out = np.zeros((data.n, 2, 2))
        out[:, 0, 0] = x
        out[:, 1, 1] = x
        return out

    def public(self) -> dict[str, Any]:
        """Total exponents (the expected progression's own plus the fitted departure)."""
        off = self.expected_offset
        out = {"beta_flange": 1.0 + off[0] + float(self.theta_[0]),
               "beta_tread": 1.0 + off[1] + float(self.theta_[1]),
               "reference_mileage_km": self.reference_mileage_km}
        if any(off):
            out.update(expected_beta_flange=1.0 + off[0], expected_beta_tread=1.0 + off[1])
        return out

    def intervals(self) -> dict[str, dict[str, float]]:
        off = self.expected_offset
        return {f"beta_{r}": _interval(self.theta_[i], self._se(i), self.n_groups_,
                                       lambda v, o=off[i]: 1.0 + o + v)
                for i, r in enumerate(REGIONS)}

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([float(params["beta_flange"]) - 1.0,
                               float(params["beta_tread"]) - 1.0])
        est.reference_mileage_km = float(params["reference_mileage_km"])
        return est

    def describe(self) -> str:
        p = self.public()
        if "expected_beta_flange" in p:
            return (f"wear area grows as mileage^{p['beta_flange']:.2f} (flange) and "
                    f"^{p['beta_tread']:.2f} (tread) where the simulated progression gives "
                    f"^{p['expected_beta_flange']:.2f} and ^{p['expected_beta_tread']:.2f}")
        return (f"wear area grows as mileage^{p['beta_flange']:.2f} (flange) and "
                f"^{p['beta_tread']:.2f} (tread) instead of linearly")


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
                   "wear flanges at a fraction m of the table's rate (m to the share of the "
                   "mileage run lubricated when a wheel changed route).")

    def skip_reason(self, data: FinderData) -> str | None:
        if data.lubricated is None:
            return "no route attribute or column says which routes are lubricated"
        if np.all(data.lubricated > 0.5) or not np.any(data.lubricated > 0):
            return "all measurements share one lubrication state"
        return None

    def covariate(self, data: FinderData) -> NDArray[Any]:
        flags = data.lubricated if data.lubricated is not None else np.zeros(data.n)
        return np.where(np.asarray(flags) > 0.5, "lubricated", "dry")

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


#: The catalogue, in docs/conventions.md order.
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


__all__ = ["CATALOGUE", "CAUSE_CODES", "OMEGA_PER_DAY", "Array", "Cause", "Composite",
           "CurveAsymmetry", "FinderData", "Mask", "NullArea", "ProfileMisalignment",
           "RunningDirection", "SeasonalFriction", "WearMeasure", "_interval",
           "accrual_season_features",
           "cause_by_code", "cluster_covariance", "life_ids", "lubrication_flags",
           "season_features", "shape_coefficients", "signature_coefficients", "solve"]
