"""What an import knows of the stored wheels, vehicles, routes and references, per upload.

While the records of an upload are read, each wheel's position (vehicle, bogie type, axle,
side) is checked against the stored one and against the upload's earlier records (a
contradiction is an :class:`~wearcast.service.readers.errors.ImportFileError` naming file,
line and field); new wheels and vehicles are inserted at once or, for a staged import
(``defer_writes``), kept for :func:`wearcast.service.import_staging.write_new_wheels`. Route
ids are resolved to route names, and each declared reference profile is resolved once
(:mod:`wearcast.service.reference_store`).
"""

from __future__ import annotations

from typing import Any

from sqlalchemy import insert, select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.batch_visibility import INCLUDE_PENDING
from wearcast.service.errors import Unprocessable
from wearcast.service.readers.bundle import Record
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.records import ProfileRecord
from wearcast.service.reference_store import ReferenceSpec, is_own_baseline, resolve_reference

_ALL = {INCLUDE_PENDING: True}


class ImportRegistry:
    """Per-import caches of wheels, vehicles and route names, checked for consistency."""

    def __init__(self, session: Session, defer_writes: bool = False,
                 batch_id: int | None = None) -> None:
        self.session = session
        #: the batch new wheels and vehicles are registered by (hidden while it is pending)
        self.batch_id = batch_id
        self.wheels: dict[str, tuple[str, str, int, str]] = {}
        self.vehicles: set[str] = set()
        self.routes: dict[str, str] = {}
        self.references: dict[str, ReferenceSpec] = {}
        self.own_wheels: set[str] = set()
        #: with ``defer_writes`` new wheels are kept here and inserted by ``write_new``
        self.defer_writes = defer_writes
        self.new_wheels: dict[str, dict[str, Any]] = {}
        for route_id, name in session.execute(select(db.Route.id, db.Route.name)):
            self.routes[str(route_id)] = name
            self.routes[name] = name

    def reference(self, record: ProfileRecord) -> ReferenceSpec:
        """The record's declared reference, resolved once per name; the own baseline is
        processed against S1002 first and re-referenced after the batch is stored."""
        name = record.meta.reference_profile
        if is_own_baseline(name):
            name = "S1002"
        spec = self.references.get(name)
        if spec is None:
            try:
                spec = resolve_reference(self.session, name)
            except Unprocessable as exc:
                meta = record.meta
                raise ImportFileError(meta.source_file, exc.reason,
                                      line=record.manifest_line or meta.source_line,
                                      field="reference_profile") from None
            self.references[name] = spec
        return spec

    def route_name(self, ref: str | None) -> str | None:
        return None if ref is None else self.routes.get(str(ref), str(ref))

    def ensure_wheels(self, records: list[Record]) -> None:
        wanted = {r.meta.wheel_id for r in records} - self.wheels.keys()
        if wanted:
            for row in self.session.execute(
                select(db.Wheel.wheel_id, db.Wheel.vehicle_id, db.Wheel.bogie_type,
                       db.Wheel.axle, db.Wheel.side).where(db.Wheel.wheel_id.in_(wanted))
                .execution_options(**_ALL)  # a pending import's new wheels are stored too
            ):
                self.wheels[row[0]] = (row[1], row[2], row[3], row[4])
                self.vehicles.add(row[1])
        new_wheels: dict[str, dict[str, Any]] = {}
        for record in records:
            meta = record.meta
            position = (meta.vehicle_id, meta.bogie_type, int(meta.axle), meta.side)
            known = self.wheels.get(meta.wheel_id)
            if known is None:
                self.wheels[meta.wheel_id] = position
                new_wheels[meta.wheel_id] = {
                    "wheel_id": meta.wheel_id, "vehicle_id": meta.vehicle_id,
                    "bogie_type": meta.bogie_type, "axle": int(meta.axle), "side": meta.side,
                    "registered_batch_id": self.batch_id}
                continue
            for name, have, got in zip(("vehicle_id", "bogie_type", "axle", "side"), known,
                                       position, strict=True):
                if have != got:
                    raise ImportFileError(
                        meta.source_file, f"wheel {meta.wheel_id!r} is stored with {name} "
                        f"{have!r}, this measurement says {got!r}",
                        line=meta.source_line, field=name)
        if not new_wheels:
            return
        if self.defer_writes:
            self.new_wheels.update(new_wheels)
            return
        vehicles = {w["vehicle_id"] for w in new_wheels.values()} - self.vehicles
        if vehicles:
            stored = set(self.session.scalars(
                select(db.Vehicle.vehicle_id).where(db.Vehicle.vehicle_id.in_(vehicles))
                .execution_options(**_ALL)))
            fresh = sorted(vehicles - stored)
            if fresh:
                self.session.execute(insert(db.Vehicle), [
                    {"vehicle_id": v, "registered_batch_id": self.batch_id} for v in fresh])
            self.vehicles |= vehicles
        self.session.execute(insert(db.Wheel), list(new_wheels.values()))
