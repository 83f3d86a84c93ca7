"""The records of an import, chunk by chunk: checked, processed, turned into rows, inserted.

A chunk of records is checked for duplicates (a (wheel_id, mileage_km) already stored or met
earlier in the upload is skipped and counted), its new wheels are registered
(:mod:`wearcast.service.import_registry`) and its profiles are processed (in worker processes
when large, :mod:`wearcast.service.import_pool`) while the next chunk is read; then its
``measurements`` rows are built (:mod:`wearcast.service.measurement_rows`,
:func:`chunk_rows`).

Imports of an upload are staged outside the write lock: reading and processing an upload
(profile cleaning, alignment, wear curves) is the slow part of an import; while it ran inside
the batch's transaction, SQLite's single write lock was held for all of it and every other
write waited. Here the rows are built first, with reads only, and spooled to an anonymous
temporary file (unlinked at once: nothing is left behind by a kill), so memory stays flat
however large the upload (:func:`stage_records`); then the batch, its raw-file rows, new
vehicles and wheels (upserts: concurrent imports sharing them both succeed) and the
measurements (a row another import stored meanwhile is skipped as a duplicate) are inserted
in one transaction — the batch stays atomic and the lock is held only for the inserts
(:func:`write_stage`). Single posts are inserted directly in the session's open transaction
(:func:`store_records`).
"""

from __future__ import annotations

import pickle
import tempfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from itertools import islice
from pathlib import Path
from typing import IO, Any

from sqlalchemy import func, insert, select, tuple_
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.import_pool import submit_profiles
from wearcast.service.import_registry import ImportRegistry
from wearcast.service.import_result import ImportCounts, collect_warnings
from wearcast.service.import_worker import Processed
from wearcast.service.measurement_rows import measurement_row
from wearcast.service.readers.bundle import Record
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.records import ProfileRecord
from wearcast.service.reference_store import OWN_BASELINE
from wearcast.service.wheel_reference import apply_reference

Progress = Callable[[int], None]

#: Records per chunk (one duplicate query, one processing batch and one bulk insert each).
DEFAULT_CHUNK = 500


def chunk_rows(session: Session, records: Iterable[Record], registry: ImportRegistry,
               counts: ImportCounts, seen: set[tuple[str, float]], *, batch_id: int | None,
               chunk_size: int, check: Callable[[list[Record]], None] | None = None
               ) -> Iterator[tuple[list[dict[str, Any]], int]]:
    """The ``measurements`` rows of the records' new measurements, chunk by chunk, each with
    the number of records its chunk read (for progress); a chunk of duplicates only gives [].

    Records already stored or in ``seen`` (the keys of earlier records, updated here) count as
    duplicates; ``check`` may refuse a chunk (ImportFileError). A chunk's profiles are
    processed (in worker processes when large) while the next chunk is read and checked; its
    rows are built after that. Counts, warnings and own-baseline wheels go to ``counts`` and
    ``registry``.
    """
    iterator = iter(records)

    def rows_of(fresh: list[Record], processed: Callable[[], list[Processed]]
                ) -> list[dict[str, Any]]:
        if not fresh:
            return []
        profiles = [r for r in fresh if isinstance(r, ProfileRecord)]
        done = dict(zip(map(id, profiles), processed(), strict=True))
        rows = [measurement_row(r, batch_id, registry, done.get(id(r))) for r in fresh]
        collect_warnings(counts, registry, fresh, rows)
        counts.points += sum(r["n_points"] for r in rows)
        return rows

    pending: tuple[list[Record], Callable[[], list[Processed]], int] | None = None
    while chunk := list(islice(iterator, chunk_size)):
        counts.records += len(chunk)
        if check is not None:
            check(chunk)
        keys = [(r.meta.wheel_id, float(r.meta.mileage_km)) for r in chunk]
        stored = {tuple(row) for row in session.execute(
            select(db.Measurement.wheel_id, db.Measurement.mileage_km).where(
                tuple_(db.Measurement.wheel_id, db.Measurement.mileage_km).in_(set(keys)))
        ).all()}
        fresh: list[Record] = []
        for record, key in zip(chunk, keys, strict=True):
            if key in stored or key in seen:
                counts.duplicates += 1
                continue
            seen.add(key)
            fresh.append(record)
        if fresh:
            registry.ensure_wheels(fresh)
        handle = submit_profiles([r for r in fresh if isinstance(r, ProfileRecord)], registry)
        if pending is not None:
            yield rows_of(pending[0], pending[1]), pending[2]
        pending = (fresh, handle, len(chunk))
    if pending is not None:
        yield rows_of(pending[0], pending[1]), pending[2]


