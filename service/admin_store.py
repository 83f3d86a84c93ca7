"""Operator corrections with the history kept: delete or supersede an import batch, a
measurement, a route, a wear table or a model.

The row (and, for a batch, its measurements' ids and its raw files, which stay on disk) is
written into the audit trail as a snapshot before it is removed, in the same transaction, so
nothing disappears without a record of what it was, who removed it and why. A row something
else depends on is refused with 409 naming the dependants (remove or supersede those first):
a measurement or batch a model was calibrated on, a route or table a model uses.
"""

from __future__ import annotations

import base64
import datetime as dt
from typing import Any, Literal

from sqlalchemy import delete, inspect, select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.batch_visibility import COMPLETE
from wearcast.service.errors import Conflict, NotFound

Kind = Literal["batches", "measurements", "routes", "wear-tables", "models"]
_TABLES: dict[str, Any] = {"batches": db.ImportBatch, "measurements": db.Measurement,
                           "routes": db.Route, "wear-tables": db.WearTable,
                           "models": db.Model}


def _plain(value: Any) -> Any:
    if isinstance(value, bytes):
        return {"base64_f32le": base64.b64encode(value).decode()}
    if isinstance(value, dt.date | dt.datetime):
        return value.isoformat()
    return value


def snapshot(row: Any) -> dict[str, Any]:
    """Every column of a row as JSON (binary points as base64 little-endian float32)."""
    mapper = inspect(type(row))
    return {c.key: _plain(getattr(row, c.key)) for c in mapper.column_attrs}


def _row(session: Session, kind: str, entity_id: int) -> Any:
    row = session.get(_TABLES[kind], entity_id)
    if row is None:
        raise NotFound("id", f"no {kind[:-1].replace('-', ' ')} with id {entity_id}")
    return row


def _models_using(session: Session, kind: str, entity_id: int) -> list[int]:
    if kind == "measurements":
        query = select(db.ModelCalibrationMeasurement.model_id).where(
            db.ModelCalibrationMeasurement.measurement_id == entity_id)
    elif kind == "batches":
        query = (select(db.ModelCalibrationMeasurement.model_id)
                 .join(db.Measurement,
                       db.Measurement.id == db.ModelCalibrationMeasurement.measurement_id)
                 .where(db.Measurement.batch_id == entity_id))
    elif kind == "routes":
        query = select(db.Model.id).where(db.Model.route_id == entity_id)
    elif kind == "wear-tables":
        query = select(db.Model.id).where(db.Model.wear_table_id == entity_id)
    else:
        return []
    return sorted(set(session.scalars(query)))


def remove(session: Session, kind: str, entity_id: int) -> dict[str, Any]:
    """Delete a row of ``kind`` (not committed) and return its snapshot; 404 when absent,
    409 when a model depends on it."""
    row = _row(session, kind, entity_id)
    if kind == "batches" and row.status != COMPLETE:
        raise Conflict("id", f"batch {entity_id} is being imported now; delete it when its "
                       "import has finished")
    users = _models_using(session, kind, entity_id)
    if users:
        raise Conflict("id", f"model(s) {', '.join(map(str, users))} depend on this "
                       f"{kind[:-1].replace('-', ' ')}; delete or supersede them first")
    shot = snapshot(row)
    if kind == "batches":
        shot["measurement_ids"] = list(session.scalars(
            select(db.Measurement.id).where(db.Measurement.batch_id == entity_id)))
        shot["raw_files"] = [snapshot(r) for r in session.scalars(
            select(db.RawFile).where(db.RawFile.batch_id == entity_id))]
        session.execute(delete(db.Measurement).where(db.Measurement.batch_id == entity_id))
        session.execute(delete(db.RawFile).where(db.RawFile.batch_id == entity_id))
    elif kind == "models":
        session.execute(delete(db.ModelCalibrationMeasurement)
                        .where(db.ModelCalibrationMeasurement.model_id == entity_id))
    elif kind == "wear-tables":
        session.execute(delete(db.WearTableRow).where(db.WearTableRow.wear_table_id == entity_id))
    session.delete(row)
    session.flush()
    return shot


def check_replacement(session: Session, kind: str, entity_id: int, by: int) -> None:
    if by == entity_id:
        raise Conflict("by", "a row cannot supersede itself")
    if session.get(_TABLES[kind], by) is None:
        raise NotFound("by", f"no {kind[:-1].replace('-', ' ')} with id {by} to supersede "
                       "it with")


def clear_caches() -> None:
    """Forget cached models, routes and tables (ids of removed rows may be given again)."""
    from wearcast.service import (
        model_loading,
        model_store,
        physics_model_store,
        prediction_store,
    )

    for module in (model_loading, model_store, prediction_store, physics_model_store):
        for value in vars(module).values():
            clear = getattr(value, "clear", None)
            if clear is not None and type(value).__name__ == "LruCache":
                clear()
