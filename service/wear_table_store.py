"""Curve-radius wear tables in storage: upload (CSV) or compute (physics core), read back as
rows, as a compiled table, or (computed tables) as the raw per-contact quantities.

Validation is :func:`wearcast.statistics.wear_tables.validate_wear_table` (columns, enums,
finite values, a tangent row for every key...); its ``"field: reason"`` errors become 422s.
Computation is :func:`wearcast.physics.wear_tables.wear_table_for_route` (quasi-static
curving of both bogie types per curve class); a class whose curving equilibrium is not found
is a 422 naming its radius.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
from dataclasses import dataclass
from typing import Any

import pandas as pd
from sqlalchemy import insert, select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.cache import LruCache
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.service.wear_table_schemas import (
    VehiclePairIn,
    WearTableComputeIn,
    WearTableContactsOut,
    WearTableOut,
    WearTableRowOut,
)
from wearcast.statistics import wear_tables

MAX_TABLE_BYTES = 20 * 1024 * 1024
#: Compiled tables kept in process (each is a few hundred rows: well under 1 MB).
COMPILED_TABLE_CACHE_SIZE = 16


_compiled_tables: LruCache[wear_tables.WearTable] = LruCache(COMPILED_TABLE_CACHE_SIZE)


def parse_table_csv(data: bytes, file_name: str) -> pd.DataFrame:
    """The long table in a CSV upload, validated (422 naming the column and row)."""
    if not data.strip():
        raise Unprocessable("file", f"{file_name} is empty")
    if len(data) > MAX_TABLE_BYTES:
        raise Unprocessable("file", f"{file_name} is larger than {MAX_TABLE_BYTES} bytes")
    try:
        frame = pd.read_csv(io.BytesIO(data), dtype={"radius_m": str}, keep_default_na=False,
                            skipinitialspace=True)
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise Unprocessable("file", f"{file_name} is not a readable CSV: {exc}") from exc
    frame.columns = [str(c).strip() for c in frame.columns]
    try:
        return wear_tables.validate_wear_table(frame)
    except ValueError as exc:
        raise from_value_error(exc, "file") from exc


def create_wear_table(session: Session, frame: pd.DataFrame, *, name: str, source: str,
                      sha256: str, kind: str = "uploaded", spec: dict[str, Any] | None = None,
                      contacts: dict[str, Any] | None = None) -> db.WearTable:
    """Store a validated table and its rows in one transaction."""
    row = db.WearTable(name=name, source=source, sha256=sha256, n_rows=len(frame), kind=kind,
                       spec=spec, contacts=contacts)
    session.add(row)
    session.flush()
    records = []
    for r in frame.to_dict(orient="records"):
        radius = r["radius_m"]
        records.append({
            "wear_table_id": row.id, "bogie_type": r["bogie_type"], "wheelset": r["wheelset"],
            "rail": r["rail"], "region": r["region"], "measure": r["measure"],
            "radius_m": None if radius is None or math.isnan(radius) else float(radius),
            "value": float(r["value"]),
        })
    session.execute(insert(db.WearTableRow), records)
    session.commit()
    return row


def upload_wear_table(session: Session, data: bytes, file_name: str,
                      name: str | None = None) -> db.WearTable:
    frame = parse_table_csv(data, file_name)
    return create_wear_table(session, frame, name=name or file_name, source=file_name,
                             sha256=hashlib.sha256(data).hexdigest())


def get_wear_table(session: Session, table_id: int, field: str = "wear_table_id"
                   ) -> db.WearTable:
    row = session.get(db.WearTable, table_id)
    if row is None:
        raise NotFound(field, f"no wear table with id {table_id}")
    return row


def table_frame(session: Session, table_id: int) -> pd.DataFrame:
    """The stored rows as the long DataFrame of :mod:`wearcast.statistics.wear_tables`."""
    rows = session.execute(
        select(db.WearTableRow.bogie_type, db.WearTableRow.wheelset, db.WearTableRow.rail,
               db.WearTableRow.radius_m, db.WearTableRow.region, db.WearTableRow.measure,
               db.WearTableRow.value)
        .where(db.WearTableRow.wear_table_id == table_id).order_by(db.WearTableRow.id)
    ).all()
    frame = pd.DataFrame(rows, columns=list(wear_tables.TABLE_COLUMNS))
    frame["radius_m"] = pd.to_numeric(frame["radius_m"]).astype(float)
    return frame


def compiled_table(session: Session, table_id: int) -> wear_tables.WearTable:
    """The stored table, validated and compiled; cached in process by its content's SHA-256.

    Tables are immutable and ``sha256`` is the hash of the uploaded content, so a cached
    table can never be stale; the cache is shared by every table id with the same content.
    """
    row = get_wear_table(session, table_id)
    return compiled_table_for(session, row)


def compiled_table_for(session: Session, row: db.WearTable) -> wear_tables.WearTable:
    """:func:`compiled_table` for a table row already loaded."""
    return cached_compiled_table(session, row.id, row.sha256, row.n_rows)


def cached_compiled_table(session: Session, table_id: int, sha256: str, n_rows: int
                          ) -> wear_tables.WearTable:
    """The compiled table with this content hash; its rows are read only on a cache miss."""
    return _compiled_tables.get_or_create(
        (sha256, n_rows),
        lambda: wear_tables.compile_wear_table(table_frame(session, table_id)))


def wear_table_out(session: Session, row: db.WearTable, with_rows: bool = True) -> WearTableOut:
    rows = None
    if with_rows:
        rows = [WearTableRowOut.model_validate(r)
                for r in wear_tables.wear_table_to_records(table_frame(session, row.id))]
    return WearTableOut(id=row.id, name=row.name, source=row.source, sha256=row.sha256,
                        n_rows=row.n_rows, kind=row.kind or "uploaded", spec=row.spec,
                        rows=rows)


# --- computed tables --------------------------------------------------------------------------

def canonical_csv(frame: pd.DataFrame) -> bytes:
    """The table as CSV bytes in a fixed form (the columns of docs/conventions.md, shortest
    round-trip
    float repr, ``\\n`` line ends): its SHA-256 is the content key of a computed table."""
    out = frame.loc[:, list(wear_tables.TABLE_COLUMNS)]
    return out.to_csv(index=False, lineterminator="\n").encode()


@dataclass(frozen=True)
class _Classes:
    radii_m: list[float | None]
    cant_mm: list[float]
    speed_kmh: list[float | None]
    shares: list[float] | None
    fields: list[str]  # the request field naming each class (for errors)
    route_name: str | None


def _presets(spec: str | VehiclePairIn, friction: float | None) -> tuple[Any, Any, str]:
    """(motor, trailer) bogie vehicles of the request; 422 naming ``vehicle`` when unknown."""
    from wearcast.physics.vehicles import preset_names, vehicle_preset

    known = preset_names()
    if isinstance(spec, str):
        pairs = [(spec, "vehicle"), (spec, "vehicle")]
        label = spec
    else:
        pairs = [(spec.motor, "vehicle.motor"), (spec.trailer, "vehicle.trailer")]
        label = f"motor {spec.motor}, trailer {spec.trailer}"
    for name, field in pairs:
        if name not in known:
            raise Unprocessable(field, f"unknown vehicle preset {name!r}; known presets: "
                                f"{', '.join(known)}")
    motor = vehicle_preset(pairs[0][0], "motor")
    trailer = vehicle_preset(pairs[1][0], "trailer")
    if friction is not None:
        motor, trailer = motor.with_(friction=friction), trailer.with_(friction=friction)
    return motor, trailer, label


def _classes(session: Session, body: WearTableComputeIn) -> _Classes:
    """The curve classes to solve, from the stored route or the given radii, with a tangent
    class (share 0) added when none is given (every table needs its tangent rows)."""
    if body.route_id is not None:
        from wearcast.service import route_store

        route = route_store.get_route(session, body.route_id, "route_id")
        items = [dict(c) for c in route.classes]
        fields = [f"route_id (route {route.name!r} classes[{i}])" for i in range(len(items))]
        route_name: str | None = route.name
    else:
        items = [r.model_dump() for r in body.radii or []]
        fields = [f"radii[{i}].radius_m" for i in range(len(items))]
        route_name = None
    radii = [None if c.get("radius_m") is None else float(c["radius_m"]) for c in items]
    cants = [float(c.get("cant_mm") or 0.0) for c in items]
    speeds = [None if c.get("speed_kmh") is None else float(c["speed_kmh"]) for c in items]
    raw_shares = [c.get("share") for c in items]
    given_shares = [v for v in raw_shares if v is not None]
    shares = ([float(v) for v in given_shares] if len(given_shares) == len(raw_shares)
              else None)
    if all(r is not None for r in radii):
        radii.append(None)
        cants.append(0.0)
        speeds.append(None)
        if shares is not None:
            shares.append(0.0)
        fields.append("tangent class (added)")
    return _Classes(radii, cants, speeds, shares, fields, route_name)


def _convergence_field(classes: _Classes, radius_m: float) -> str:
    target = None if not math.isfinite(radius_m) else abs(radius_m)
    for r, field in zip(classes.radii_m, classes.fields, strict=True):
        if (r is None and target is None) or (r is not None and target is not None
                                             and math.isclose(r, target, rel_tol=1e-9)):
            return field if field.startswith("radii") else "route_id"
    return "radii" if classes.route_name is None else "route_id"


def check_compute_request(session: Session, body: WearTableComputeIn) -> None:
    """The checks of :func:`compute_table_frames` that need no physics, for a request queued
    as a job (``wear_table_jobs``): the vehicle preset, a measured rail and wheel, the route
    or radii (4xx naming the field)."""
    from wearcast.service import rail_store
    from wearcast.service.measured_wheel_source import requested_wheel

    _presets(body.vehicle, body.friction)
    rail_store.requested_rails(session, body)
    requested_wheel(session, body)
    _classes(session, body)


def compute_table_frames(session: Session, body: WearTableComputeIn
                         ) -> tuple[pd.DataFrame, pd.DataFrame, dict[str, Any]]:
    """Run the physics core for a compute request: (validated table, raw contacts, spec).

    Reads the route (when named) and runs the curving solver (about a second for a few
    dozen classes); writes nothing.
    """
    from wearcast.physics.curving import CurvingConvergenceError
    from wearcast.physics.wear_tables import wear_table_for_route

    motor, trailer, label = _presets(body.vehicle, body.friction)
    rail_info = None
    from wearcast.service import rail_store

    rails = rail_store.requested_rails(session, body)  # measured rails for the nominal one
    if any(r is not None for r in rails):
        motor, trailer = (rail_store.with_rails(v, *rails) for v in (motor, trailer))
        rail_info = {"inclination": motor.rail_inclination,
                     "placement": "gauge point (14 mm below its top) at the track gauge"}
        for field, role, rail in zip(rail_store.RAIL_FIELDS, ("", "high ", "low "), rails,
                                     strict=True):
            if rail is None:
                continue
            label = f"{label}, {role}{rail}"
            entry = {"rail_id": getattr(body, field), "name": rail.name, "kind": rail.kind}
            if field == "rail_id":
                rail_info.update(entry)
            else:
                rail_info[field.removesuffix("_id")] = entry
    wheel_info = None
    from wearcast.service.measured_wheel_source import requested_wheel

    measured = requested_wheel(session, body)  # a measured wheel in place of S1002
    if measured is not None:
        wheel, wheel_info = measured
        motor = motor.with_(wheel_profile=wheel)
        trailer = trailer.with_(wheel_profile=wheel)
        label = f"{label}, {wheel}"
    classes = _classes(session, body)
    try:
        table, contacts = wear_table_for_route(
            (motor, trailer), classes.radii_m, classes.cant_mm, classes.speed_kmh,
            classes.shares, unbalanced_acceleration_m_s2=body.unbalanced_acceleration_m_s2,
            tangent_speed_kmh=body.tangent_speed_kmh, max_speed_kmh=body.max_speed_kmh,
            with_contacts=True, contact_model=body.contact_model)
    except CurvingConvergenceError as exc:
        radius = exc.radius_m
        where = "tangent track" if not math.isfinite(radius) else f"radius {abs(radius):g} m"
        raise Unprocessable(
            _convergence_field(classes, radius),
            f"the quasi-static curving solver found no equilibrium at {where} for {label} "
            f"(residual norm {exc.residual_norm:.3g}); check the radius, cant and speed "
            "of this class" + ("" if wheel_info is None else ", and whether the measured "
                               "wheel fits this track (flange thickness, datum placement)")
        ) from exc
    except ValueError as exc:
        raise from_value_error(exc, "radii" if body.radii is not None else "route_id") from exc
    try:
        frame = wear_tables.validate_wear_table(table)
    except ValueError as exc:  # the physics produced an unusable table: say which row
        raise from_value_error(exc, "table") from exc
    spec = body.model_dump(mode="json")
    spec.update(route_name=classes.route_name, vehicle_label=label,
                n_classes=len(classes.radii_m), rail=rail_info, wheel=wheel_info,
                engine="wearcast.physics.wear_tables.wear_table_for_route")
    return frame, contacts, spec


def compute_wear_table(session: Session, body: WearTableComputeIn) -> db.WearTable:
    """Compute a table with the physics core and store it like an uploaded one (rows and the
    SHA-256 of its canonical CSV) plus the raw per-contact quantities."""
    frame, contacts, spec = compute_table_frames(session, body)
    data = canonical_csv(frame)
    raw = json.loads(contacts.to_json(orient="split", index=False, double_precision=15))
    where = f"route {spec['route_name']}" if spec["route_name"] else \
        f"{len(body.radii or [])} radii"
    return create_wear_table(session, frame, name=body.name,
                             source=f"computed: {spec['vehicle_label']}, {where}",
                             sha256=hashlib.sha256(data).hexdigest(), kind="computed",
                             spec=spec, contacts={"columns": raw["columns"],
                                                  "data": raw["data"]})


def wear_table_contacts(session: Session, table_id: int) -> WearTableContactsOut:
    """The raw per-contact quantities of a computed table (404 for an uploaded one)."""
    row = get_wear_table(session, table_id, "table_id")
    contacts = session.scalar(select(db.WearTable.contacts).where(db.WearTable.id == table_id))
    if not contacts:
        raise NotFound("table_id", f"wear table {table_id} was {row.kind or 'uploaded'}, not "
                       "computed: it has no raw contact quantities")
    columns = list(contacts["columns"])
    records = [dict(zip(columns, values, strict=True)) for values in contacts["data"]]
    return WearTableContactsOut(wear_table_id=table_id, n_contacts=len(records),
                                columns=columns, contacts=records)
