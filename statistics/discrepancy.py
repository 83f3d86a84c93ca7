"""The discrepancy finder: what the calibrated model gets wrong, the cause, the gain.

``diagnose`` fits every extension of the catalogue (:mod:`wearcast.statistics.causes`) and
scores it out of sample:

1. residuals of the calibrated model per measurement and region (log-area residuals) and of
   the wear-curve shape (:mod:`wearcast.statistics.residuals`);
2. K-fold cross-validation with folds grouped by vehicle (by wheel when fewer than 5
   vehicles), never by row: each extension and the null extension (the model with its
   per-region scale refitted) are fitted on K-1 folds and their squared log residuals
   computed on the held-out fold;
3. per test group (vehicle when the cause's covariate is constant within vehicles, else
   wheel): the held-out error difference null - extension; a one-sided t-test on these,
   Holm-adjusted across the catalogue; the relative gain 1 - after/before with a 95 %
   percentile bootstrap over the same groups;
4. verdict: among causes with Holm p < alpha, relative gain >= ``min_relative_gain`` and a
   bootstrap interval above 0, the one with the largest relative gain; else ``"none"``.

Nested or confounded causes: a cause whose covariate is (nearly) collinear with another's at
the level both vary on (e.g. load differing only between motor and trailer cars vs traction;
one instrument per route vs that route's lubrication) is flagged in its evidence
(``confounded_with``); the scoring then prefers the extension that explains more of the
held-out error, which separates them only when their signatures differ (traction changes
treads of motor bogies, load both regions of heavy vehicles).

Pure: no I/O. Figures are matplotlib SVG strings.
"""

from __future__ import annotations

import html
import io
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, cast

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from scipy import stats

from wearcast.statistics import causes as cz
from wearcast.statistics.hybrid import HybridModel, Prediction, predict, profile_at_areas
from wearcast.statistics.residuals import (
    geometric_basis,
    leading_share,
    model_residuals,
    residual_structure,
    shape_residuals,
)
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import MEASURES, WearTable, compile_wear_table

DEFAULT_ALPHA = 0.05
DEFAULT_MIN_RELATIVE_GAIN = 0.05


