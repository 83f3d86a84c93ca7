"""Wear predictions of a stored hybrid model (``POST /v1/models/{id}/predict``).

The modelling is :mod:`wearcast.statistics.hybrid` (seed 001 eqs. 2–4); this module runs it
on a model's inputs (:mod:`wearcast.service.model_loading`), turns its ``"field: reason"``
errors into 422s (unknown bogie type, radius outside the table, ...), and answers as the
:class:`PredictionOut` schema or, on the hot path, as JSON bytes written by orjson straight
from the numpy arrays (every request computes its own: nothing caches a response). An
extended model with cause ``nonlinear_progression`` predicts with its mileage exponent.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import orjson
from sqlalchemy.orm import Session

from wearcast.service.cache import LruCache
from wearcast.service.model_loading import (
    LoadedModel,
    ModelInputs,
    RouteInputs,
    load_inputs,
    request_covariates,
    statistics_error,
    weighted_measures,
    wheel_model,
)
from wearcast.service.prediction_schemas import (
    PredictIn,
    PredictionAt,
    PredictionOut,
    QuantileValues,
)
from wearcast.service.wheel_start import WheelStart, wheel_start
from wearcast.statistics import hybrid_prediction
from wearcast.statistics.extension import ExtendedModel
from wearcast.statistics.json_values import finite_list_or_none, finite_or_none
from wearcast.statistics.routes import Route


def run_prediction(loaded: LoadedModel | ModelInputs, route: Route, *, bogie_type: str,
                   axle: int, side: str, mileage_km: list[float],
                   start_areas_mm2: dict[str, float] | None = None,
                   covariates: dict[str, Any] | None = None) -> hybrid_prediction.Prediction:
    try:
        measures = weighted_measures(loaded, route, bogie_type=bogie_type, axle=axle,
                                     side=side)
        model = loaded.model
        if isinstance(model, ExtendedModel) and model.cause == "nonlinear_progression" \
                and not start_areas_mm2:
            return model.predict(route, loaded.table, bogie_type=bogie_type, axle=axle,
                                 side=side, mileage_km=mileage_km, covariates=covariates)
        plain = wheel_model(model, route, loaded.table, bogie_type=bogie_type, axle=axle,
                            side=side, covariates=covariates)
        return hybrid_prediction.predict(plain, route, loaded.table, bogie_type=bogie_type,
                                         axle=axle, side=side, mileage_km=mileage_km,
                                         start_areas_mm2=start_areas_mm2,
                                         weighted_measures=measures)
    except ValueError as exc:
        raise statistics_error(exc) from exc


def compute_prediction(inputs: ModelInputs, route: RouteInputs, body: PredictIn
                       ) -> hybrid_prediction.Prediction:
    assert body.bogie_type is not None and body.axle is not None and body.side is not None
    return run_prediction(inputs, route.route, bogie_type=body.bogie_type, axle=body.axle,
                          side=body.side, mileage_km=body.mileage_km,
                          covariates=request_covariates(inputs, route, body.covariates))


def _measured_prediction(inputs: ModelInputs, route: RouteInputs, body: PredictIn,
                         start: WheelStart) -> tuple[PredictIn, hybrid_prediction.Prediction]:
    """A prediction from a measured start: areas grow from the measured ones and Sd/Sh/qR
    follow the measured values plus the model's changes (as reprofiling does); mileages
    count from the start measurement. Returns the request with the wheel's position."""
    import dataclasses

    body = body.model_copy(update={"bogie_type": start.bogie_type, "axle": start.axle,
                                   "side": start.side})
    covariates = request_covariates(inputs, route, body.covariates) or {}
    for key, value in (start.covariates or {}).items():
        covariates.setdefault(key, value)
    result = run_prediction(inputs, route.route, bogie_type=start.bogie_type, axle=start.axle,
                            side=start.side, mileage_km=[0.0, *body.mileage_km],
                            start_areas_mm2=start.areas_mm2, covariates=covariates or None)
    keep = slice(1, None)
    changes: dict[str, Any] = {
        name: np.asarray(getattr(result, name))[..., keep]
        for name in ("mileage_km", "flange_area_mm2", "tread_area_mm2", "extrapolated")}
    for name in ("wear_mm", "z_mm"):
        changes[name] = np.asarray(getattr(result, name))[keep]
    for name in ("sd_mm", "sh_mm", "qr_mm"):
        values = np.asarray(getattr(result, name), dtype=float)
        if start.parameters is not None:
            values = values + (start.parameters[name] - values[0])
        changes[name] = values[keep]
    return body, dataclasses.replace(result, **changes)


def _start_fields(start: WheelStart | None) -> dict[str, Any]:
    if start is None:
        return {"start_mileage_km": None, "start_measurement_id": None,
                "start_parameters_mm": None, "start_notes": []}
    return {"start_mileage_km": start.mileage_km, "start_measurement_id": start.measurement_id,
            "start_parameters_mm": start.parameters, "start_notes": list(start.notes)}


def predict(session: Session, model_id: int, body: PredictIn) -> PredictionOut:
    """Wear areas (P10/P50/P90), wear curve, worn profile and Sd/Sh/qR per mileage."""
    inputs, route = load_inputs(session, model_id, body.route_id, body.route)
    if body.measured_start:
        start = wheel_start(session, body)
        body, result = _measured_prediction(inputs, route, body, start)
        out = prediction_out(model_id, route.name, body, result)
        return out.model_copy(update=_start_fields(start))
    return prediction_out(model_id, route.name, body, compute_prediction(inputs, route, body))


