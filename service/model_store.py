"""Hybrid models in storage: calibrate, read, predict, remaining mileage to reprofiling.

The modelling is :mod:`wearcast.statistics.hybrid` (seed 001 eqs. 2–4) and
:mod:`wearcast.statistics.reprofiling`; this module loads the inputs from storage, calls them
and turns their ``"field: reason"`` errors into 422s (unknown bogie type, radius outside the
table, ...).

A stored model's state carries its kind: a plain hybrid model (``HybridModel.to_dict()``, no
``kind`` key) or a model extended by the discrepancy finder (``{"kind": "extended", ...}``,
:class:`wearcast.statistics.discrepancy.ExtendedModel`). Predict and reprofiling dispatch on
it: an extended model is turned into the plain hybrid model of the wheel asked about
(``ExtendedModel.for_wheel``, from the route's attributes and the request's ``covariates``),
and ``nonlinear_progression`` predicts with its mileage exponent.

Hot path (``POST /v1/models/{id}/predict`` and ``/reprofiling``): models and routes are
never updated or deleted once created (no endpoint or store function does either), so after a
first request has read them, :func:`cached_inputs` finds the deserialised model, its compiled
table and the stored route in process under (database URL, model id) and (database URL,
route id or name) without touching the database. :func:`predict_json` and
:func:`reprofiling_json` then compute the answer (every request computes its own: nothing
caches a response) and serialise it with orjson straight from the numpy arrays.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeAlias, TypedDict

import numpy as np
import orjson
from sqlalchemy import bindparam, func, insert, select
from sqlalchemy.orm import Session, defer

from wearcast.physics.vocabulary import REGIONS
from wearcast.service import measurement_store, route_store, wear_table_store
from wearcast.service import models_db as db
from wearcast.service.cache import LruCache
from wearcast.service.errors import ApiError, NotFound, Unprocessable, from_value_error
from wearcast.service.schemas import (
    ModelIn,
    ModelOut,
    PredictIn,
    PredictionAt,
    PredictionOut,
    QuantileValues,
    ReprofilingIn,
    ReprofilingOut,
)
from wearcast.statistics import hybrid
from wearcast.statistics import reprofiling as stat_reprofiling
from wearcast.statistics.discrepancy import ExtendedModel
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import RadiusOutOfTableError, WearTable

#: Deserialised models kept in process (a model's state is ~100 kB of JSON).
MODEL_CACHE_SIZE = 32
AnyModel: TypeAlias = hybrid.HybridModel | ExtendedModel
_models: LruCache[AnyModel] = LruCache(MODEL_CACHE_SIZE)


def model_from_state(state: dict[str, Any]) -> AnyModel:
    """The model a stored state describes, by its ``kind`` (default: a plain hybrid model)."""
    if state.get("kind") == "extended":
        return ExtendedModel.from_dict(state)
    return hybrid.HybridModel.from_dict(state)


def base_model(model: AnyModel) -> hybrid.HybridModel:
    """The calibrated hybrid model under an extension (the model itself when plain)."""
    return model.base if isinstance(model, ExtendedModel) else model


def model_kind(model: AnyModel) -> str:
    return "extended" if isinstance(model, ExtendedModel) else "hybrid"


def _statistics_error(exc: ValueError, route_field: str = "route") -> ApiError:
    if isinstance(exc, RadiusOutOfTableError):
        return Unprocessable(f"{route_field}.classes.radius_m", str(exc).partition(": ")[2])
    return from_value_error(exc)


def get_model_row(session: Session, model_id: int) -> db.Model:
    row = session.get(db.Model, model_id)
    if row is None:
        raise NotFound("model_id", f"no model with id {model_id}")
    return row


#: Weighted wear measures P_s kept in process (a few floats each).
MEASURE_CACHE_SIZE = 1024
_measures: LruCache[dict[str, float]] = LruCache(
    MEASURE_CACHE_SIZE)


@dataclass(frozen=True)
class ModelInputs:
    """A model, its compiled wear table and the table's content key (sha256, rows)."""

    model: AnyModel
    table: WearTable
    table_key: tuple[str, int]


@dataclass(frozen=True)
class LoadedModel:
    row: db.Model
    model: AnyModel
    table: WearTable
    table_key: tuple[str, int] | None = None


