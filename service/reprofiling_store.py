"""Remaining mileage to reprofiling of a stored hybrid model (``POST
/v1/models/{id}/reprofiling``): :mod:`wearcast.statistics.reprofiling` run from the wheel's
start state, its errors turned into 422s, answered as the :class:`ReprofilingOut` schema or
as JSON bytes.
"""

from __future__ import annotations

import math
from typing import Any, TypedDict

import numpy as np
import orjson
from sqlalchemy.orm import Session

from wearcast.service.model_loading import (
    ModelInputs,
    RouteInputs,
    load_inputs,
    request_covariates,
    statistics_error,
    weighted_measures,
    wheel_model,
)
from wearcast.service.reprofiling_schemas import ReprofilingIn, ReprofilingOut
from wearcast.service.wheel_start import WheelStart, wheel_start
from wearcast.statistics import hybrid
from wearcast.statistics import reprofiling as stat_reprofiling
from wearcast.statistics.extension import ExtendedModel
from wearcast.statistics.json_values import finite_or_none


class _Position(TypedDict):
    """A wheel's position, passed on as keyword arguments."""

    bogie_type: str
    axle: int
    side: str


def _wheel_hybrid(inputs: ModelInputs, route: RouteInputs, body: ReprofilingIn,
                  start: WheelStart) -> tuple[hybrid.HybridModel, dict[str, float] | None]:
    """The hybrid model of this wheel (an extended model made concrete for its covariates)
    and its weighted measures P_s on the route."""
    position: _Position = {"bogie_type": start.bogie_type, "axle": start.axle,
                           "side": start.side}
    measures = weighted_measures(inputs, route.route, **position)
    model = inputs.model
    if isinstance(model, ExtendedModel):
        covariates = request_covariates(inputs, route, body.covariates) or {}
        for key, value in (start.covariates or {}).items():
            covariates.setdefault(key, value)
        model = wheel_model(model, route.route, inputs.table, covariates=covariates,
                            **position)
    return model, measures


def parameter_corridor(inputs: ModelInputs, route: RouteInputs, body: ReprofilingIn,
                       start: WheelStart, mileage_km: np.ndarray
                       ) -> stat_reprofiling.ParameterCorridor:
    """Predicted Sd/Sh/qR P10/P50/P90 from the wheel's start state (for pictures)."""
    try:
        model, measures = _wheel_hybrid(inputs, route, body, start)
        return stat_reprofiling.parameter_corridor(
            model, route.route, inputs.table, mileage_km, bogie_type=start.bogie_type,
            axle=start.axle, side=start.side, start_areas=start.areas_mm2,
            start_parameters=start.parameters, weighted_measures=measures)
    except ValueError as exc:
        raise statistics_error(exc) from exc


def reprofiling_payload(inputs: ModelInputs, route: RouteInputs, model_id: int,
                        body: ReprofilingIn, start: WheelStart) -> dict[str, Any]:
    """The :class:`ReprofilingOut` fields (plain floats; None where not finite)."""
    limits = body.limits.model_dump(exclude_none=True) if body.limits else None
    position: _Position = {"bogie_type": start.bogie_type, "axle": start.axle,
                           "side": start.side}
    try:
        model, measures = _wheel_hybrid(inputs, route, body, start)
        result = stat_reprofiling.reprofiling_mileage(
            model, route.route, inputs.table, **position,
            limits=limits if limits else stat_reprofiling.DEFAULT_LIMITS,
            start_areas=start.areas_mm2, weighted_measures=measures,
            start_parameters=start.parameters)
    except ValueError as exc:
        raise statistics_error(exc) from exc
    remaining = [result.mileage_p10_km, result.mileage_p50_km, result.mileage_p90_km]

    def opt(offset: float) -> dict[str, float | None]:
        p10, p50, p90 = (offset + v if math.isfinite(v) else None for v in remaining)
        return {"p10": p10, "p50": p50, "p90": p90}

    return {
        "model_id": model_id, "route": route.name, "wheel_id": body.wheel_id, **position,
        "start_mileage_km": start.mileage_km, "start_measurement_id": start.measurement_id,
        "start_areas_mm2": start.areas_mm2 or {"flange": 0.0, "tread": 0.0},
        "remaining_km": opt(0.0), "mileage_km": opt(start.mileage_km),
        "governing_limit": result.governing_limit, "sd_mm": finite_or_none(result.sd_mm),
        "sh_mm": finite_or_none(result.sh_mm), "qr_mm": finite_or_none(result.qr_mm),
        "extrapolated": bool(result.extrapolated), "reason": result.reason,
        "limits": {k: float(v) for k, v in result.limits.items()},
        "crossed_limits": dict(result.crossed_limits),
        "start_parameters_mm": start.parameters, "start_notes": list(start.notes),
    }


def reprofiling(session: Session, model_id: int, body: ReprofilingIn) -> ReprofilingOut:
    """Mileage at which the first limit is crossed, P10/P50/P90, and the governing limit.

    With ``wheel_id`` the wheel's position comes from storage and the remaining mileage
    starts at its latest measured profile (its measured wear areas); ``mileage_km`` is then
    that measurement's mileage plus the remaining mileage.
    """
    inputs, route = load_inputs(session, model_id, body.route_id, body.route)
    payload = reprofiling_payload(inputs, route, model_id, body, wheel_start(session, body))
    return ReprofilingOut.model_validate(payload)


def reprofiling_json(inputs: ModelInputs, route: RouteInputs, model_id: int,
                     body: ReprofilingIn, start: WheelStart) -> bytes:
    """:func:`reprofiling`'s answer as JSON bytes (the :class:`ReprofilingOut` schema)."""
    return orjson.dumps(reprofiling_payload(inputs, route, model_id, body, start))
