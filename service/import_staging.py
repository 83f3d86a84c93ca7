"""The records of an import, chunk by chunk: checked, processed, turned into rows, inserted.

A chunk of records is checked for duplicates (a (wheel_id, mileage_km) already stored or met
earlier in the upload is skipped and counted), its new wheels are registered
(:mod:`wearcast.service.import_registry`) and its profiles are processed (in worker processes
when large, :mod:`wearcast.service.import_pool`) while the next chunk is read; then its
``measurements`` rows are built (:mod:`wearcast.service.measurement_rows`,
:func:`chunk_rows`).

An upload's rows are inserted under a batch whose status is ``pending`` (invisible to every
read, :mod:`wearcast.service.batch_visibility`), chunk by chunk, each chunk its own short write
transaction (:func:`write_records`): SQLite's single write lock is held for one chunk's
inserts at a time (``import_chunk_size`` rows) and released between chunks, so another
writer waits for one chunk at most, however large the upload (:class:`WriteLockShare` keeps
the import from taking the lock straight back). Reading and processing (the slow part) run
outside any write transaction, the next chunk's while the current one is inserted. New
vehicles and wheels are upserts (concurrent imports sharing them both succeed); a row
another import stored meanwhile is skipped as a duplicate, one another running import holds
is a 409 (retry when it has finished). The batch is flipped to ``complete`` in one last
short transaction (:mod:`wearcast.service.pending_batches`). Single posts are inserted
directly in the session's open transaction (:func:`store_records`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from itertools import groupby, islice
from typing import Any

from sqlalchemy import func, insert, select, tuple_
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.batch_visibility import COMPLETE, INCLUDE_PENDING
from wearcast.service.errors import ApiError, Conflict
from wearcast.service.import_pool import submit_profiles
from wearcast.service.import_registry import ImportRegistry
from wearcast.service.import_result import ImportCounts, collect_warnings
from wearcast.service.import_worker import Processed
from wearcast.service.measurement_rows import measurement_row
from wearcast.service.pending_batches import BEAT_S, beat
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
        found = session.execute(
            select(db.Measurement.wheel_id, db.Measurement.mileage_km,
                   db.Measurement.batch_id).where(
                tuple_(db.Measurement.wheel_id, db.Measurement.mileage_km).in_(set(keys)))
            .execution_options(**{INCLUDE_PENDING: True})).all()
        stored = {(row[0], row[1]) for row in found}
        if any(row[2] is not None and row[2] != batch_id for row in found):
            in_flight_conflict(session, stored, batch_id)
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


def write_new_wheels(session: Session, registry: ImportRegistry,
                     wheel_ids: set[str] | None = None) -> None:
    """Insert the vehicles and wheels an import found new (all, or those of ``wheel_ids``;
    upserts: another import may have stored them meanwhile), then check that every one is
    stored where the upload says. Written wheels leave ``registry.new_wheels``."""
    chosen = list(registry.new_wheels) if wheel_ids is None else \
        sorted(registry.new_wheels.keys() & wheel_ids)
    new = {w: registry.new_wheels.pop(w) for w in chosen}
    if not new:
        return
    vehicles = sorted({w["vehicle_id"] for w in new.values()})
    session.execute(insert_ignoring_duplicates(session, db.Vehicle, ["vehicle_id"]),
                    [{"vehicle_id": v, "registered_batch_id": registry.batch_id}
                     for v in vehicles])
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


#: On SQLite, the longest pause [s] an import leaves between two chunk transactions so that
#: writers waiting for the database lock get it (their busy handler retries every 100 ms at
#: most once it has waited a while).
MAX_LOCK_PAUSE_S = 0.1


class WriteLockShare:
    """Keeps an import's share of SQLite's one write lock at most about one half.

    SQLite grants its write lock to whoever asks first when it is free; a waiting writer
    sleeps in its busy handler and asks again, it is not queued. An import that started its
    next chunk transaction right after committing the last one could take the lock again
    each time before the waiter wakes. So before each chunk transaction the import pauses,
    if needed, until the lock has been free for as long as it held it last time (at most
    :data:`MAX_LOCK_PAUSE_S`; reading and processing the next chunk usually take longer
    anyway, so the pause is rarely needed). Not needed on PostgreSQL (row locks).
    """

    def __init__(self, sqlite: bool, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.sqlite = sqlite
        self.clock, self.sleep = clock, sleep
        self.held_s = 0.0
        self.released_at: float | None = None
        self.started_at = 0.0

    def acquire(self) -> None:
        """Before a chunk transaction: pause until the lock has been free long enough."""
        if self.sqlite and self.released_at is not None:
            pause = min(self.held_s, MAX_LOCK_PAUSE_S) - (self.clock() - self.released_at)
            if pause > 0:
                self.sleep(pause)
        self.started_at = self.clock()

    def release(self) -> None:
        """After a chunk transaction (committed or rolled back)."""
        self.released_at = self.clock()
        self.held_s = self.released_at - self.started_at


def in_flight_conflict(session: Session, keys: Iterable[tuple[str, float]],
                       batch_id: int | None) -> None:
    """409 when a (wheel_id, mileage_km) of ``keys`` belongs to another import that is still
    running (a pending batch): whether it is a duplicate is known only once that import has
    completed (or failed, and its rows are gone)."""
    wanted = set(keys)
    if not wanted:
        return
    holders = set(session.scalars(
        select(db.Measurement.batch_id).where(
            tuple_(db.Measurement.wheel_id, db.Measurement.mileage_km).in_(wanted),
            db.Measurement.batch_id.is_not(None))
        .execution_options(**{INCLUDE_PENDING: True})))
    holders.discard(batch_id)
    if not holders:
        return
    running = sorted(session.scalars(select(db.ImportBatch.id).where(
        db.ImportBatch.id.in_(holders), db.ImportBatch.status != COMPLETE)))
    if running:
        error: ApiError = Conflict("file", "measurements of this upload are being imported "
                                   f"now by batch {running[0]}; retry when it has finished")
        error.headers = {"Retry-After": "5"}
        raise error


@dataclass
class Written:
    """What :func:`write_records` read and inserted under a pending batch."""

    counts: ImportCounts
    registry: ImportRegistry
    keys: set[tuple[str, float]] = field(default_factory=set)


def write_records(session: Session, records: Iterable[Record], batch_id: int, *,
                  chunk_size: int, max_points: int | None = None, max_id_length: int = 200,
                  progress: Progress | None = None) -> Written:
    """Check, process and insert the records under the pending batch ``batch_id``, each
    chunk of rows in its own short transaction (committed here).

    A chunk's profiles are processed while the previous chunk is inserted
    (:func:`chunk_rows`); the new wheels and vehicles a chunk's rows need are upserted in the
    same transaction as those rows (so every wheel the batch created has a measurement of the
    batch, and goes with it if the batch is discarded); a row another import stored meanwhile
    is skipped (a duplicate), one another import is still inserting is a 409
    (:func:`in_flight_conflict`). The session must see pending batches
    (:func:`wearcast.service.batch_visibility.seeing_pending`).
    """
    registry = ImportRegistry(session, defer_writes=True, batch_id=batch_id)
    written = Written(ImportCounts(), registry)
    statement = insert_ignoring_duplicates(session, db.Measurement.__table__,
                                           ["wheel_id", "mileage_km"])
    share = WriteLockShare(session.get_bind().dialect.name == "sqlite")

    def check(chunk: list[Record]) -> None:
        if max_points is not None:
            _check_points(chunk, max_points)
        _check_texts(chunk, max_id_length)

    last_beat = time.monotonic()
    for rows, n_read in chunk_rows(session, records, registry, written.counts, written.keys,
                                   batch_id=batch_id, chunk_size=chunk_size, check=check):
        if rows or time.monotonic() - last_beat > BEAT_S:
            session.commit()  # end the reads of this chunk before the write transaction
            share.acquire()
            try:
                if rows:
                    write_new_wheels(session, registry, {row["wheel_id"] for row in rows})
                    inserted = _insert_runs(session, statement, rows)
                    # the driver's count of inserted rows when it has one (SQLite, psycopg
                    # sum the executemany's); fewer (a row stored meanwhile) or none: ask
                    if inserted != len(rows):
                        keys = [(row["wheel_id"], float(row["mileage_km"])) for row in rows]
                        if _inserted(session, keys, batch_id) < len(rows):
                            in_flight_conflict(session, keys, batch_id)
                beat(session, batch_id)
                session.commit()
                last_beat = time.monotonic()
            finally:
                share.release()
        if progress is not None:
            progress(n_read)
    session.commit()
    return written


def _insert_runs(session: Session, statement: Any, rows: list[dict[str, Any]]) -> int:
    """Insert ``rows`` in order, one executemany per run of rows with the same keys, and
    return the driver's count of inserted rows (-1 where it has none).

    SQLAlchemy compiles an executemany for its first row's keys and asks every other row
    for them, so a chunk mixing profiles and parameter records (which carry no points, no
    reference fits) must go as separate runs; order is kept, so ids follow the file."""
    def keys(row: dict[str, Any]) -> tuple[str, ...]:
        return tuple(row)

    total = 0
    for _, run in groupby(rows, key=keys):
        count = session.connection().execute(statement, list(run)).rowcount
        if count < 0 or total < 0:
            total = -1
        else:
            total += count
    return total


def _inserted(session: Session, keys: list[tuple[str, float]], batch_id: int) -> int:
    return int(session.scalar(
        select(func.count()).select_from(db.Measurement).where(
            db.Measurement.batch_id == batch_id,
            tuple_(db.Measurement.wheel_id, db.Measurement.mileage_km).in_(set(keys)))
        .execution_options(**{INCLUDE_PENDING: True})) or 0)


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
