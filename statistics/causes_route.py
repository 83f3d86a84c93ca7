"""Causes acting through the route's wear measure: running direction, curve asymmetry and
the blend of the two wear measures; and the instrument's wear-curve signature.

Part of the discrepancy finder's catalogue (:mod:`wearcast.statistics.causes`).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.vocabulary import WEAR_MEASURES
from wearcast.statistics.cause_base import Cause, FinderData, Mask, _levels
from wearcast.statistics.finder_shape_growth import without_wear_growth
from wearcast.statistics.finder_shape_position import wheel_positions, without_position_shape
from wearcast.statistics.residuals import life_ids
from wearcast.statistics.route_measure import weighted_measure

Array = NDArray[np.float64]


def _log_ratio(new: Array, nominal: Array) -> Array:
    """log(new / nominal) where both measures are positive, else 0 (no factor)."""
    return np.asarray(np.where((new > 0) & (nominal > 0),
                               np.log(np.maximum(new, 1e-300) / np.maximum(nominal, 1e-300)),
                               0.0))


def _relative(change: Array, measure: Array) -> Array:
    """change / measure where the measure is positive, else 0."""
    return np.asarray(np.where(measure > 0,
                               change / np.where(measure > 0, measure, 1.0), 0.0))


class _ShareByLevel(Cause):
    """A cause with one share in [0, 1] per level of a covariate (a running mode, a route):
    the parameters are named ``prefix`` + level, the levels set in ``prepare``."""

    prefix: ClassVar[str] = ""
    levels: tuple[str, ...] = ()

    def level_sentence(self, level: str, share: float) -> str:
        raise NotImplementedError

    def param_names(self) -> list[str]:
        return [f"{self.prefix}{level}" for level in self.levels]

    def clip(self, theta: Array) -> Array:
        return np.clip(theta, 0.0, 1.0)

    def per_level(self, data: FinderData, level_of_row: NDArray[Any],
                  value: Callable[[Mask], Array]) -> Array:
        """(n, 2, k) features: column j holds ``value(rows)`` on the rows of level j."""
        x = np.zeros((data.n, 2, len(self.levels)))
        for j, level in enumerate(self.levels):
            sel = np.asarray(level_of_row == level)
            x[sel, :, j] = value(sel)
        return x

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.levels = tuple(k[len(self.prefix):] for k in params if k.startswith(self.prefix))
        est.theta_ = np.array([float(params[self.prefix + level]) for level in est.levels])
        return est

    def describe(self) -> str:
        return "; ".join(self.level_sentence(level, float(share))
                         for level, share in zip(self.levels, self.theta_, strict=True))


class RunningDirection(_ShareByLevel):
    """One share per running mode (the levels)."""

    code = "running_direction"
    needs = ("axle", "running_mode")
    covariate_name = "axle"
    linear = False
    explanation = ("The real leading/trailing mix differs from the model's: axle 1 leads a "
                   "share p of the distance, P = p P_lead + (1 - p) P_trail (seed 001 §4).")
    prefix = "axle1_leading_share_"

    def skip_reason(self, data: FinderData) -> str | None:
        axles = set(data.frame["axle"].astype(int))
        if not {1, 2} <= axles:
            return "needs wheels on both axles (1 and 2)"
        return None

    def prepare(self, data: FinderData, rows: Mask) -> None:
        self.levels = tuple(sorted({str(m) for m in data.mode}))

    def start(self) -> Array:
        return np.array([1.0 if m == "lead" else 0.5 for m in self.levels])

    def level_sentence(self, level: str, share: float) -> str:
        return f"in {level} mode axle 1 leads {100 * share:.0f} % of the distance"

    def _per_wheelset(self, data: FinderData) -> tuple[Array, Array]:
        block = data.parts[:, data.measure_index].sum(axis=3)   # (n, region, wheelset)
        return block[:, :, 0], block[:, :, 1]

    def _lead(self, data: FinderData, theta: Array) -> Array:
        axle = data.frame["axle"].to_numpy()
        lead = data.lead_share.copy()
        for m, p in zip(self.levels, theta, strict=True):
            sel = np.asarray(data.mode == m)
            lead[sel] = np.where(axle[sel] == 1, p, 1.0 - p)
        return lead

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        lp, tp = self._per_wheelset(data)
        lead = self._lead(data, theta)[:, None]
        new = lp * lead + tp * (1.0 - lead)
        nominal = lp * data.lead_share[:, None] + tp * (1.0 - data.lead_share[:, None])
        return _log_ratio(new, nominal)

    def features(self, data: FinderData, theta: Array) -> Array:
        lp, tp = self._per_wheelset(data)
        lead = self._lead(data, theta)[:, None]
        p_now = lp * lead + tp * (1.0 - lead)
        axle = data.frame["axle"].to_numpy()
        sign = np.where(axle == 1, 1.0, -1.0)[:, None]
        d = _relative(sign * (lp - tp), p_now)
        return self.per_level(data, data.mode, lambda sel: d[sel])


class CurveAsymmetry(_ShareByLevel):
    """One left-curve share per route (the levels)."""

    code = "curve_asymmetry"
    needs = ("side", "route with left and right curves")
    covariate_name = "side"
    linear = False
    explanation = ("Left and right wheels see a different mix of curve directions than the "
                   "route description says: a share q of the curved length bends left.")
    prefix = "left_curve_share_"
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
        self.levels = tuple(self._eligible(data))
        lr = data.left_right
        self.nominal = tuple(float((lr[:, 0] / (lr[:, 0] + lr[:, 1]))[data.route == r][0])
                             for r in self.levels)

    def start(self) -> Array:
        return np.array(self.nominal, dtype=float)

    def level_sentence(self, level: str, share: float) -> str:
        return f"on {level} {100 * share:.0f} % of the curved length bends left"

    def _p(self, data: FinderData, lr: Array) -> Array:
        return weighted_measure(data.parts, data.lead_share, data.measure_index, lr)

    def _weights(self, data: FinderData, theta: Array) -> Array:
        lr = np.ones((data.n, 2))
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        total = left + right
        for name, q in zip(self.levels, theta, strict=True):
            sel = np.asarray(data.route == name)
            lr[sel, 0] = q * total[sel] / left[sel]
            lr[sel, 1] = (1.0 - q) * total[sel] / right[sel]
        return lr

    def log_factor(self, data: FinderData, theta: Array) -> Array:
        new = self._p(data, self._weights(data, theta))
        if "curve_nominal_measure" not in data.cache:   # theta-independent
            data.cache["curve_nominal_measure"] = self._p(data, np.ones((data.n, 2)))
        return _log_ratio(new, data.cache["curve_nominal_measure"])

    @staticmethod
    def _side_parts(data: FinderData) -> tuple[Array, Array]:
        """(n, 2) measure of the left and of the right curves alone above the tangent
        (theta-independent: computed once per dataset)."""
        if "curve_side_parts" not in data.cache:
            def measure(shares: Array) -> Array:
                return weighted_measure(data.parts, data.lead_share, data.measure_index,
                                        shares)
            ones, zeros = np.ones(data.n), np.zeros(data.n)
            tangent = measure(np.zeros((data.n, 2)))
            data.cache["curve_side_parts"] = (
                measure(np.column_stack([ones, zeros])) - tangent,
                measure(np.column_stack([zeros, ones])) - tangent)
        lpart, rpart = data.cache["curve_side_parts"]
        return lpart, rpart

    def features(self, data: FinderData, theta: Array) -> Array:
        p_now = self._p(data, self._weights(data, theta))
        left, right = data.left_right[:, 0], data.left_right[:, 1]
        total = left + right
        lpart, rpart = self._side_parts(data)

        def route_features(sel: Mask) -> Array:
            dp = (total[sel] / left[sel])[:, None] * lpart[sel] \
                - (total[sel] / right[sel])[:, None] * rpart[sel]
            return _relative(dp, p_now[sel])

        return self.per_level(data, data.route, route_features)


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
        self.other = WEAR_MEASURES[1 - data.measure_index]

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

    def reference_instrument(self, data: FinderData, inst: NDArray[Any], rows: Mask) -> str:
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
        coef = signature_coefficients(data)
        # the finder's precision weights of the rows when it set them (``diagnose``,
        # ``finder_shape_weights``), else plain means
        w = np.asarray(data.cache.get("shape_weights", np.ones(data.n)), dtype=float)
        est.coefs_ = {i: np.average(coef[rows & (inst == i)], axis=0,
                                    weights=w[rows & (inst == i)])
                      if (rows & (inst == i)).any() else np.zeros(3) for i in _levels(inst)}
        est.reference_ = self.reference_instrument(data, inst, rows)
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
    if "shape_coefficients" not in data.cache:   # computed once per dataset
        d = np.nan_to_num(data.shape_res, nan=0.0)
        coef, *_ = np.linalg.lstsq(data.basis.T, d.T, rcond=None)
        data.cache["shape_coefficients"] = np.asarray(coef.T)
    return np.array(data.cache["shape_coefficients"])


def signature_coefficients(data: FinderData) -> Array:
    """(n, 3) ``shape_coefficients`` less each wheel life's growth with its predicted worn area
    (``finder_shape_growth``) and less the shape of the wheel's position (bogie type and
    leading share, ``finder_shape_position``): what an instrument's signature, the same at
    every wear and in every position, is estimated and tested on."""
    if "signature_coefficients" not in data.cache:   # computed once per dataset
        col = data.column("instrument_id")
        inst = None if col is None else col.astype(str).to_numpy()
        grown = without_wear_growth(shape_coefficients(data), data.base.sum(axis=1),
                                    life_ids(data.frame, data.mileage_km), inst)
        bogie = data.column("bogie_type")
        # the positions tested in the curve-space metric (``finder_shape_test.whitened_shape``)
        gram = data.basis @ data.basis.T
        chol = np.linalg.cholesky(gram + 1e-12 * np.eye(gram.shape[0]))
        data.cache["signature_coefficients"] = without_position_shape(
            grown, wheel_positions(None if bogie is None else bogie.to_numpy(),
                                   data.lead_share), inst, metric=chol)
    return np.array(data.cache["signature_coefficients"])
