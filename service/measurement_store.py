"""Measurements in storage: one posted as JSON, listing with filters, reading back points.

A ``filter`` maps metadata field names to one accepted value or a list of them (docs/conventions.md
"Service"): the standard fields (``wheel_id, vehicle_id, bogie_type, axle, side, mileage_km,
measured_on, route_id, running_mode, instrument_id, load_t, reference_profile, kind,
batch_id, id``) are matched in SQL; any other name is a covariate, matched in Python (numbers
numerically, text exactly) so the same rules hold on SQLite and PostgreSQL. ``route_id``
accepts a route's id or its name.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import Select, func, or_, select
from sqlalchemy.orm import Session, defer

from wearcast.service import models_db as db
from wearcast.service import route_store
from wearcast.service.errors import Conflict, NotFound, Unprocessable
from wearcast.service.float32_blobs import from_f32
from wearcast.service.import_staging import store_records
from wearcast.service.measurement_schemas import MeasurementIn, MeasurementOut
from wearcast.service.readers.records import MeasurementMeta, ParameterRecord, ProfileRecord


def _as_int(value: Any) -> int:
    if isinstance(value, bool):
        raise ValueError("not an integer")
    number = float(value)
    if not number.is_integer():
        raise ValueError("not an integer")
    return int(number)


def _as_float(value: Any) -> float:
    number = float(value)
    if not math.isfinite(number):
        raise ValueError("not finite")
    return number


def _as_date(value: Any) -> dt.date:
    return value if isinstance(value, dt.date) else dt.date.fromisoformat(str(value))


def _as_text(value: Any) -> str:
    return str(value)


def _as_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in ("true", "1", "yes"):
        return True
    if text in ("false", "0", "no"):
        return False
    raise ValueError("not a boolean")


M, W = db.Measurement, db.Wheel
STANDARD_FIELDS: dict[str, tuple[Any, Callable[[Any], Any]]] = {
    "id": (M.id, _as_int),
    "batch_id": (M.batch_id, _as_int),
    "wheel_id": (M.wheel_id, _as_text),
    "vehicle_id": (W.vehicle_id, _as_text),
    "bogie_type": (W.bogie_type, _as_text),
    "axle": (W.axle, _as_int),
    "side": (W.side, _as_text),
    "mileage_km": (M.mileage_km, _as_float),
    "measured_on": (M.measured_on, _as_date),
    "running_mode": (M.running_mode, _as_text),
    "instrument_id": (M.instrument_id, _as_text),
    "load_t": (M.load_t, _as_float),
    "diameter_mm": (M.diameter_mm, _as_float),
    "reference_profile": (M.reference_profile, _as_text),
    "kind": (M.kind, _as_text),
    "source_file": (M.source_file, _as_text),
    "reference_fits": (M.reference_fits, _as_bool),
}
RANGE_FIELDS = {"mileage_km_min": (M.mileage_km, ">="), "mileage_km_max": (M.mileage_km, "<="),
                "measured_on_from": (M.measured_on, ">="), "measured_on_to": (M.measured_on, "<=")}


def _values(value: Any) -> list[Any]:
    return list(value) if isinstance(value, list | tuple) else [value]


def _covariate_match(stored: Any, wanted: Iterable[Any]) -> bool:
    for value in wanted:
        if value is None:
            if stored is None:
                return True
            continue
        if stored is None:
            continue
        if str(stored) == str(value):
            return True
        try:
            if float(stored) == float(value):
                return True
        except (TypeError, ValueError):
            pass
    return False


def filtered_query(session: Session, filter_: dict[str, Any], field: str = "filter"
                   ) -> tuple[Select[Any], dict[str, list[Any]]]:
    """SQL for the standard fields of ``filter_`` and the covariate conditions left over."""
    query = select(M.id).join(W, W.wheel_id == M.wheel_id)
    covariates: dict[str, list[Any]] = {}
    for name, raw in filter_.items():
        values = _values(raw)
        if name in RANGE_FIELDS:
            column, op = RANGE_FIELDS[name]
            convert: Callable[[Any], Any] = (_as_date if name.startswith("measured_on")
                                             else _as_float)
            try:
                bound = convert(values[0])
            except (TypeError, ValueError) as exc:
                raise Unprocessable(f"{field}.{name}", f"{values[0]!r} is not valid") from exc
            query = query.where(column >= bound if op == ">=" else column <= bound)
        elif name == "route_id":
            accepted: set[str] = set()
            for value in values:
                accepted.add(str(value))
                row = route_store.find_route(session, value)
                if row is not None:
                    accepted |= {row.name, str(row.id)}
            query = query.where(M.route_id.in_(sorted(accepted)))
        elif name in STANDARD_FIELDS:
            column, convert = STANDARD_FIELDS[name]
            try:
                converted = [None if v is None else convert(v) for v in values]
            except (TypeError, ValueError) as exc:
                raise Unprocessable(f"{field}.{name}",
                                    f"{values!r} does not fit the field's type") from exc
            plain = [v for v in converted if v is not None]
            conditions = [column.in_(plain)] if plain else []
            if None in converted:
                conditions.append(column.is_(None))
            query = query.where(or_(*conditions))
        else:
            covariates[name] = values
    return query, covariates


def matching_ids(session: Session, filter_: dict[str, Any], field: str = "filter") -> list[int]:
    """Ids of the measurements matching ``filter_``, ascending."""
    query, covariates = filtered_query(session, filter_, field)
    if not covariates:
        return list(session.scalars(query.order_by(M.id)))
    rows = session.execute(query.add_columns(M.covariates).order_by(M.id))
    return [mid for mid, cov in rows
            if all(_covariate_match((cov or {}).get(k), v) for k, v in covariates.items())]


def page(session: Session, filter_: dict[str, Any], limit: int, offset: int,
         include_points: bool = False) -> tuple[int, list[MeasurementOut]]:
    """One page of matching measurements and the total count."""
    query, covariates = filtered_query(session, filter_)
    if not covariates:
        total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
        ids = list(session.scalars(query.order_by(M.id).limit(limit).offset(offset)))
    else:
        every = matching_ids(session, filter_)
        total, ids = len(every), every[offset:offset + limit]
    return total, load(session, ids, include_points)


def load(session: Session, ids: list[int], include_points: bool = False
         ) -> list[MeasurementOut]:
    if not ids:
        return []
    query = select(M, W).join(W, W.wheel_id == M.wheel_id).where(M.id.in_(ids)).order_by(M.id)
    if not include_points:  # a page without points reads none of the point blobs
        query = query.options(defer(M.y_mm), defer(M.z_mm), defer(M.wear_mm))
    rows = session.execute(query).all()
    return [to_out(m, w, include_points) for m, w in rows]


#: Fields of an answer read from the measurement row (the points are added separately).
_ROW_FIELDS = tuple(c for c in MeasurementOut.model_fields
                    if hasattr(db.Measurement, c) and c not in {"y_mm", "z_mm"})


def to_out(m: db.Measurement, w: db.Wheel, include_points: bool = False) -> MeasurementOut:
    data = {c: getattr(m, c) for c in _ROW_FIELDS}
    data.update(vehicle_id=w.vehicle_id, bogie_type=w.bogie_type, axle=w.axle, side=w.side,
                covariates=m.covariates or {})
    if include_points:
        y_points, z_points = from_f32(m.y_mm), from_f32(m.z_mm)
        if y_points is not None and z_points is not None:
            data["y_mm"] = [round(v, 4) for v in y_points.tolist()]
            data["z_mm"] = [round(v, 4) for v in z_points.tolist()]
    return MeasurementOut.model_validate(data)


def get(session: Session, measurement_id: int) -> MeasurementOut:
    row = session.execute(select(M, W).join(W, W.wheel_id == M.wheel_id)
                          .where(M.id == measurement_id)).first()
    if row is None:
        raise NotFound("measurement_id", f"no measurement with id {measurement_id}")
    return to_out(row[0], row[1], include_points=True)


def create(session: Session, body: MeasurementIn) -> MeasurementOut:
    """Store one measurement posted as JSON (processed like an imported one)."""
    meta = MeasurementMeta(
        wheel_id=body.wheel_id, vehicle_id=body.vehicle_id, bogie_type=body.bogie_type,
        axle=body.axle, side=body.side, mileage_km=body.mileage_km,
        measured_on=body.measured_on,
        route_id=None if body.route_id is None else str(body.route_id),
        running_mode=body.running_mode, instrument_id=body.instrument_id, load_t=body.load_t,
        reference_profile=body.reference_profile,
        covariates={k: v for k, v in body.covariates.items() if v is not None},
        source_file="api", source_line=None, diameter_mm=body.diameter_mm)
    record: ProfileRecord | ParameterRecord
    if body.y_mm is not None and body.z_mm is not None:
        reported = body.instrument_parameters.model_dump(exclude_none=True) \
            if body.instrument_parameters else None
        record = ProfileRecord(meta, np.asarray(body.y_mm, float), np.asarray(body.z_mm, float),
                               reported or None)
    else:
        record = ParameterRecord(meta, float(body.sd_mm or 0), float(body.sh_mm or 0),
                                 float(body.qr_mm or 0))
    from wearcast.service.readers.errors import ImportFileError

    try:
        counts, ids = store_records(session, [record], None)
    except ImportFileError as exc:
        session.rollback()
        field = "y_mm" if exc.field == "z_mm" else (exc.field or "body")
        raise Unprocessable(field, exc.reason) from exc
    if counts.duplicates:
        session.rollback()
        raise Conflict("mileage_km", f"wheel {body.wheel_id!r} already has a measurement at "
                       f"{body.mileage_km:g} km")
    session.commit()
    return get(session, ids[0])


def calibration_frame(session: Session, ids: list[int]) -> tuple[pd.DataFrame, np.ndarray]:
    """Measurements (metadata, areas, parameters) and their wear curves [n, grid] by id."""
    frames = []
    curves = []
    for start in range(0, len(ids), 900):
        chunk = ids[start:start + 900]
        rows = session.execute(
            select(M.id, M.wheel_id, W.vehicle_id, W.bogie_type, W.axle, W.side, M.mileage_km,
                   M.measured_on, M.route_id, M.running_mode, M.instrument_id, M.load_t,
                   M.kind, M.flange_area_mm2, M.tread_area_mm2, M.sd_mm, M.sh_mm, M.qr_mm,
                   M.wear_mm).join(W, W.wheel_id == M.wheel_id).where(M.id.in_(chunk))
            .order_by(M.id)).all()
        for row in rows:
            curves.append(from_f32(row[-1] if isinstance(row[-1], bytes) else None))
        frames.append(pd.DataFrame([r[:-1] for r in rows], columns=[
            "measurement_id", "wheel_id", "vehicle_id", "bogie_type", "axle", "side",
            "mileage_km", "measured_on", "route_id", "running_mode", "instrument_id", "load_t",
            "kind", "flange_area_mm2", "tread_area_mm2", "sd_mm", "sh_mm", "qr_mm"]))
    frame = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    return frame, curves  # type: ignore[return-value]