def load_model(session: Session, model_id: int) -> LoadedModel:
    """The model row, its deserialised hybrid model and its compiled wear table.

    Models are never updated, so the deserialised model is cached in process under
    (database URL, model id, created_at) and its JSON state is only read on a miss; the
    table is cached by its content hash (:func:`wear_table_store.compiled_table`).
    """
    row = session.get(db.Model, model_id, options=[defer(db.Model.state),
                                                   defer(db.Model.spec)])
    if row is None:
        raise NotFound("model_id", f"no model with id {model_id}")
    inputs = model_inputs(session, model_id)
    return LoadedModel(row, inputs.model, inputs.table, inputs.table_key)


# built once: constructing a statement costs more than running it on a cache hit
_MODEL_INPUTS = (
    select(db.Model.created_at, db.Model.wear_table_id, db.WearTable.sha256,
           db.WearTable.n_rows)
    .join(db.WearTable, db.WearTable.id == db.Model.wear_table_id)
    .where(db.Model.id == bindparam("model_id")))


def model_inputs(session: Session, model_id: int) -> ModelInputs:
    """The deserialised model and its compiled table, from one small query when cached.

    The query reads the model's id, creation time and table reference and the table's
    content hash; the model's JSON state and the table's rows are read only on a cache miss.
    """
    found = session.execute(_MODEL_INPUTS, {"model_id": model_id}).first()
    if found is None:
        if session.scalar(select(db.Model.kind).where(db.Model.id == model_id)) == "physics":
            raise Unprocessable("model_id", f"model {model_id} is a physics model: it has no "
                                "curve-radius table; use POST /v1/models/{id}/predict, "
                                "/reprofiling or /diagnose")
        raise NotFound("model_id", f"no model with id {model_id}")
    created_at, table_id, sha256, n_rows = found  # the inner join: a hybrid model's table
    assert table_id is not None

    def deserialise() -> AnyModel:
        state = session.scalar(select(db.Model.state).where(db.Model.id == model_id))
        if state is None:
            raise NotFound("model_id", f"no model with id {model_id}")
        return model_from_state(state)

    model = _models.get_or_create((str(session.get_bind().engine.url), model_id, created_at),
                                  deserialise)
    table = wear_table_store.cached_compiled_table(session, table_id, sha256, n_rows)
    return ModelInputs(model, table, (sha256, n_rows))


def weighted_measures(inputs: ModelInputs | LoadedModel, route: Route, *, bogie_type: str,
                      axle: int, side: str) -> dict[str, float] | None:
    """P_s per region (seed 001 eq. 2) for a model, route and wheel position, cached in
    process under (table content, measure, running mode, route, position).

    None when the model does not cover the bogie type (the statistics core then raises its
    error) or the table's content key is unknown. Raises the statistics core's errors
    (e.g. a radius outside the table) uncached.
    """
    model = base_model(inputs.model)  # P_s does not depend on c_s or the extension
    if inputs.table_key is None or bogie_type not in model.bogie_types:
        return None
    key = (inputs.table_key, model.measure, model.running_mode, route, bogie_type, axle, side)
    return dict(_measures.get_or_create(key, lambda: hybrid.model_weighted_measures(
        model, route, inputs.table, bogie_type=bogie_type, axle=axle, side=side)))


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return _jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def create_model(session: Session, body: ModelIn) -> db.Model:
    """Calibrate a model on the measurements the filter selects (profiles only) and store it.

    Seed 001 eq. 3: c_s = k_m / P_m per region, P_m from the calibration route and the table.
    """
    table = wear_table_store.compiled_table(session, body.wear_table_id)
    route_row = route_store.get_route(session, body.calibration.route_id, "calibration.route_id")
    route = route_store.to_domain(route_row)
    filter_ = dict(body.calibration.filter)
    filter_.setdefault("kind", "profile")
    ids = measurement_store.matching_ids(session, filter_, "calibration.filter")
    frame, curves = measurement_store.calibration_frame(session, ids)
    if frame.empty:
        raise Unprocessable("calibration.filter", "no profile measurements match the filter")
    usable = frame["flange_area_mm2"].notna() & frame["tread_area_mm2"].notna()
    frame = frame[usable.to_numpy()].reset_index(drop=True)
    curves_2d = np.vstack([c for c, ok in zip(curves, usable, strict=True) if ok]) \
        if len(frame) else np.empty((0, 0))
    if frame.empty:
        raise Unprocessable("calibration.filter", "no matching measurement has wear areas")
    frame["route"] = route.name
    try:
        model = hybrid.calibrate(frame, route, table, wear_curves_mm=curves_2d,
                                 measure=body.measure, running_mode=body.running_mode)
    except ValueError as exc:
        raise _statistics_error(exc, "calibration.route_id") from exc
    row = db.Model(name=body.name, measure=body.measure, running_mode=body.running_mode,
                   wear_table_id=body.wear_table_id, route_id=route_row.id,
                   spec=body.model_dump(mode="json"), state=_jsonable(model.to_dict()))
    session.add(row)
    session.flush()
    used = frame["measurement_id"].astype(int).tolist()
    for start in range(0, len(used), 5000):
        session.execute(insert(db.ModelCalibrationMeasurement),
                        [{"model_id": row.id, "measurement_id": m}
                         for m in used[start:start + 5000]])
    session.commit()
    return row