def store_records(session: Session, records: Iterable[Record], batch_id: int | None, *,
                  chunk_size: int = DEFAULT_CHUNK, progress: Progress | None = None,
                  ) -> tuple[ImportCounts, list[int]]:
    """Insert the records (chunked bulk inserts) inside the session's open transaction.

    Returns the counts and, when ``batch_id`` is None, the new measurement ids (single posts).
    Duplicates of stored measurements or of earlier records in ``records`` are skipped.
    """
    registry = ImportRegistry(session)
    counts = ImportCounts()
    new_ids: list[int] = []
    for rows, n_read in chunk_rows(session, records, registry, counts, set(),
                                   batch_id=batch_id, chunk_size=chunk_size):
        if rows:
            if batch_id is None:
                for row in rows:
                    new_ids.append(session.execute(
                        insert(db.Measurement).returning(db.Measurement.id), [row]
                    ).scalar_one())
            else:
                session.execute(insert(db.Measurement), rows)
            counts.created += len(rows)
        if progress is not None:
            progress(n_read)
    for wheel_id in sorted(registry.own_wheels):
        session.flush()
        apply_reference(session, wheel_id, OWN_BASELINE, commit=False)
    return counts, new_ids


def insert_ignoring_duplicates(session: Session, table: Any, index_elements: list[str]) -> Any:
    """``INSERT ... ON CONFLICT DO NOTHING`` on SQLite and PostgreSQL (plain INSERT else)."""
    from sqlalchemy.dialects import postgresql, sqlite

    dialect = session.get_bind().dialect.name
    if dialect == "postgresql":
        return postgresql.insert(table).on_conflict_do_nothing(index_elements=index_elements)
    if dialect == "sqlite":
        return sqlite.insert(table).on_conflict_do_nothing(index_elements=index_elements)
    return insert(table)


def write_new_wheels(session: Session, registry: ImportRegistry) -> None:
    """Insert the vehicles and wheels a staged import found new (upserts: another import may
    have stored them meanwhile), then check that every one is stored where the upload says."""
    new = registry.new_wheels
    if not new:
        return
    vehicles = sorted({w["vehicle_id"] for w in new.values()})
    session.execute(insert_ignoring_duplicates(session, db.Vehicle, ["vehicle_id"]),
                    [{"vehicle_id": v} for v in vehicles])
    session.execute(insert_ignoring_duplicates(session, db.Wheel, ["wheel_id"]),
                    list(new.values()))
    stored = {row[0]: tuple(row[1:]) for row in session.execute(
        select(db.Wheel.wheel_id, db.Wheel.vehicle_id, db.Wheel.bogie_type, db.Wheel.axle,
               db.Wheel.side).where(db.Wheel.wheel_id.in_(list(new))))}
    for wheel_id, wanted in new.items():
        position = (wanted["vehicle_id"], wanted["bogie_type"], wanted["axle"], wanted["side"])
        if stored.get(wheel_id) != position:
            raise ImportFileError("upload", f"wheel {wheel_id!r} was stored meanwhile with "
                                  f"another position {stored.get(wheel_id)!r}", field="wheel_id")


@dataclass
class Stage:
    """Rows of an upload ready to insert, spooled to an anonymous temporary file."""

    counts: ImportCounts
    registry: ImportRegistry
    spool: IO[bytes]
    chunks: int = 0
    keys: set[tuple[str, float]] = field(default_factory=set)

    def rows(self) -> Iterator[list[dict[str, Any]]]:
        self.spool.seek(0)
        for _ in range(self.chunks):
            yield pickle.load(self.spool)

    def close(self) -> None:
        self.spool.close()


