"""Base of the discrepancy finder's causes: the data they read, the estimator class, the
linearised least squares on the log-area residual and its cluster-robust covariance.

See :mod:`wearcast.statistics.causes` for the catalogue.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import pandas as pd
from numpy.typing import NDArray

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


@dataclass(frozen=True)
class FinderData:
    """Everything the causes read, per measurement (n rows).

    frame : validated measurements with residual columns (see ``residuals.ModelResiduals``)
    measured, base : (n, 2) measured and model-predicted areas [mm²] (flange, tread)
    floor : (2,) area floor [mm²]; mileage_km : (n,) [km]
    c_s : (2,) calibration factors of the model; parts : route measures by part
    measure_index : index of the model's measure in ``vocabulary.WEAR_MEASURES``
    lead_share : (n,) nominal leading share; mode : (n,) running mode per row
    left_right : (n, 2) the route's left / right curve shares
    route : (n,) route names; lubricated : (n,) share of the mileage run lubricated (0/1
        without route changes) or None when no attribute is known
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
    lubricated: NDArray[Any] | None
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

    @property
    def weights(self) -> Array:
        """(n, 2) robustness weights of the rows (``set_robust_weights``; 1 by default)."""
        w = self.cache.get("weights")
        return np.ones((self.n, 2)) if w is None else np.asarray(w)

    def set_robust_weights(self, residual: Array, k: float = 2.0) -> None:
        """Robustness and precision weights of the rows from a baseline residual (n, 2).

        The noise scale s_ir of every (measurement, region) row is 1.4826 MAD of the
        region's residuals (``noise_scale``; ``NOISE_WEIGHTING = "region"``). The weight is
        the Huber weight min(1, k s / |r|) -- heavy-tailed measurements (outliers, a route
        change the model does not know) count with bounded influence in every fit, score
        and resample -- times the region's precision (s_ref / s)^2, s_ref the rows'
        root-mean-square scale: a region whose log residuals scatter four times as much
        (the depot campaign's flanges) no longer drowns the other in every least-squares
        fit, held-out error and resampled null (inverse-variance weighting of the two
        regions' equations; Carroll and Ruppert 1988, ch. 3). ``"area"``: the scale from a
        variance function of the predicted area instead (it up-weights the large, late
        areas, where the model's own small errors then stand out: 2 of 20 effect-free depot
        campaigns were named a cause against 1 of 20 with ``"region"``); ``"none"``: the
        Huber weights alone (the finder before the precision weights)."""
        r = np.asarray(residual, dtype=float)
        s = noise_scale(r, self.base, NOISE_WEIGHTING)
        w = np.minimum(1.0, k * s / np.maximum(np.abs(r), 1e-12))
        if NOISE_WEIGHTING != "none":
            w = w * float(np.mean(s ** 2)) / s ** 2
        self.cache["weights"] = w
        from wearcast.statistics.finder_random_effects import _CACHE_KEYS

        for key in _CACHE_KEYS:   # the GLS transform depends on the weights
            self.cache.pop(key, None)

    def season(self) -> Array | None:
        """``season_features`` of the data, computed once."""
        if "season" not in self.cache:
            from wearcast.statistics.causes_calendar import season_features

            self.cache["season"] = season_features(self.frame, self.mileage_km)
        return self.cache["season"]  # type: ignore[no-any-return]

    def season_by_region(self) -> Array | None:
        """(n, region, 2) season features weighted by the baseline's predicted wear area of
        each region (``causes_calendar.accrual_season_features``), computed once."""
        if "season_by_region" not in self.cache:
            from wearcast.statistics.causes_calendar import accrual_season_features

            self.cache["season_by_region"] = accrual_season_features(
                self.frame, self.mileage_km, np.clip(self.base, 0.0, None))
        return self.cache["season_by_region"]  # type: ignore[no-any-return]


# noise model of the rows' weights (``FinderData.set_robust_weights``): "area" (a robust
# variance function of the predicted area per region), "region" (one scale per region) or
# "none" (one scale per region for the Huber weights only, no precision weighting)
NOISE_WEIGHTING = "region"
NOISE_BINS = 8


def _mad(values: Array) -> float:
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


def noise_scale(residual: Array, predicted: Array, kind: str = "area",
                bins: int = NOISE_BINS) -> Array:
    """(n, 2) robust noise scale of every (measurement, region) log residual.

    ``kind`` "area": per region the rows are split by their predicted area [mm^2] into
    ``bins`` bins of equal count; each bin's scale is 1.4826 MAD of its residuals, placed
    at the bin's median log area, and every row gets the scale interpolated at its own log
    area (constant beyond the outer bins): a binned robust estimate of the variance
    function (Carroll and Ruppert 1988, Transformation and Weighting in Regression, ch. 3).
    "region" or "none": one 1.4826 MAD scale per region.
    """
    r = np.asarray(residual, dtype=float)
    out = np.empty_like(r)
    for j in range(r.shape[1]):
        whole = max(_mad(r[:, j]), 1e-9)
        if kind != "area" or r.shape[0] < 4 * bins:
            out[:, j] = whole
            continue
        x = np.log(np.clip(np.asarray(predicted, dtype=float)[:, j], 1e-6, None))
        order = np.argsort(x, kind="stable")
        centres, scales = [], []
        for part in np.array_split(order, bins):
            centres.append(float(np.median(x[part])))
            scales.append(max(_mad(r[part, j]), 1e-3 * whole))
        out[:, j] = np.interp(x, np.asarray(centres), np.asarray(scales))
    return out


# --- linear algebra of the working residual -----------------------------------------------