def model_out(session: Session, row: db.Model) -> ModelOut:
    if row.kind == "physics":
        from wearcast.service import physics_model_store

        return physics_model_store.model_out(session, row)
    n = session.scalar(select(func.count()).select_from(db.ModelCalibrationMeasurement)
                       .where(db.ModelCalibrationMeasurement.model_id == row.id)) or 0
    state = row.state
    kind = "extended" if state.get("kind") == "extended" else "hybrid"
    extension = None
    if kind == "extended":
        extension = {"cause": state.get("cause"), "parameters": state.get("parameters"),
                     "log_scale": state.get("log_scale")}
        state = state["base"]
    summary: dict[str, Any] = {"bogie_types": state.get("bogie_types")}
    for region in REGIONS:
        cal = state[region]
        summary[region] = {k: cal[k] for k in ("c_s", "c_s_rel_std_error", "c_s_rel_spread",
                                               "p_m")}
        summary[region]["rate"] = cal.get("rate")
    return ModelOut(id=row.id, name=row.name, measure=row.measure,
                    running_mode=row.running_mode, wear_table_id=row.wear_table_id,
                    route_id=row.route_id, calibration=row.spec.get("calibration", {}),
                    n_calibration_measurements=int(n), summary=summary, kind=kind,
                    derived_from=row.spec.get("derived_from"), extension=extension)


#: Answers of ``GET /v1/models/{id}`` kept in process (models are never updated).
MODEL_OUT_CACHE_SIZE = 256
_model_outs: LruCache[ModelOut] = LruCache(MODEL_OUT_CACHE_SIZE)
_MODEL_OUT_KEY = (
    select(db.Model.created_at,
           select(func.count()).select_from(db.ModelCalibrationMeasurement)
           .where(db.ModelCalibrationMeasurement.model_id == bindparam("model_id"))
           .scalar_subquery())
    .where(db.Model.id == bindparam("model_id")))


def model_out_cached(session: Session, model_id: int) -> ModelOut:
    """:func:`model_out` of a stored model; its summary (from the model's JSON state, read
    only on a miss) is cached in process under (database URL, id, created_at), as models
    are never updated; the count of calibration measurements is read every time."""
    found = session.execute(_MODEL_OUT_KEY, {"model_id": model_id}).first()
    if found is None:
        raise NotFound("model_id", f"no model with id {model_id}")
    created_at, n = found
    out = _model_outs.get_or_create(
        (str(session.get_bind().engine.url), model_id, created_at),
        lambda: model_out(session, get_model_row(session, model_id)))
    return out.model_copy(update={"n_calibration_measurements": int(n or 0)})


def _q(values: np.ndarray, quantiles: tuple[float, ...]) -> QuantileValues:
    pick = {q: float(v) for q, v in zip(quantiles, values, strict=True)}
    return QuantileValues(p10=pick[0.1], p50=pick[0.5], p90=pick[0.9])


