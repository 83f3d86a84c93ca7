"""Hybrid models in storage: calibrate (seed 001 eq. 3) and read.

The modelling is :mod:`wearcast.statistics.hybrid`; this module selects the calibration
measurements, calls it, stores the model's state and answers ``GET /v1/models/{id}``.
Loading a stored model for use is :mod:`wearcast.service.model_loading`; predictions are
:mod:`wearcast.service.prediction_store`, remaining mileage to reprofiling
:mod:`wearcast.service.reprofiling_store`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sqlalchemy import bindparam, func, insert, select
from sqlalchemy.orm import Session

from wearcast.physics.vocabulary import REGIONS
from wearcast.service import (
    measurement_store,
    route_store,
    wear_table_store,
)
from wearcast.service import models_db as db
from wearcast.service.cache import LruCache
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.model_loading import get_model_row, statistics_error
from wearcast.service.model_schemas import ModelIn, ModelOut
from wearcast.statistics import hybrid
from wearcast.statistics.json_values import json_value


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
        raise statistics_error(exc, "calibration.route_id") from exc
    row = db.Model(name=body.name, measure=body.measure, running_mode=body.running_mode,
                   wear_table_id=body.wear_table_id, route_id=route_row.id,
                   spec=body.model_dump(mode="json"),
                   state=json_value(model.to_dict(), infinity_as_text=True))
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