def solve(data: FinderData, target: Array, features: Array, rows: Mask,
          weights: Array | None = None, re_columns: Mask | None = None
          ) -> tuple[Array, Array]:
    """Least squares of ``target`` (n, 2) on phi (b_r + x theta) over ``rows``.

    features : (n, 2, k). Returns (b (2,), theta (k,)). ``re_columns`` (k,): parameters
    taken from the random-effects GLS fit, the others and b refitted by least squares given
    them (``finder_random_effects.two_stage``; default weights only).
    """
    n, _, k = features.shape
    ph = data.phi
    design = np.zeros((n, 2, 2 + k))
    design[:, 0, 0] = 1.0
    design[:, 1, 1] = 1.0
    design[:, :, 2:] = features
    design = design * ph[:, :, None]
    use_re = re_columns is not None and bool(np.any(re_columns)) and weights is None
    weights = data.weights if weights is None else weights
    w_all = np.sqrt(weights)
    x_all = (design * w_all[:, :, None]).reshape(-1, 2 + k)
    y_all = (target * w_all).reshape(-1)
    flat_rows = np.repeat(rows, 2)
    x, y = x_all[flat_rows], y_all[flat_rows]
    keep = np.any(x != 0, axis=1)
    if use_re:
        from wearcast.statistics import finder_random_effects as fre

        xq = fre.cached_quasi_demean(data, x_all)[flat_rows]
        yq = fre.quasi_demean(data, y_all)[flat_rows]
        mask = np.concatenate([[False, False], np.asarray(re_columns, dtype=bool)])
        coef = fre.two_stage(x[keep], y[keep], xq[keep], yq[keep], mask)
    else:
        coef = _least_squares(x[keep], y[keep])
    return coef[:2], coef[2:]


def _least_squares(x: Array, y: Array) -> Array:
    """Least-squares coefficients of y on x: by the normal equations when x'x is well
    conditioned (a few parameters on thousands of rows: the SVD of x costs far more and
    gives the same solution to ~1e-10), else the minimum-norm solution (a parameter without
    rows in a fold)."""
    xtx = x.T @ x
    if xtx.size and np.linalg.cond(xtx) < 1e8:
        return np.asarray(np.linalg.solve(xtx, x.T @ y))
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return np.asarray(coef)


def cluster_covariance(data: FinderData, residual: Array, features: Array,
                       cluster: NDArray[Any], re_columns: Mask | None = None) -> Array:
    """Cluster-robust (vehicle) covariance of (b, theta) of ``solve`` (CR1, Liang-Zeger).

    residual : (n, 2) working residual after the fit; features : (n, 2, k).
    ``re_columns`` (k,): the parameters ``solve`` took from the random-effects GLS fit; the
    coefficients are then L y with L the two-stage estimator's linear map
    (``finder_random_effects.two_stage_map``), and the sandwich sums L's columns times the
    residual over each cluster.
    """
    n, _, k = features.shape
    design = np.zeros((n, 2, 2 + k))
    design[:, 0, 0] = 1.0
    design[:, 1, 1] = 1.0
    design[:, :, 2:] = features
    design = design * data.phi[:, :, None]
    sw = np.sqrt(data.weights).reshape(-1)
    x = design.reshape(-1, 2 + k) * sw[:, None]
    u = residual.reshape(-1) * sw
    codes = np.repeat(pd.factorize(pd.Series(cluster).astype(str))[0], 2)
    g = int(codes.max()) + 1
    p = 2 + k
    corr = g / max(g - 1, 1) * (x.shape[0] - 1) / max(x.shape[0] - p, 1)
    if re_columns is not None:
        from wearcast.statistics import finder_random_effects as fre

        mask = np.concatenate([[False, False], np.asarray(re_columns, dtype=bool)])
        lmap = fre.two_stage_map(x, fre.quasi_demean(data, x), mask,
                                 lambda v: fre.quasi_demean_transpose(data, v))
        scores = np.zeros((g, p))
        np.add.at(scores, codes, lmap.T * u[:, None])
        return np.asarray(corr * scores.T @ scores)
    bread = np.linalg.pinv(x.T @ x)
    scores = np.zeros((g, 2 + k))
    np.add.at(scores, codes, x * u[:, None])
    meat = scores.T @ scores
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
    # theta from the random-effects GLS fit (``finder_random_effects``): a cause whose
    # contrast lies within the wheels (the season), not between them
    random_effects: ClassVar[bool] = False
    # the tests score this cause's held-out error after a random log-scale per vehicle
    # (``finder_scoring.SCORE_METRIC``): a cause whose contrast lies within the cars
    # (traction: a car's motor against its trailer bogie), which the cars' own rate factors
    # would otherwise drown; a contrast between the cars (a greased route) keeps the rows'
    # own metric, which the vehicle transform would take most of it from
    within_vehicle: ClassVar[bool] = False

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

    def re_columns(self) -> Mask:
        """(k,) parameters fitted by random-effects GLS (``random_effects``)."""
        return np.full(len(self.param_names()), bool(self.random_effects))

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
        re = est.re_columns()
        for _ in range(steps):
            x = est.features(data, theta)
            g = est.log_factor(data, theta) if not est.linear else 0.0
            b, delta = solve(data, target - data.phi * g, x, rows, re_columns=re)
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
            est.cov_ = cluster_covariance(data, res, xr, cluster,
                                          re_columns=re if re.any() else None)
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
    uniq = pd.unique(pd.Series(values).dropna())
    return sorted({str(v) for v in uniq if str(v) != ""})


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

    def re_columns(self) -> Mask:
        parts = [m.re_columns() for m in self.members]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=bool)

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