def _none_if_nan(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _list_none_if_nan(values: np.ndarray) -> list[float | None]:
    """``values`` as a list of floats, None where not finite (one pass when all are)."""
    if np.isfinite(values).all():
        return values.tolist()
    return [_none_if_nan(v) for v in values.tolist()]


def wheel_model(model: AnyModel, route: Route, table: WearTable, *, bogie_type: str,
                axle: int, side: str, covariates: dict[str, Any] | None = None
                ) -> hybrid.HybridModel:
    """The plain hybrid model for one wheel: the model itself, or an extended model's
    ``for_wheel`` (its rate factors from the wheel's position and covariates)."""
    if not isinstance(model, ExtendedModel):
        return model
    return model.for_wheel(route, table, bogie_type=bogie_type, axle=axle, side=side,
                           covariates=covariates)


def route_covariates(session: Session, route_name: str,
                     given: dict[str, Any] | None) -> dict[str, Any]:
    """A stored route's attributes overlaid with the request's covariates (extended models
    read e.g. ``flange_lubrication`` from the route and ``load_t`` from the request)."""
    out: dict[str, Any] = {}
    if route_name != "inline":
        row = route_store.find_route(session, route_name)
        if row is not None:
            out.update(row.attributes or {})
    out.update(given or {})
    return out


def run_prediction(loaded: LoadedModel | ModelInputs, route: Route, *, bogie_type: str,
                   axle: int, side: str, mileage_km: list[float],
                   start_areas_mm2: dict[str, float] | None = None,
                   covariates: dict[str, Any] | None = None) -> hybrid.Prediction:
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
        return hybrid.predict(plain, route, loaded.table, bogie_type=bogie_type,
                              axle=axle, side=side, mileage_km=mileage_km,
                              start_areas_mm2=start_areas_mm2, weighted_measures=measures)
    except ValueError as exc:
        raise _statistics_error(exc) from exc


# --- the hot path: inputs served from process memory -----------------------------------------


#: Models and stored routes the hot path keeps in process, per database.
HOT_CACHE_SIZE = 256




@dataclass(frozen=True)
class RouteInputs:
    """A route as the hot path needs it: the domain route, its name (``inline`` for a route
    given in the request) and its stored attributes (extended models read covariates there)."""

    route: Route
    name: str
    attributes: Mapping[str, Any]


_hot_models: LruCache[ModelInputs] = LruCache(HOT_CACHE_SIZE)
_hot_routes: LruCache[RouteInputs] = LruCache(HOT_CACHE_SIZE)


def _route_ref(route_id: int | str) -> tuple[str, int | str]:
    return ("id", route_id) if isinstance(route_id, int) else ("name", route_id)


def cached_inputs(database_url: str, model_id: int, route_id: int | str | None,
                  route: Any = None) -> tuple[ModelInputs, RouteInputs] | None:
    """The model's inputs and the route from process memory, or None when either has not
    been read from this database yet. No database access.

    ``route`` is an inline :class:`~wearcast.service.schemas.RouteSpec` (when ``route_id`` is
    None): it is built from the request (422 naming the field when invalid).
    """
    inputs = _hot_models.get((database_url, model_id))
    if inputs is None:
        return None
    if route_id is None:
        return inputs, _inline_route(route)
    stored = _hot_routes.get((database_url, *_route_ref(route_id)))
    return None if stored is None else (inputs, stored)


def _inline_route(route: Any) -> RouteInputs:
    if route is None:
        raise Unprocessable("route_id", "give either route_id or route")
    return RouteInputs(route_store.build_route(route, "inline", "route."), "inline", {})


def load_inputs(session: Session, model_id: int, route_id: int | str | None,
                route: Any = None) -> tuple[ModelInputs, RouteInputs]:
    """:func:`cached_inputs` read from the database (404/422 naming the field), and kept in
    process for the next requests."""
    url = str(session.get_bind().engine.url)
    inputs = model_inputs(session, model_id)
    _hot_models.put((url, model_id), inputs)
    if route_id is None:
        return inputs, _inline_route(route)
    row = route_store.find_route(session, route_id)
    if row is None:
        raise NotFound("route_id", f"no route with id or name {route_id!r}")
    stored = RouteInputs(route_store.to_domain(row), row.name, dict(row.attributes or {}))
    # a string of digits that named a route (no route had that id) may name another route
    # once a route with that id exists: only lookups that cannot change are kept
    if isinstance(route_id, int) or not route_id.isdigit() or row.id == int(route_id):
        _hot_routes.put((url, *_route_ref(route_id)), stored)
    return inputs, stored


def _covariates(inputs: ModelInputs, route: RouteInputs,
                given: dict[str, Any] | None) -> dict[str, Any] | None:
    """The covariates an extended model reads: the route's attributes overlaid with the
    request's (None for a plain model, which reads none)."""
    if not isinstance(inputs.model, ExtendedModel):
        return None
    return {**route.attributes, **(given or {})}


def compute_prediction(inputs: ModelInputs, route: RouteInputs, body: PredictIn
                       ) -> hybrid.Prediction:
    assert body.bogie_type is not None and body.axle is not None and body.side is not None
    return run_prediction(inputs, route.route, bogie_type=body.bogie_type, axle=body.axle,
                          side=body.side, mileage_km=body.mileage_km,
                          covariates=_covariates(inputs, route, body.covariates))


def _measured_prediction(inputs: ModelInputs, route: RouteInputs, body: PredictIn,
                         start: WheelStart) -> tuple[PredictIn, hybrid.Prediction]:
    """A prediction from a measured start: areas grow from the measured ones and Sd/Sh/qR
    follow the measured values plus the model's changes (as reprofiling does); mileages
    count from the start measurement. Returns the request with the wheel's position."""
    import dataclasses

    body = body.model_copy(update={"bogie_type": start.bogie_type, "axle": start.axle,
                                   "side": start.side})
    covariates = _covariates(inputs, route, body.covariates) or {}
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
    pick = dict(zip(quantiles, values.tolist(), strict=True))
    return {"p10": pick[0.1], "p50": pick[0.5], "p90": pick[0.9]}


def _prediction_payload(model_id: int, route_name: str, body: PredictIn,
                        result: hybrid.Prediction) -> dict[str, Any]:
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
                   result: hybrid.Prediction) -> PredictionOut:
    q = result.quantiles
    points = []
    for i, s in enumerate(result.mileage_km):
        points.append(PredictionAt(
            mileage_km=float(s), flange_area_mm2=_q(result.flange_area_mm2[:, i], q),
            tread_area_mm2=_q(result.tread_area_mm2[:, i], q),
            sd_mm=_none_if_nan(result.sd_mm[i]), sh_mm=_none_if_nan(result.sh_mm[i]),
            qr_mm=_none_if_nan(result.qr_mm[i]), extrapolated=bool(result.extrapolated[i]),
            wear_mm=_list_none_if_nan(result.wear_mm[i]),
            z_mm=_list_none_if_nan(result.z_mm[i])))
    return PredictionOut(
        model_id=model_id, route=route_name, bogie_type=body.bogie_type, axle=body.axle,
        side=body.side, weighted_measure={k: float(v) for k, v in
                                          result.weighted_measure.items()},
        rates_mm2_per_km={"flange": _q(result.flange_rate_mm2_per_km, q),
                          "tread": _q(result.tread_rate_mm2_per_km, q)},
        start_areas_mm2={k: float(v) for k, v in result.start_areas_mm2.items()},
        y_mm=result.grid_y_mm.tolist(),
        reference_z_mm=_reference_heights(result.grid_y_mm), points=points)