def predict_json(inputs: ModelInputs, route: RouteInputs, model_id: int, body: PredictIn,
                 start: WheelStart | None = None) -> bytes:
    """:func:`predict`'s answer as JSON bytes (the :class:`PredictionOut` schema); ``start``
    is the measured start state when the request names one."""
    if start is not None:
        body, result = _measured_prediction(inputs, route, body, start)
    else:
        result = compute_prediction(inputs, route, body)
    payload = _prediction_payload(model_id, route.name, body, result)
    payload.update(_start_fields(start))
    return orjson.dumps(payload, option=orjson.OPT_SERIALIZE_NUMPY)


_reference_cache: LruCache[np.ndarray] = LruCache(8)


def _reference_array(grid_y_mm: np.ndarray) -> np.ndarray:
    """S1002 heights [mm] on a lateral grid (read-only), cached by the grid's bytes."""
    from wearcast.physics.profiles.s1002 import s1002_height_mm

    grid = np.ascontiguousarray(grid_y_mm, dtype=float)

    def make() -> np.ndarray:
        z = np.ascontiguousarray(s1002_height_mm(grid), dtype=float)
        z.setflags(write=False)
        return z

    return _reference_cache.get_or_create(grid.tobytes(), make)


def _reference_heights(grid_y_mm: np.ndarray) -> list[float]:
    """S1002 heights [mm] on a lateral grid as a new list (callers may change it)."""
    return _reference_array(grid_y_mm).tolist()


def _quantile_dict(values: np.ndarray, quantiles: tuple[float, ...]) -> dict[str, float]:
    """P10/P50/P90 of ``values`` given at ``quantiles``."""
    pick = dict(zip(quantiles, values.tolist(), strict=True))
    return {"p10": pick[0.1], "p50": pick[0.5], "p90": pick[0.9]}


def _q(values: np.ndarray, quantiles: tuple[float, ...]) -> QuantileValues:
    return QuantileValues(**_quantile_dict(values, quantiles))


def _prediction_payload(model_id: int, route_name: str, body: PredictIn,
                        result: hybrid_prediction.Prediction) -> dict[str, Any]:
    """The :class:`PredictionOut` fields with numpy arrays where orjson can write them
    directly (non-finite numbers become null, as :func:`prediction_out` does)."""
    q = result.quantiles
    wear = np.ascontiguousarray(result.wear_mm, dtype=float)
    z = np.ascontiguousarray(result.z_mm, dtype=float)
    flange, tread = result.flange_area_mm2, result.tread_area_mm2
    sd, sh, qr = (np.asarray(v, dtype=float).tolist()
                  for v in (result.sd_mm, result.sh_mm, result.qr_mm))
    points = [{
        "mileage_km": s, "flange_area_mm2": _quantile_dict(flange[:, i], q),
        "tread_area_mm2": _quantile_dict(tread[:, i], q),
        "sd_mm": sd[i], "sh_mm": sh[i], "qr_mm": qr[i],
        "extrapolated": bool(result.extrapolated[i]), "wear_mm": wear[i], "z_mm": z[i],
    } for i, s in enumerate(np.asarray(result.mileage_km, dtype=float).tolist())]
    return {
        "model_id": model_id, "route": route_name, "bogie_type": body.bogie_type,
        "axle": body.axle, "side": body.side,
        "weighted_measure": {k: float(v) for k, v in result.weighted_measure.items()},
        "rates_mm2_per_km": {"flange": _quantile_dict(result.flange_rate_mm2_per_km, q),
                             "tread": _quantile_dict(result.tread_rate_mm2_per_km, q)},
        "start_areas_mm2": {k: float(v) for k, v in result.start_areas_mm2.items()},
        "y_mm": np.ascontiguousarray(result.grid_y_mm, dtype=float),
        "reference_z_mm": _reference_array(result.grid_y_mm), "points": points,
    }


def prediction_out(model_id: int, route_name: str, body: PredictIn,
                   result: hybrid_prediction.Prediction) -> PredictionOut:
    q = result.quantiles
    points = []
    for i, s in enumerate(result.mileage_km):
        points.append(PredictionAt(
            mileage_km=float(s), flange_area_mm2=_q(result.flange_area_mm2[:, i], q),
            tread_area_mm2=_q(result.tread_area_mm2[:, i], q),
            sd_mm=finite_or_none(result.sd_mm[i]), sh_mm=finite_or_none(result.sh_mm[i]),
            qr_mm=finite_or_none(result.qr_mm[i]), extrapolated=bool(result.extrapolated[i]),
            wear_mm=finite_list_or_none(result.wear_mm[i]),
            z_mm=finite_list_or_none(result.z_mm[i])))
    return PredictionOut(
        model_id=model_id, route=route_name, bogie_type=body.bogie_type, axle=body.axle,
        side=body.side, weighted_measure={k: float(v) for k, v in
                                          result.weighted_measure.items()},
        rates_mm2_per_km={"flange": _q(result.flange_rate_mm2_per_km, q),
                          "tread": _q(result.tread_rate_mm2_per_km, q)},
        start_areas_mm2={k: float(v) for k, v in result.start_areas_mm2.items()},
        y_mm=result.grid_y_mm.tolist(),
        reference_z_mm=_reference_heights(result.grid_y_mm), points=points)