def stage_records(session: Session, records: Iterable[Record], *, chunk_size: int,
                  tmp_dir: Path | None = None, max_points: int | None = None,
                  max_id_length: int = 200, progress: Progress | None = None) -> Stage:
    """Read, check and process every record (reads only); the rows go to a spool file."""
    registry = ImportRegistry(session, defer_writes=True)
    if tmp_dir is not None:
        tmp_dir.mkdir(parents=True, exist_ok=True)
    stage = Stage(ImportCounts(), registry, tempfile.TemporaryFile(dir=tmp_dir))

    def check(chunk: list[Record]) -> None:
        if max_points is not None:
            _check_points(chunk, max_points)
        _check_texts(chunk, max_id_length)

    try:
        for rows, n_read in chunk_rows(session, records, registry, stage.counts, stage.keys,
                                       batch_id=None, chunk_size=chunk_size, check=check):
            if rows:
                pickle.dump(rows, stage.spool, protocol=pickle.HIGHEST_PROTOCOL)
                stage.chunks += 1
            if progress is not None:
                progress(n_read)
    except BaseException:
        stage.close()
        raise
    return stage


#: Text fields of a measurement that are stored in bounded columns.
TEXT_FIELDS = ("wheel_id", "vehicle_id", "route_id", "instrument_id", "reference_profile")


def _check_texts(chunk: list[Record], max_id_length: int) -> None:
    """Ids longer than their columns or text holding NUL bytes (which PostgreSQL cannot store)
    are refused on every database alike, naming the field."""
    for record in chunk:
        meta = record.meta
        for name in TEXT_FIELDS:
            value = getattr(meta, name)
            if isinstance(value, str) and (len(value) > max_id_length or "\x00" in value):
                reason = ("holds a NUL byte" if "\x00" in value else
                          f"is {len(value):,} characters long (limit max_id_length = "
                          f"{max_id_length})")
                raise ImportFileError(meta.source_file, f"{name} {reason}",
                                      line=meta.source_line, field=name)
        for key, value in meta.covariates.items():
            if "\x00" in key or (isinstance(value, str) and "\x00" in value):
                raise ImportFileError(meta.source_file, f"covariate {key[:50]!r} holds a NUL "
                                      "byte", line=meta.source_line, field=key[:100])


def _check_points(chunk: list[Record], max_points: int) -> None:
    for record in chunk:
        if isinstance(record, ProfileRecord) and len(record.y_mm) > max_points:
            meta = record.meta
            raise ImportFileError(meta.source_file, f"profile of wheel {meta.wheel_id!r} at "
                                  f"{meta.mileage_km:g} km has {len(record.y_mm):,} points "
                                  f"(limit max_points_per_profile = {max_points:,})",
                                  line=meta.source_line, field="y_mm")


def write_stage(session: Session, stage: Stage, batch_id: int) -> ImportCounts:
    """Insert the staged rows under ``batch_id`` in the session's transaction; rows stored
    meanwhile by another import count as duplicates. Returns the final counts."""
    write_new_wheels(session, stage.registry)
    # Core executemany on the table (not the ORM entity): no per-row ORM bookkeeping
    statement = insert_ignoring_duplicates(session, db.Measurement.__table__,
                                           ["wheel_id", "mileage_km"])
    connection = session.connection()
    for rows in stage.rows():
        for row in rows:
            row["batch_id"] = batch_id
        connection.execute(statement, rows)
    created = int(session.scalar(select(func.count()).select_from(db.Measurement)
                                 .where(db.Measurement.batch_id == batch_id)) or 0)
    for wheel_id in sorted(stage.registry.own_wheels):  # baseline = own first measurement
        session.flush()
        apply_reference(session, wheel_id, OWN_BASELINE, commit=False)
    counts = stage.counts
    counts.duplicates += len(stage.keys) - created
    counts.created = created
    return counts