def _latest_profile(session: Session, wheel_id: str) -> tuple[db.Wheel, db.Measurement]:
    """The wheel and its latest profile measurement (with or without wear areas: a shape
    flagged against its reference still has its measured Sd/Sh/qR)."""
    wheel = session.get(db.Wheel, wheel_id)
    if wheel is None:
        raise NotFound("wheel_id", f"no wheel {wheel_id!r}")
    latest = session.scalar(
        select(db.Measurement).where(db.Measurement.wheel_id == wheel_id,
                                     db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km.desc(), db.Measurement.id.desc()).limit(1))
    if latest is None:
        raise Unprocessable("wheel_id", f"wheel {wheel_id!r} has no measured profile to start "
                            "from")
    return wheel, latest


@dataclass(frozen=True)
class WheelStart:
    """Where a wheel's remaining mileage starts: its position and latest measured state."""

    bogie_type: str
    axle: int
    side: str
    mileage_km: float = 0.0
    measurement_id: int | None = None
    areas_mm2: dict[str, float] | None = None
    covariates: dict[str, Any] | None = None
    #: measured Sd/Sh/qR [mm] the prediction starts from
    parameters: dict[str, float] | None = None
    notes: tuple[str, ...] = ()


def _measured_state(sd: float | None, sh: float | None, qr: float | None,
                    flange: float | None, tread: float | None, reference: str,
                    fits: bool | None) -> tuple[dict[str, float] | None, dict[str, float],
                                                tuple[str, ...]]:
    """Start parameters, start areas and notes of a measured state."""
    notes: list[str] = []
    parameters = None
    if None not in (sd, sh, qr) and all(math.isfinite(float(v)) for v in (sd, sh, qr)):  # type: ignore[arg-type]
        parameters = {"sd_mm": float(sd), "sh_mm": float(sh), "qr_mm": float(qr)}  # type: ignore[arg-type]
    else:
        notes.append("the measurement has no complete Sd/Sh/qR: the model's own are used")
    if flange is None or tread is None:
        areas = {"flange": 0.0, "tread": 0.0}
        why = ("its shape does not fit its reference " + reference if fits is False
               else "it has no wear areas")
        notes.append(f"wear areas start at 0 ({why}); Sd/Sh/qR start from the measured values")
    else:
        areas = {"flange": max(0.0, float(flange)), "tread": max(0.0, float(tread))}
    return parameters, areas, tuple(notes)


