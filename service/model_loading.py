"""A stored hybrid model loaded for use: the deserialised model, its compiled wear table, the
weighted wear measures P_s (seed 001 eq. 2) and the route a request names, cached in process.

A stored model's state carries its kind: a plain hybrid model (``HybridModel.to_dict()``, no
``kind`` key) or a model extended by the discrepancy finder (``{"kind": "extended", ...}``,
:class:`wearcast.statistics.extension.ExtendedModel`); :func:`wheel_model` turns an
extended model into the plain hybrid model of the wheel asked about (``ExtendedModel.for_wheel``,
from the route's attributes and the request's ``covariates``).

Hot path (``POST /v1/models/{id}/predict`` and ``/reprofiling``): models and routes are
never updated or deleted once created (no endpoint or store function does either), so after a
first request has read them, :func:`cached_inputs` finds the deserialised model, its compiled
table and the stored route in process under (database URL, model id) and (database URL,
route id or name) without touching the database.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeAlias

from sqlalchemy import bindparam, select
from sqlalchemy.orm import Session, defer

from wearcast.service import models_db as db
from wearcast.service import route_store, wear_table_store
from wearcast.service.cache import LruCache
from wearcast.service.errors import ApiError, NotFound, Unprocessable, from_value_error
from wearcast.service.id_text import decimal_id
from wearcast.statistics import hybrid, hybrid_prediction
from wearcast.statistics.extension import ExtendedModel
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import RadiusOutOfTableError, WearTable

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


def statistics_error(exc: ValueError, route_field: str = "route") -> ApiError:
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
    return dict(_measures.get_or_create(key, lambda: hybrid_prediction.model_weighted_measures(
        model, route, inputs.table, bogie_type=bogie_type, axle=axle, side=side)))


def wheel_model(model: AnyModel, route: Route, table: WearTable, *, bogie_type: str,
                axle: int, side: str, covariates: dict[str, Any] | None = None
                ) -> hybrid.HybridModel:
    """The plain hybrid model for one wheel: the model itself, or an extended model's
    ``for_wheel`` (its rate factors from the wheel's position and covariates)."""
    if not isinstance(model, ExtendedModel):
        return model
    return model.for_wheel(route, table, bogie_type=bogie_type, axle=axle, side=side,
                           covariates=covariates)


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

    ``route`` is an inline :class:`~wearcast.service.route_schemas.RouteSpec` (when ``route_id`` is
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
    if isinstance(route_id, int) or decimal_id(route_id) in (None, row.id):
        _hot_routes.put((url, *_route_ref(route_id)), stored)
    return inputs, stored


def request_covariates(inputs: ModelInputs, route: RouteInputs,
                       given: dict[str, Any] | None) -> dict[str, Any] | None:
    """The covariates an extended model reads: the route's attributes overlaid with the
    request's (None for a plain model, which reads none)."""
    if not isinstance(inputs.model, ExtendedModel):
        return None
    return {**route.attributes, **(given or {})}
