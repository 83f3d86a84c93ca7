"""Prediction with the hybrid wear model of seed 001 (§2.4).

* Weighted wear measure of a route (seed 001 eq. 2): P = sum_i c_i P_i, c_i the route share
  of curve class i, P_i the curve-radius table value for the wheel's bogie type, wheelset
  position, rail and region (:mod:`wearcast.statistics.route_measure`).
* Prediction (eq. 4): k_s = c_s P_s per region, A(s) = A_0 + k_s s, wear curves from the
  wear states, flange and tread joined with a moving average (§2.4), worn profile
  z = z_ref - w, and Sd/Sh/qR per mileage (:mod:`wearcast.statistics.hybrid_profiles`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.hybrid import QUANTILES, HybridModel
from wearcast.statistics.hybrid_profiles import profile_at_areas
from wearcast.statistics.json_values import finite_list_or_none
from wearcast.statistics.route_measure import (
    UnknownBogieTypeError,
    check_choice,
    weighted_wear_measure,
)
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_rates import normal_quantile
from wearcast.statistics.wear_tables import WearTable


@dataclass(frozen=True)
class Prediction:
    """Prediction for one wheel on one route (seed 001 §2.4).

    Arrays over mileage have length M; ``*_area_mm2`` and ``*_rate_mm2_per_km`` carry the
    quantiles in ``quantiles`` (default P10/P50/P90) along their first axis. Curves, profile
    and parameters are those of the median (P50) areas.
    """

    mileage_km: np.ndarray
    quantiles: tuple[float, ...]
    weighted_measure: dict[str, float]
    flange_rate_mm2_per_km: np.ndarray
    tread_rate_mm2_per_km: np.ndarray
    flange_area_mm2: np.ndarray
    tread_area_mm2: np.ndarray
    grid_y_mm: np.ndarray
    wear_mm: np.ndarray
    z_mm: np.ndarray
    sd_mm: np.ndarray
    sh_mm: np.ndarray
    qr_mm: np.ndarray
    extrapolated: np.ndarray
    start_areas_mm2: dict[str, float] = field(default_factory=dict)

    @property
    def any_extrapolated(self) -> bool:
        return bool(np.any(self.extrapolated))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mileage_km": self.mileage_km.tolist(),
            "quantiles": list(self.quantiles),
            "weighted_measure": dict(self.weighted_measure),
            "flange_rate_mm2_per_km": self.flange_rate_mm2_per_km.tolist(),
            "tread_rate_mm2_per_km": self.tread_rate_mm2_per_km.tolist(),
            "flange_area_mm2": self.flange_area_mm2.tolist(),
            "tread_area_mm2": self.tread_area_mm2.tolist(),
            "grid_y_mm": self.grid_y_mm.tolist(),
            "wear_mm": self.wear_mm.tolist(),
            "z_mm": self.z_mm.tolist(),
            "sd_mm": finite_list_or_none(self.sd_mm),
            "sh_mm": finite_list_or_none(self.sh_mm),
            "qr_mm": finite_list_or_none(self.qr_mm),
            "extrapolated": self.extrapolated.tolist(),
            "start_areas_mm2": dict(self.start_areas_mm2),
        }
        return out


def region_rates(model: HybridModel, route: Route, table: pd.DataFrame | WearTable, *,
                 bogie_type: str, axle: int, side: str,
                 quantiles: Sequence[float] = QUANTILES,
                 weighted_measures: Mapping[str, float] | None = None,
                 ) -> tuple[dict[str, float], dict[str, NDArray]]:
    """Weighted measures P_s and rate quantiles k_s,q = c_s P_s (1 + z_q u) per region.

    u is the relative predictive uncertainty of c_s (standard error and spread of the
    calibration); rates are clipped at 0. Seed 001 eq. 4. ``weighted_measures`` gives P_s
    per region when the caller has it already (:func:`model_weighted_measures` of the same
    model, route, table and wheel position); otherwise it is computed.
    """
    if bogie_type not in model.bogie_types:
        raise UnknownBogieTypeError(
            f"bogie_type: the model covers {model.bogie_types}, not {bogie_type!r}"
        )
    if weighted_measures is None:
        weighted_measures = model_weighted_measures(model, route, table, bogie_type=bogie_type,
                                                    axle=axle, side=side)
    z = normal_quantile(np.asarray(quantiles, dtype=float))
    p_s: dict[str, float] = {}
    rates: dict[str, NDArray] = {}
    for r in REGIONS:
        cal = model.region(r)
        p_s[r] = float(weighted_measures[r])
        k = cal.c_s * p_s[r]
        rates[r] = np.maximum(0.0, k * (1.0 + z * cal.c_s_rel_predictive))
    return p_s, rates


def model_weighted_measures(model: HybridModel, route: Route,
                            table: pd.DataFrame | WearTable, *, bogie_type: str, axle: int,
                            side: str) -> dict[str, float]:
    """P_s per region (seed 001 eq. 2) with the model's running mode and wear measure."""
    return {
        r: weighted_wear_measure(route, table, bogie_type=bogie_type, axle=axle, side=side,
                                 running_mode=model.running_mode, region=r,
                                 measure=model.measure)
        for r in REGIONS
    }