@dataclass(frozen=True)
class Gain:
    """Held-out error before (null extension) and after (the cause's extension).

    before_error, after_error : mean squared held-out residual per measurement (log-area
        residual summed over both regions, or wear-curve shape residual [mm²·points])
    relative : 1 - after / before; ci95_low, ci95_high : bootstrap interval over groups
    calibrated_error : held-out error of the model exactly as calibrated (area metric)
    metric : 'log_area' or 'wear_curve_shape'
    """

    before_error: float
    after_error: float
    relative: float
    ci95_low: float
    ci95_high: float
    calibrated_error: float
    metric: str

    def to_dict(self) -> dict[str, Any]:
        return {k: _json(v) for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class Finding:
    """One cause: plain summary, evidence, fitted extension and gain."""

    cause: str
    summary: str
    evidence: dict[str, Any]
    extension: dict[str, Any]
    gain: Gain
    significant: bool
    material: bool

    def to_dict(self) -> dict[str, Any]:
        return {"cause": self.cause, "summary": self.summary, "evidence": _json(self.evidence),
                "extension": _json(self.extension), "gain": self.gain.to_dict(),
                "significant": self.significant, "material": self.material}


@dataclass(frozen=True)
class Diagnosis:
    """Result of ``diagnose``: verdict (cause code or 'none'), findings ranked by gain."""

    verdict: str
    findings: tuple[Finding, ...]
    skipped: dict[str, str]
    n_measurements: int
    n_groups: int
    group_by: str
    residuals: pd.DataFrame = field(repr=False, compare=False)
    covariates: dict[str, list[Any]] = field(default_factory=dict, repr=False, compare=False)
    predictions: dict[str, list[list[float]]] = field(default_factory=dict, repr=False,
                                                      compare=False)

    def finding(self, cause: str) -> Finding | None:
        return next((f for f in self.findings if f.cause == cause), None)

    @property
    def reported(self) -> tuple[Finding, ...]:
        """Findings with a significant and material gain (the verdict first)."""
        return tuple(f for f in self.findings if f.significant and f.material)

    def to_dict(self) -> dict[str, Any]:
        return {"verdict": self.verdict, "findings": [f.to_dict() for f in self.findings],
                "skipped": dict(self.skipped), "n_measurements": self.n_measurements,
                "n_groups": self.n_groups, "group_by": self.group_by}


def _json(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json(value.tolist())
    if isinstance(value, np.generic):
        return _json(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _holm(p: Sequence[float]) -> NDArray[np.float64]:
    p_arr = np.asarray(p, dtype=float)
    order = np.argsort(p_arr)
    m = p_arr.size
    adj = np.empty(m)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p_arr[i]))
        adj[i] = running
    return adj


def _folds(groups: NDArray[Any], k: int, seed: int) -> NDArray[np.int64]:
    uniq = np.unique(groups)
    rng = np.random.default_rng(seed)
    perm = rng.permutation(uniq.size)
    fold_of = {g: int(perm[i] % k) for i, g in enumerate(uniq)}
    return np.array([fold_of[g] for g in groups], dtype=np.int64)


def build_data(model: HybridModel, measurements: pd.DataFrame, wear_curves: Any,
               routes_by_name: Mapping[str, Route], table: pd.DataFrame | WearTable, *,
               calibration_wheel_ids: Collection[Any] = (),
               route_attributes: Mapping[str, Mapping[str, Any]] | None = None
               ) -> cz.FinderData:
    """Residuals and covariates in the form the causes read (see ``causes.FinderData``)."""
    res = model_residuals(model, measurements, routes_by_name, table,
                          calibration_wheel_ids=calibration_wheel_ids)
    frame = res.frame
    rcol = "route" if "route" in frame.columns else "route_id"
    route = frame[rcol].astype(str).to_numpy()
    shape = None
    basis = geometric_basis(model.grid_y_mm, model.split_y_mm)
    if wear_curves is not None:
        # keep only the part of each shape residual that a geometric error can produce:
        # its least-squares projection on the basis (the rest no extension can explain)
        d = np.nan_to_num(shape_residuals(model, res.measured_mm2, wear_curves), nan=0.0)
        coef, *_ = np.linalg.lstsq(basis.T, d.T, rcond=None)
        shape = (basis.T @ coef).T
    return cz.FinderData(
        frame=frame, measured=res.measured_mm2, base=res.predicted_mm2, floor=res.floor_mm2,
        mileage_km=frame["mileage_km"].to_numpy(dtype=float),
        c_s=np.array([model.flange.c_s, model.tread.c_s]), parts=res.parts,
        measure_index=MEASURES.index(model.measure),
        lead_share=leading_share(frame["axle"].to_numpy(), res.mode), mode=res.mode,
        left_right=res.left_right_shares, route=route,
        lubricated=cz.lubrication_flags(frame, route, route_attributes),
        shape_res=shape, basis=basis,
    )


def _cv_rows(data: cz.FinderData, cause: cz.Cause, folds: NDArray[np.int64],
             residuals: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """Held-out per-row error of a cause (or null) over the folds.

    When ``residuals`` is given ((n, 2) for the area metric, (n, 3) for the shape metric) it
    is filled with the held-out signed residuals (log-area residuals per region, or the
    basis coefficients of the remaining wear-curve shape residual).
    """
    out = np.empty(data.n)
    for k in np.unique(folds):
        test = folds == k
        fit = cause.fit(data, ~test)
        if cause.metric == "shape":
            corr = cause.correction(data, fit)  # type: ignore[attr-defined]
            rows = cz.shape_row_sse(data, corr)
            if residuals is not None:
                assert data.shape_res is not None
                coef, *_ = np.linalg.lstsq(data.basis.T, (data.shape_res[test] - corr[test]).T,
                                           rcond=None)
                residuals[test] = coef.T
        else:
            pred = cause.predict(data, fit)
            rows = cz.row_sse(data, pred)
            if residuals is not None:
                residuals[test] = cz.log_residual(data.measured, pred, data.floor)[test]
        out[test] = rows[test]
    return out


def design_effect(values: NDArray[np.float64], vehicle: NDArray[Any],
                  covariate: NDArray[Any] | None = None) -> tuple[float, int]:
    """Design effect of wheels clustered in vehicles for a wheel-level mean.

    values : (n_wheels,) the per-wheel quantity being tested (held-out error differences)
    vehicle : (n_wheels,) vehicle of each wheel
    covariate : (n_wheels,) the cause's covariate (constant within vehicles); its systematic
        part (level means, or a quadratic in a numeric covariate) is removed first, so that
        only the random between-vehicle variation counts as clustering

    One-way ANOVA by vehicle: rho = (MSB - MSW) / (MSB + (m0 - 1) MSW) (Donner 1986, with
    the between-vehicle degrees of freedom reduced by the covariate's parameters) and
    deff = 1 + (m0 - 1) rho. Returns (deff, n_vehicles).
    """
    v = np.asarray(values, dtype=float)
    n_w = v.size
    v_codes, v_inv = np.unique(np.asarray(vehicle).astype(str), return_inverse=True)
    g = v_codes.size
    q = 1
    x = np.ones((n_w, 1))
    if covariate is not None:
        num = pd.to_numeric(pd.Series(covariate), errors="coerce")
        if num.notna().all() and num.nunique() > 4:
            z = (num.to_numpy(float) - num.mean()) / max(float(num.std()), 1e-12)
            x = np.column_stack([np.ones(n_w), z, z * z])
        else:
            codes = pd.factorize(pd.Series(covariate).astype(str))[0]
            x = np.eye(codes.max() + 1)[codes]
        q = x.shape[1]
    if g - q < 1 or n_w <= g:
        return float(n_w) / max(g, 1), g
    coef, *_ = np.linalg.lstsq(x, v, rcond=None)
    e = v - x @ coef
    m_g = np.bincount(v_inv, minlength=g).astype(float)
    m0 = (n_w - np.sum(m_g ** 2) / n_w) / (g - 1)
    mean_g = np.bincount(v_inv, weights=e, minlength=g) / m_g
    msb = np.sum(m_g * mean_g ** 2) / (g - q)
    msw = np.sum((e - mean_g[v_inv]) ** 2) / (n_w - g)
    den = msb + (m0 - 1) * msw
    rho = float(np.clip((msb - msw) / den, 0.0, 1.0)) if den > 0 else 1.0
    return float(1.0 + (m0 - 1.0) * rho), g


def _pvalue(before: NDArray[np.float64], after: NDArray[np.float64], wheel: NDArray[Any],
            vehicle: NDArray[Any], covariate: NDArray[Any] | None) -> tuple[float, str]:
    """One-sided p-value that the extension lowers the held-out error, and how it was got.

    Wheel-level causes (``covariate`` None): paired t-test over wheels. Vehicle-level causes
    (covariate constant within vehicles): the wheel-level test with its variance inflated by
    the design effect of the error differences' vehicle clustering (``design_effect``) and
    degrees of freedom n_wheels / deff - 1, never fewer than n_vehicles - 1: with strongly
    clustered wheels this is the vehicle-level test, with independent wheels the wheel-level
    one.
    """
    uniq, inv = np.unique(wheel, return_inverse=True)
    # a weighted bincount is float64 (the stubs type every bincount as intp)
    d = cast(NDArray[np.float64],
             np.bincount(inv, weights=before - after, minlength=uniq.size))
    if uniq.size < 2 or np.std(d) == 0:
        return 1.0, "no variation"
    deff, g = 1.0, 0
    if covariate is not None:
        first = pd.Series(np.arange(inv.size)).groupby(inv).first().to_numpy()
        deff, g = design_effect(d, np.asarray(vehicle)[first], np.asarray(covariate)[first])
    se = np.std(d, ddof=1) / np.sqrt(uniq.size) * np.sqrt(deff)
    df = max(float(max(g - 1, 1)), min(uniq.size - 1.0, uniq.size / deff - 1.0))
    p = float(stats.t.sf(float(np.mean(d) / se), df))
    if covariate is not None:
        how = (f"one-sided t-test over {uniq.size} wheels of held-out error differences, "
               f"variance x design effect {deff:.2f} for {g} vehicles (df {df:.1f}), "
               "Holm-adjusted")
    else:
        how = (f"one-sided paired t-test over {uniq.size} wheel_id groups of held-out error "
               "differences, Holm-adjusted")
    return p, how


def _vehicle_level(values: NDArray[Any], vehicle: NDArray[Any]) -> bool:
    s = pd.Series(values.astype(str)).groupby(vehicle).nunique()
    return bool((s <= 1).all())


def _numeric(values: NDArray[Any]) -> NDArray[np.float64]:
    v = pd.to_numeric(pd.Series(values), errors="coerce")
    if v.notna().all():
        return v.to_numpy(dtype=float)
    return pd.factorize(pd.Series(values).astype(str))[0].astype(float)


def diagnose(
    model: HybridModel,
    measurements_df: pd.DataFrame,
    wear_curves: Any,
    routes_by_name: Mapping[str, Route],
    table: pd.DataFrame | WearTable,
    *,
    calibration_wheel_ids: Collection[Any] = (),
    route_attributes: Mapping[str, Mapping[str, Any]] | None = None,
    causes: Sequence[str] | None = None,
    alpha: float = DEFAULT_ALPHA,
    min_relative_gain: float = DEFAULT_MIN_RELATIVE_GAIN,
    n_folds: int = 5,
    n_boot: int = 1000,
    seed: int = 0,
) -> Diagnosis:
    """Find what the calibrated model gets wrong, name the cause and measure the gain.

    Parameters
    ----------
    model : calibrated hybrid model (seed 001)
    measurements_df : one row per measurement (``residuals.model_residuals`` lists the
        columns): the wheels not used in calibration and, ideally, the calibration wheels too
        (flagged via ``calibration_wheel_ids``; every extension refits its scale, so they
        inform the extension without favouring it)
    wear_curves : (n, g) measured wear curves [mm] on the model's grid, or None (then
        ``profile_misalignment`` is skipped)
    routes_by_name : Route per route name used in the ``route``/``route_id`` column
    table : curve-radius table (both measures for ``wear_measure``)
    route_attributes : attributes per route name (``flange_lubrication``, ...)
    causes : cause codes to try (default: the whole catalogue)
    alpha : family-wise error rate (Holm) across the causes tried
    min_relative_gain : smallest relative reduction of the held-out error that counts
    n_folds, n_boot, seed : cross-validation folds, bootstrap resamples, random seed

    Returns
    -------
    Diagnosis (module docstring for the procedure).
    """
    wt = compile_wear_table(table)
    data = build_data(model, measurements_df, wear_curves, routes_by_name, wt,
                      calibration_wheel_ids=calibration_wheel_ids,
                      route_attributes=route_attributes)
    frame = data.frame
    vehicle = frame["vehicle_id"].astype(str).to_numpy()
    wheel = frame["wheel_id"].astype(str).to_numpy()
    group_by = "vehicle_id" if np.unique(vehicle).size >= 5 else "wheel_id"
    groups = vehicle if group_by == "vehicle_id" else wheel
    k = int(min(n_folds, np.unique(groups).size))
    if k < 2:
        raise ValueError("measurements: need at least two wheels to score out of sample")
    folds = _folds(groups, k, seed)
    chosen = cz.CATALOGUE if causes is None else tuple(cz.cause_by_code(c) for c in causes)
    null_area = _cv_rows(data, cz.NullArea(), folds)
    calibrated_rows = cz.row_sse(data, data.base)
    null_shape = None
    skipped: dict[str, str] = {}
    scored: list[tuple[cz.Cause, NDArray[np.float64], NDArray[np.float64], NDArray[Any]]] = []
    for cause in chosen:
        reason = cause.skip_reason(data)
        if reason is not None:
            skipped[cause.code] = reason
            continue
        if cause.metric == "shape":
            if null_shape is None:
                null_shape = _cv_rows(data, cz.NullShape(), folds)
            before = null_shape
        else:
            before = null_area
        after = _cv_rows(data, cause, folds)
        level = vehicle if _vehicle_level(cause.covariate(data), vehicle) else wheel
        scored.append((cause, before, after, level))
    rng = np.random.default_rng(seed + 1)
    raw_p, results = [], []
    for cause, before, after, level in scored:
        uniq, inv = np.unique(level, return_inverse=True)
        b_g = np.bincount(inv, weights=before, minlength=uniq.size)
        a_g = np.bincount(inv, weights=after, minlength=uniq.size)
        p, how = _pvalue(before, after, wheel, vehicle,
                         np.asarray(cause.covariate(data)) if level is vehicle else None)
        idx = rng.integers(0, uniq.size, size=(n_boot, uniq.size))
        rel_boot = 1.0 - a_g[idx].sum(axis=1) / np.maximum(b_g[idx].sum(axis=1), 1e-300)
        lo, hi = np.percentile(rel_boot, [2.5, 97.5])
        n = before.size
        rel = 1.0 - after.sum() / max(before.sum(), 1e-300)
        gain = Gain(before_error=float(before.sum() / n), after_error=float(after.sum() / n),
                    relative=float(rel), ci95_low=float(lo), ci95_high=float(hi),
                    calibrated_error=float(calibrated_rows.sum() / n),
                    metric="wear_curve_shape" if cause.metric == "shape" else "log_area")
        raw_p.append(p)
        results.append((cause, gain, p, how))
    adj = _holm(raw_p) if raw_p else np.array([])
    findings, preds = [], {}
    covs: dict[str, list[Any]] = {}
    for (cause, gain, p, how), p_adj in zip(results, adj, strict=True):
        full = cause.fit(data, np.ones(data.n, dtype=bool))
        significant = bool(p_adj < alpha)
        material = bool(gain.relative >= min_relative_gain and gain.ci95_low > 0)
        cov = cause.covariate(data)
        covs[cause.code] = [_json(v) for v in np.asarray(cov).tolist()]
        if cause.metric != "shape":
            preds[cause.code] = cause.predict(data, full).tolist()
        evidence = {
            "p_value": p_adj, "p_value_raw": p, "test": how,
            "effect_size": _effect_size(cause, full), "subgroup": _subgroup(cause, data),
            "interval": {"relative_gain_ci95": [gain.ci95_low, gain.ci95_high]},
            "confounded_with": _confounded(cause, chosen, data, vehicle),
        }
        if cause.metric != "shape" and cause.covariate_name in frame.columns \
                and frame[cause.covariate_name].nunique() <= 20:
            evidence["residual_by_level"] = residual_structure(
                frame, cause.covariate_name).to_dict(orient="records")
        extension = {"cause": cause.code, "parameters": full.params,
                     "log_scale": {"flange": float(full.log_scale[0]),
                                   "tread": float(full.log_scale[1])},
                     "explanation": cause.explanation, "needs": list(cause.needs)}
        summary = (f"{cause.describe(full)}; held-out error "
                   f"{'down' if gain.relative >= 0 else 'up'} {100 * abs(gain.relative):.1f} % "
                   f"(95 % CI {100 * gain.ci95_low:.1f} to {100 * gain.ci95_high:.1f} %)")
        findings.append(Finding(cause.code, summary, evidence, extension, gain, significant,
                                material))
    findings.sort(key=lambda f: (not (f.significant and f.material), -f.gain.relative))
    verdict = findings[0].cause if findings and findings[0].significant \
        and findings[0].material else "none"
    preds["none"] = cz.NullArea().predict(data, cz.NullArea().fit(
        data, np.ones(data.n, dtype=bool))).tolist()
    preds["calibrated"] = data.base.tolist()
    preds["measured"] = data.measured.tolist()
    return Diagnosis(verdict=verdict, findings=tuple(findings), skipped=skipped,
                     n_measurements=data.n, n_groups=int(np.unique(groups).size),
                     group_by=group_by, residuals=frame, covariates=covs, predictions=preds)


def _effect_size(cause: cz.Cause, fit: cz.Fit) -> dict[str, Any]:
    p = dict(fit.params)
    if cause.code == "profile_misalignment":
        return p["instruments"]
    return p


def _subgroup(cause: cz.Cause, data: cz.FinderData) -> str:
    subgroups = {
        "traction": "tread of motor bogies vs other bogies",
        "running_direction": "axle 1 vs axle 2 per running mode",
        "curve_asymmetry": "left vs right wheels per curved route",
        "flange_lubrication": "flanges on lubricated vs dry routes",
        "wear_measure": "all wheel positions (ratio of the two measures)",
        "nonlinear_progression": "mileage since reprofiling",
        "seasonal_friction": "season of the running interval",
        "vehicle_load": "vehicles by load_t",
        "profile_misalignment": "wear curves per instrument_id",
    }
    return subgroups.get(cause.code, "")


def _confounded(cause: cz.Cause, chosen: Sequence[cz.Cause], data: cz.FinderData,
                vehicle: NDArray[Any]) -> list[str]:
    """Other causes whose covariate is nearly collinear with this one's (|r| > 0.9)."""
    x = _numeric(np.asarray(cause.covariate(data)))
    if np.std(x) == 0:
        return []
    out = []
    for other in chosen:
        if other.code == cause.code or other.skip_reason(data) is not None:
            continue
        y = _numeric(np.asarray(other.covariate(data)))
        if np.std(y) > 0 and abs(np.corrcoef(x, y)[0, 1]) > 0.9:
            out.append(other.code)
    return out


# --- the extended model -----------------------------------------------------------------------

@dataclass(frozen=True)
class ExtendedModel:
    """A hybrid model with one fitted extension of the catalogue.

    ``rate_factors`` gives the per-region multiplier of the base model's rate for one wheel
    (its covariates); ``for_wheel`` returns a plain HybridModel whose c_s carries that factor,
    so ``hybrid.predict`` and ``reprofiling.reprofiling_mileage`` work unchanged;
    ``predict`` adds the mileage dependence of ``nonlinear_progression``.
    """

    base: HybridModel
    cause: str
    parameters: dict[str, Any]
    log_scale: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "extended", "base": self.base.to_dict(), "cause": self.cause,
                "parameters": _json(self.parameters), "log_scale": dict(self.log_scale)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ExtendedModel:
        return cls(HybridModel.from_dict(data["base"]), str(data["cause"]),
                   dict(data["parameters"]), {k: float(v) for k, v in
                                              data["log_scale"].items()})

    def correct_wear_curves(self, frame: pd.DataFrame, curves_mm: Any) -> NDArray[np.float64]:
        """``profile_misalignment`` only: measured wear curves on the base model's grid with
        each instrument's geometric error removed (module ``correct_wear_curves``)."""
        return correct_wear_curves(self, frame, curves_mm, grid_y_mm=self.base.grid_y_mm,
                                   split_y_mm=self.base.split_y_mm)

    def correct_profile(self, instrument_id: str, y_mm: Any, z_mm: Any
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``profile_misalignment`` only: a raw profile's points corrected (module
        ``correct_profile``)."""
        return correct_profile(self, instrument_id, y_mm, z_mm, split_y_mm=self.base.split_y_mm)

    def rate_factors(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                     axle: int, side: str, covariates: Mapping[str, Any] | None = None
                     ) -> dict[str, float]:
        """Multiplier of the base rate per region for one wheel (scale included)."""
        cov = dict(covariates or {})
        f = {r: math.exp(self.log_scale.get(r, 0.0)) for r in ("flange", "tread")}
        p = self.parameters
        if self.cause == "traction" and bogie_type == "motor":
            f["tread"] *= float(p["tread_multiplier_motor"])
        elif self.cause == "flange_lubrication" and _truthy(
                cov.get("flange_lubrication", cov.get("lubricated", False))):
            f["flange"] *= float(p["flange_multiplier_lubricated"])
        elif self.cause == "vehicle_load" and cov.get("load_t") is not None:
            f = {r: v * (float(cov["load_t"]) / float(p["load_ref_t"])) ** float(p["gamma"])
                 for r, v in f.items()}
        elif self.cause in ("running_direction", "curve_asymmetry"):
            frame = pd.DataFrame([{"wheel_id": "w", "bogie_type": bogie_type, "axle": axle,
                                   "side": side, "mileage_km": 1.0, "route": route.name,
                                   "flange_area_mm2": 1.0, "tread_area_mm2": 1.0,
                                   "running_mode": cov.get("running_mode",
                                                           self.base.running_mode)}])
            data = build_data(self.base, frame, None, {route.name: route}, table)
            cause = cz.cause_by_code(self.cause)
            theta = {k.split("_", 3)[-1]: float(v)
                     for k, v in p.items()}
            fit = cz.Fit(dict(p), np.zeros(2), theta)
            ext = cause.predict(data, fit)[0]
            base = data.base[0]
            for j, r in enumerate(("flange", "tread")):
                f[r] *= float(ext[j] / base[j]) if base[j] > 0 else 1.0
        return f

    def for_wheel(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                  axle: int, side: str, covariates: Mapping[str, Any] | None = None
                  ) -> HybridModel:
        """A plain HybridModel whose rates equal the extended model's for this wheel."""
        f = self.rate_factors(route, table, bogie_type=bogie_type, axle=axle, side=side,
                              covariates=covariates)
        m = self.base
        return replace(m, flange=replace(m.flange, c_s=m.flange.c_s * f["flange"]),
                       tread=replace(m.tread, c_s=m.tread.c_s * f["tread"]))

    def predict(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                axle: int, side: str, mileage_km: Any,
                covariates: Mapping[str, Any] | None = None) -> Prediction:
        """``hybrid.predict`` with the extension (areas A = k s, or k s_ref (s/s_ref)^beta)."""
        m = self.for_wheel(route, table, bogie_type=bogie_type, axle=axle, side=side,
                           covariates=covariates)
        out = predict(m, route, table, bogie_type=bogie_type, axle=axle, side=side,
                      mileage_km=mileage_km)
        if self.cause != "nonlinear_progression":
            return out
        s = out.mileage_km
        s_ref = float(self.parameters["reference_mileage_km"])
        g = {r: np.where(s > 0, (np.maximum(s, 1e-9) / s_ref)
                         ** (float(self.parameters[f"beta_{r}"]) - 1.0), 1.0)
             for r in ("flange", "tread")}
        fa = out.flange_area_mm2 * g["flange"][None, :]
        ta = out.tread_area_mm2 * g["tread"][None, :]
        median = out.quantiles.index(0.5)
        wear, z, params, extra = profile_at_areas(m, fa[median], ta[median])
        return replace(out, flange_area_mm2=fa, tread_area_mm2=ta, wear_mm=wear, z_mm=z,
                       sd_mm=params[:, 0], sh_mm=params[:, 1], qr_mm=params[:, 2],
                       extrapolated=extra)


def _truthy(v: Any) -> bool:
    if isinstance(v, str):
        return v.strip().lower() in ("true", "yes", "on", "1", "y", "lubricated")
    return bool(v)


def apply_extension(model: HybridModel, finding: Finding) -> HybridModel | ExtendedModel:
    """The model extended by a finding.

    ``wear_measure`` gives a plain HybridModel with the other measure and refitted c_s;
    ``profile_misalignment`` corrects the data, not the rates: an ``ExtendedModel`` that
    predicts exactly as the base model and carries the per-instrument corrections
    (``correct_wear_curves``, ``correct_profile``); every other cause an ``ExtendedModel``.
    """
    ext = finding.extension
    params = dict(ext["parameters"])
    if finding.cause == "wear_measure":
        return replace(model, measure=str(params["measure"]),
                       flange=replace(model.flange, c_s=float(params["c_s_flange"])),
                       tread=replace(model.tread, c_s=float(params["c_s_tread"])))
    if finding.cause == "profile_misalignment":
        # the wear model itself is right; what the extension carries is the per-instrument
        # geometric correction of the measurements (``correct_wear_curves``,
        # ``correct_profile``); its rates are the base model's (no scale change)
        return ExtendedModel(model, finding.cause, params, {"flange": 0.0, "tread": 0.0})
    return ExtendedModel(model, finding.cause, params, dict(ext["log_scale"]))


def _instrument_corrections(extension: Finding | ExtendedModel | Mapping[str, Any]
                            ) -> dict[str, dict[str, float]]:
    if isinstance(extension, Finding):
        params = extension.extension["parameters"]
    elif isinstance(extension, ExtendedModel):
        params = extension.parameters
    else:
        params = extension.get("parameters", extension)
    corr = params.get("corrections")
    if corr is None:
        raise ValueError("extension: not a profile_misalignment extension with corrections")
    return {str(k): {n: float(x) for n, x in v.items()} for k, v in corr.items()}


def correct_wear_curves(extension: Finding | ExtendedModel | Mapping[str, Any],
                        frame: pd.DataFrame, curves_mm: Any, *, grid_y_mm: Any,
                        split_y_mm: float = -30.0) -> NDArray[np.float64]:
    """Measured wear curves with each instrument's fitted geometric error removed [mm].

    extension : the ``profile_misalignment`` finding, the saved ExtendedModel or its
        parameters (``corrections`` per instrument relative to the reference instrument)
    frame : one row per curve with ``instrument_id``; curves_mm : (n, g) on ``grid_y_mm``

    w_corrected = w - (e y z' + d_f z' [y < split] + d_s z') with the instrument's lateral
    scale error e, flange-tread offset d_f and lateral shift d_s (residuals.geometric_basis,
    seed 000 §IV.A). Instruments without a correction are returned unchanged.
    """
    corr = _instrument_corrections(extension)
    curves = np.array(curves_mm, dtype=float, copy=True)
    basis = geometric_basis(grid_y_mm, split_y_mm)
    if curves.ndim != 2 or curves.shape[1] != basis.shape[1]:
        raise ValueError(f"curves: must have shape (n, {basis.shape[1]}) on grid_y_mm")
    if "instrument_id" not in frame.columns or len(frame) != curves.shape[0]:
        raise ValueError("frame: needs instrument_id and one row per curve")
    inst = frame["instrument_id"].astype(str).to_numpy()
    names = cz.ProfileMisalignment.basis_names
    for name, c in corr.items():
        coef = np.array([c[k] for k in names])
        curves[inst == name] -= coef @ basis
    return curves


def correct_profile(extension: Finding | ExtendedModel | Mapping[str, Any], instrument_id: str,
                    y_mm: Any, z_mm: Any, *, split_y_mm: float = -30.0
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A measured profile's points with the instrument's fitted geometric error undone [mm].

    Inverse of the error model of ``correct_wear_curves``: y <- y - d_s - d_f [y < split],
    then y <- y / (1 + e) about the tape circle; z unchanged. Align and process the
    corrected points as usual (``processing.process_profile``).
    """
    corr = _instrument_corrections(extension).get(str(instrument_id))
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    if corr is None:
        return y.copy(), z.copy()
    y = y - corr["lateral_shift_mm"]
    y = np.where(y < split_y_mm, y - corr["flange_offset_mm"], y)
    return y / (1.0 + corr["lateral_scale"]), z.copy()


# --- figures and report -----------------------------------------------------------------------

def _svg(fig: Any) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return buf.getvalue()


def diagnosis_figures(diagnosis: Diagnosis, cause: str | None = None) -> dict[str, str]:
    """SVG figures: residuals against the named covariate; predicted vs measured areas.

    ``cause`` defaults to the verdict (or the top finding when the verdict is 'none').
    Returns {'residuals': svg, 'predicted_vs_measured': svg}.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    code = cause or (diagnosis.verdict if diagnosis.verdict != "none" else
                     (diagnosis.findings[0].cause if diagnosis.findings else "none"))
    frame = diagnosis.residuals
    out: dict[str, str] = {}
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5), sharey=True)
    cov = diagnosis.covariates.get(code)
    x = np.asarray(cov if cov is not None else frame["mileage_km"].tolist(), dtype=object)
    numeric = pd.to_numeric(pd.Series(x), errors="coerce")
    for ax, region in zip(axes, ("flange", "tread"), strict=True):
        y = frame[f"logres_{region}"].to_numpy()
        if numeric.notna().all() and numeric.nunique() > 6:
            ax.plot(numeric.to_numpy(), y, ".", alpha=0.5)
        else:
            levels = sorted({str(v) for v in x})
            for i, lev in enumerate(levels):
                sel = np.array([str(v) == lev for v in x])
                ax.plot(np.full(sel.sum(), i) + np.linspace(-0.2, 0.2, sel.sum()), y[sel], ".",
                        alpha=0.5)
            ax.set_xticks(range(len(levels)), levels)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_title(f"{region}: log(measured / predicted)")
        ax.set_xlabel(code if cov is not None else "mileage_km")
    out["residuals"] = _svg(fig)
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    meas = np.asarray(diagnosis.predictions.get("measured", []), dtype=float)
    before = np.asarray(diagnosis.predictions.get("calibrated", []), dtype=float)
    after = np.asarray(diagnosis.predictions.get(code, diagnosis.predictions.get("none", [])),
                       dtype=float)
    for j, (ax, region) in enumerate(zip(axes, ("flange", "tread"), strict=True)):
        if meas.size:
            ax.plot(meas[:, j], before[:, j], ".", alpha=0.5, label="calibrated model")
            if after.size:
                ax.plot(meas[:, j], after[:, j], ".", alpha=0.5, label=f"extended ({code})")
            top = float(np.nanmax([meas[:, j].max(), before[:, j].max(), 1e-9]))
            ax.plot([0, top], [0, top], "k-", lw=0.8)
        ax.set_xlabel(f"measured {region} area [mm²]")
        ax.set_ylabel(f"predicted {region} area [mm²]")
        ax.legend(fontsize=7)
    out["predicted_vs_measured"] = _svg(fig)
    return out


def report_html(diagnosis: Diagnosis, figures_svg: Mapping[str, str]) -> str:
    """A self-contained HTML report: verdict, findings table, skipped causes, figures."""
    esc = html.escape
    rows = []
    for f in diagnosis.findings:
        g = f.gain
        rows.append(
            f"<tr><td>{esc(f.cause)}</td><td>{esc(f.summary)}</td>"
            f"<td>{g.before_error:.4g}</td><td>{g.after_error:.4g}</td>"
            f"<td>{100 * g.relative:.1f} % [{100 * g.ci95_low:.1f}, {100 * g.ci95_high:.1f}]</td>"
            f"<td>{f.evidence.get('p_value', float('nan')):.2g}</td>"
            f"<td>{'yes' if f.significant and f.material else 'no'}</td></tr>")
    skipped = "".join(f"<li><b>{esc(k)}</b>: {esc(v)}</li>"
                      for k, v in diagnosis.skipped.items())
    figs = "".join(f"<h3>{esc(name.replace('_', ' '))}</h3><div>{svg}</div>"
                   for name, svg in figures_svg.items())
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>wearcast diagnosis</title>"
        "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}"
        "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px}</style>"
        "</head><body><h1>wearcast diagnosis</h1>"
        f"<p>Verdict: <b>{esc(diagnosis.verdict)}</b> ({diagnosis.n_measurements} measurements, "
        f"{diagnosis.n_groups} groups by {esc(diagnosis.group_by)})</p>"
        "<table><tr><th>cause</th><th>summary</th><th>held-out error before</th>"
        "<th>after</th><th>relative gain [95 % CI]</th><th>p (Holm)</th><th>reported</th></tr>"
        + "".join(rows) + "</table>"
        + (f"<h2>Skipped</h2><ul>{skipped}</ul>" if skipped else "")
        + f"<h2>Figures</h2>{figs}</body></html>")