def _profile_start(body: ReprofilingIn | PredictIn) -> WheelStart:
    """Start state of an uploaded profile: placed by its datum, wear against its reference."""
    from wearcast.service.importing import _process_arrays
    from wearcast.service.reference_store import ReferenceSpec

    profile = body.profile
    assert profile is not None
    if len(profile.y_mm) != len(profile.z_mm):
        raise Unprocessable("profile.z_mm", f"has {len(profile.z_mm)} values, y_mm "
                            f"{len(profile.y_mm)}")
    from wearcast.physics.profiles.references import canonical_s1002_name

    name = canonical_s1002_name(profile.reference_profile)
    if name is None:
        raise Unprocessable("profile.reference_profile", "only the built-in S1002 family is "
                            "accepted here; store the profile to use an uploaded reference")
    p = _process_arrays(np.asarray(profile.y_mm, float), np.asarray(profile.z_mm, float),
                        ReferenceSpec(name, "builtin"), True)
    if isinstance(p, str):
        raise Unprocessable("profile.y_mm", f"not a usable wheel profile: {p}")
    fits = bool(p.reference_fits)
    parameters, areas, notes = _measured_state(
        p.sd_mm, p.sh_mm, p.qr_mm, p.flange_area_mm2 if fits else None,
        p.tread_area_mm2 if fits else None, name, fits)
    return WheelStart(str(body.bogie_type), int(body.axle or 1), str(body.side),
                      float(profile.mileage_km), None, areas, None, parameters, notes)


def wheel_start(session: Session | None, body: ReprofilingIn | PredictIn) -> WheelStart:
    """The wheel's position from the request, or with ``wheel_id`` / ``measurement_id``
    from storage (its latest / that measured profile as the start state: measured Sd/Sh/qR
    and wear areas), or an uploaded ``profile``; needs a session only for stored starts."""
    if body.profile is not None:
        return _profile_start(body)
    if body.wheel_id is None and body.measurement_id is None:
        return WheelStart(str(body.bogie_type), int(body.axle or 1), str(body.side))
    assert session is not None
    if body.measurement_id is not None:
        latest = session.get(db.Measurement, body.measurement_id)
        if latest is None:
            raise NotFound("measurement_id", f"no measurement {body.measurement_id}")
        wheel = session.get(db.Wheel, latest.wheel_id)
        assert wheel is not None
    else:
        assert body.wheel_id is not None
        wheel, latest = _latest_profile(session, body.wheel_id)
    for name, given, stored in (("bogie_type", body.bogie_type, wheel.bogie_type),
                                ("axle", body.axle, wheel.axle),
                                ("side", body.side, wheel.side)):
        if given is not None and given != stored:
            raise Unprocessable(name, f"wheel {wheel.wheel_id!r} has {name} {stored!r}")
    covariates = {key: value for key in ("load_t", "running_mode", "instrument_id")
                  if (value := getattr(latest, key, None)) is not None}
    parameters, areas, notes = _measured_state(
        latest.sd_mm, latest.sh_mm, latest.qr_mm, latest.flange_area_mm2,
        latest.tread_area_mm2, latest.reference_profile, latest.reference_fits)
    return WheelStart(
        wheel.bogie_type, int(wheel.axle), wheel.side, float(latest.mileage_km), latest.id,
        areas, covariates, parameters, notes)


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
        covariates = _covariates(inputs, route, body.covariates) or {}
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
        raise _statistics_error(exc) from exc


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
        raise _statistics_error(exc) from exc
    remaining = [result.mileage_p10_km, result.mileage_p50_km, result.mileage_p90_km]

    def opt(offset: float) -> dict[str, float | None]:
        p10, p50, p90 = (offset + v if math.isfinite(v) else None for v in remaining)
        return {"p10": p10, "p50": p50, "p90": p90}

    return {
        "model_id": model_id, "route": route.name, "wheel_id": body.wheel_id, **position,
        "start_mileage_km": start.mileage_km, "start_measurement_id": start.measurement_id,
        "start_areas_mm2": start.areas_mm2 or {"flange": 0.0, "tread": 0.0},
        "remaining_km": opt(0.0), "mileage_km": opt(start.mileage_km),
        "governing_limit": result.governing_limit, "sd_mm": _none_if_nan(result.sd_mm),
        "sh_mm": _none_if_nan(result.sh_mm), "qr_mm": _none_if_nan(result.qr_mm),
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