def start_areas(given: Mapping[str, float | None] | None, name: str) -> dict[str, float]:
    """Wear areas [mm²] of the start state per region: the measured ones in ``given``
    (each finite and >= 0), 0 (the new profile) for the regions it leaves out.

    ``name`` is the argument's name in the error messages.
    """
    start: dict[str, float] = {r: 0.0 for r in REGIONS}
    for r, v in (given or {}).items():
        check_choice(r, REGIONS, f"{name}.{r}")
        if v is None or not math.isfinite(float(v)) or float(v) < 0:
            raise ValueError(f"{name}.{r}: must be finite and >= 0")
        start[r] = float(v)
    return start

def predict(
    model: HybridModel,
    route: Route,
    table: pd.DataFrame | WearTable,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    mileage_km: ArrayLike,
    start_areas_mm2: Mapping[str, float] | None = None,
    quantiles: Sequence[float] = QUANTILES,
    weighted_measures: Mapping[str, float] | None = None,
) -> Prediction:
    """Predict wear areas, wear curve, worn profile and Sd/Sh/qR of a wheel on a route.

    Parameters
    ----------
    model : calibrated hybrid model
    route : the route to predict for (its classes must lie within the table's radii)
    table : curve-radius table with the model's measure (compile it once for speed)
    bogie_type, axle (1|2), side ('left'|'right') : the wheel's position
    mileage_km : (M,) mileages [km] from the start state
    start_areas_mm2 : measured areas {'flange': ..., 'tread': ...} [mm²] of the start state
        (default: new profile, 0)
    quantiles : area quantiles to report (the curves use the median)
    weighted_measures : P_s per region if known already (see :func:`region_rates`)

    Returns
    -------
    Prediction. k_s = c_s P_s (seed 001 eq. 4), A(s) = A_0 + k_s s.
    """
    s = np.atleast_1d(np.asarray(mileage_km, dtype=float))
    if s.ndim != 1 or np.any(~np.isfinite(s)) or np.any(s < 0):
        raise ValueError("mileage_km: must be a list of finite mileages >= 0")
    q = tuple(float(v) for v in quantiles)
    if 0.5 not in q:
        raise ValueError("quantiles: must include 0.5 (the median drives the wear curves)")
    start = start_areas(start_areas_mm2, "start_areas_mm2")
    p_s, rates = region_rates(model, route, table, bogie_type=bogie_type, axle=axle, side=side,
                              quantiles=q, weighted_measures=weighted_measures)
    areas = {r: start[r] + rates[r][:, None] * s[None, :] for r in REGIONS}
    median = q.index(0.5)
    wear, z, params, extrapolated = profile_at_areas(
        model, areas["flange"][median], areas["tread"][median]
    )
    return Prediction(
        mileage_km=s,
        quantiles=q,
        weighted_measure=p_s,
        flange_rate_mm2_per_km=rates["flange"],
        tread_rate_mm2_per_km=rates["tread"],
        flange_area_mm2=areas["flange"],
        tread_area_mm2=areas["tread"],
        grid_y_mm=model.grid_y_mm,
        wear_mm=wear,
        z_mm=z,
        sd_mm=params[:, 0],
        sh_mm=params[:, 1],
        qr_mm=params[:, 2],
        extrapolated=extrapolated,
        start_areas_mm2=start,
    )
