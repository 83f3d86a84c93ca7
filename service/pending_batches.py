"""The life of an import batch written chunk by chunk: opened ``pending``, completed in one
short transaction, or discarded with everything it wrote.

An import (:mod:`wearcast.service.importing`) opens its batch as ``pending`` in a short
transaction of its own (:func:`open_batch`: the batch row with its checksum and idempotency
key, so a concurrent import of the same content sees it at once, and the rows of its raw
files), inserts the measurements in chunk transactions
(:func:`wearcast.service.import_staging.write_records`) — all invisible to every read while
the batch is pending (:mod:`wearcast.service.batch_visibility`) — and flips it to
``complete`` with its counts in one last short transaction (:func:`complete_batch`). When an
import fails, or was killed and the service starts again
(:func:`wearcast.service.housekeeping.clean_after_restart`), its pending batch is removed
chunk by chunk (:func:`discard_batch`): its measurements, the wheels and vehicles only those
measurements used, its raw-file rows and the batch; every step stays invisible, since the
batch row, the last to go, keeps the rest hidden until then. An import notes in each chunk
transaction that it is alive (``heartbeat_at``, :func:`beat`); a pending batch silent for
:data:`STALE_S` — its process died while the service kept running, e.g. a killed worker of
``serve --workers N`` — is discarded by the service's periodic sweep
(:func:`wearcast.service.housekeeping.sweep_abandoned_imports`).
"""

from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

from sqlalchemy import delete, exists, func, select, update
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.batch_visibility import (
    COMPLETE,
    DISCARDING,
    INCLUDE_PENDING,
    PENDING,
    visible,
)
from wearcast.service.errors import Conflict
from wearcast.service.import_result import ImportCounts
from wearcast.service.reference_store import OWN_BASELINE
from wearcast.service.utc_time import as_utc, now_utc
from wearcast.service.wheel_reference import apply_reference

if TYPE_CHECKING:
    from wearcast.service.import_staging import Written

#: Measurements deleted per transaction when a pending batch is discarded.
DISCARD_CHUNK = 2000
#: A pending batch whose import has written nothing for this long [s] belongs to a process
#: that died without the service restarting (a killed worker of ``serve --workers N``); the
#: services' periodic sweep discards it. An import notes it is alive at least every
#: :data:`BEAT_S` seconds.
STALE_S = 600.0
BEAT_S = 30.0
_ALL = {INCLUDE_PENDING: True}


def open_batch(session: Session, *, checksum: str, idempotency_key: str | None,
               file_name: str, raw_files: list[dict[str, Any]]) -> int:
    """Insert a pending batch and its raw-file rows (``role, name, sha256, size_bytes,
    storage_path``) and commit; its id. IntegrityError when the checksum or key is taken."""
    batch = db.ImportBatch(checksum_sha256=checksum, idempotency_key=idempotency_key,
                           file_name=file_name, n_records=0, n_created=0, n_duplicates=0,
                           n_points=0, status=PENDING, heartbeat_at=now_utc())
    session.add(batch)
    session.flush()
    for raw in raw_files:
        session.add(db.RawFile(batch_id=batch.id, **raw))
    session.commit()
    return batch.id


def beat(session: Session, batch_id: int) -> None:
    """Note that the batch's import is alive (in its current transaction)."""
    session.execute(update(db.ImportBatch).where(db.ImportBatch.id == batch_id)
                    .values(heartbeat_at=now_utc()))


def complete_batch(session: Session, batch_id: int, written: Written) -> ImportCounts:
    """Make a pending batch visible with its final counts; returns them.

    Wheels whose baseline is their own first measurement are re-taken against it first: a
    wheel all of whose measurements are in this batch in a transaction of its own (still
    invisible); one that had measurements before, whose stored rows change too, in the last
    transaction, the one that flips the batch to ``complete``.
    """
    m = db.Measurement
    counts = written.counts
    created = int(session.scalar(select(func.count()).select_from(m)
                                 .where(m.batch_id == batch_id).execution_options(**_ALL))
                  or 0)
    counts.duplicates += len(written.keys) - created
    counts.created = created
    seen_before = set(session.scalars(
        select(m.wheel_id).where(m.wheel_id.in_(sorted(written.registry.own_wheels)),
                                 visible(m)).distinct()))  # stored before this batch
    for wheel_id in sorted(written.registry.own_wheels - seen_before):
        apply_reference(session, wheel_id, OWN_BASELINE, commit=True)
    for wheel_id in sorted(seen_before):
        apply_reference(session, wheel_id, OWN_BASELINE, commit=False)
    _adopt_registered(session, batch_id, sorted({key[0] for key in written.keys}))
    flipped = session.execute(update(db.ImportBatch).where(
        db.ImportBatch.id == batch_id, db.ImportBatch.status == PENDING).values(
        status=COMPLETE, n_records=counts.records, n_created=counts.created,
        n_duplicates=counts.duplicates, n_points=counts.points, heartbeat_at=None))
    if flipped.rowcount != 1:  # type: ignore[attr-defined]
        session.rollback()
        raise Conflict("file", f"import batch {batch_id} was given up as abandoned while it "
                       "was imported (no chunk written for "
                       f"{STALE_S:.0f} s); try again")
    session.commit()
    return counts


def discard_batch(session: Session, batch_id: int) -> int:
    """Remove an incomplete batch and what it wrote, in short transactions; the number of its
    measurements removed. A complete batch is left alone (0).

    The batch is first marked ``discarding``, so that its import, should it still be alive,
    cannot flip it to complete (:func:`complete_batch` answers 409 then) and nothing it
    writes meanwhile becomes visible; a batch whose rows could not all be removed stays
    ``discarding`` and is removed by the next sweep or start."""
    m, w, v = db.Measurement, db.Wheel, db.Vehicle
    session.rollback()
    claimed = session.execute(update(db.ImportBatch).where(
        db.ImportBatch.id == batch_id, db.ImportBatch.status != COMPLETE).values(
        status=DISCARDING))
    session.commit()
    if claimed.rowcount != 1:  # type: ignore[attr-defined]
        return 0
    wheels = sorted(set(session.scalars(select(m.wheel_id).where(m.batch_id == batch_id)
                                        .distinct().execution_options(**_ALL))))
    removed = 0
    while ids := list(session.scalars(select(m.id).where(m.batch_id == batch_id)
                                      .limit(DISCARD_CHUNK).execution_options(**_ALL))):
        session.execute(delete(m).where(m.id.in_(ids)),
                        execution_options={"synchronize_session": False})
        session.commit()
        removed += len(ids)
    for start in range(0, len(wheels), DISCARD_CHUNK):
        chunk = wheels[start:start + DISCARD_CHUNK]
        vehicles = sorted(set(session.scalars(select(w.vehicle_id)
                                              .where(w.wheel_id.in_(chunk))
                                              .execution_options(**_ALL))))
        # a wheel only this batch measured, then a vehicle left without wheels and without
        # planning attributes (fleet, mileage per day)
        session.execute(delete(w).where(w.wheel_id.in_(chunk),
                                        ~exists().where(m.wheel_id == w.wheel_id)),
                        execution_options={"synchronize_session": False})
        session.execute(delete(v).where(v.vehicle_id.in_(vehicles), v.fleet_id.is_(None),
                                        v.km_per_day.is_(None),
                                        ~exists().where(w.vehicle_id == v.vehicle_id)),
                        execution_options={"synchronize_session": False})
        session.commit()
    session.execute(delete(db.RawFile).where(db.RawFile.batch_id == batch_id))
    session.execute(delete(db.ImportBatch).where(db.ImportBatch.id == batch_id,
                                                 db.ImportBatch.status == DISCARDING))
    session.commit()
    return removed


def _adopt_registered(session: Session, batch_id: int, wheel_ids: list[str]) -> None:
    """Wheels (and their vehicles) this batch measured that another import still pending
    registered become visible with this batch: their ``registered_batch_id`` is cleared."""
    w, v = db.Wheel, db.Vehicle
    if not session.scalar(select(
            exists().where(w.registered_batch_id.is_not(None), w.registered_batch_id != batch_id)
            | exists().where(v.registered_batch_id.is_not(None),
                             v.registered_batch_id != batch_id))):
        return  # no other import has registered anything: nothing to adopt (indexed check)
    for start in range(0, len(wheel_ids), DISCARD_CHUNK):
        chunk = wheel_ids[start:start + DISCARD_CHUNK]
        session.execute(update(v).where(
            v.vehicle_id.in_(select(w.vehicle_id).where(w.wheel_id.in_(chunk))),
            v.registered_batch_id.is_not(None), v.registered_batch_id != batch_id).values(
            registered_batch_id=None), execution_options={"synchronize_session": False})
        session.execute(update(w).where(
            w.wheel_id.in_(chunk), w.registered_batch_id.is_not(None),
            w.registered_batch_id != batch_id).values(registered_batch_id=None),
            execution_options={"synchronize_session": False})


def incomplete_batch_ids(session: Session, silent_since: dt.datetime | None = None
                         ) -> list[int]:
    """Batches that are not complete: all of them, or (``silent_since``) those being
    discarded and the pending ones whose import has not written since then."""
    rows = session.execute(select(db.ImportBatch.id, db.ImportBatch.status,
                                  db.ImportBatch.heartbeat_at, db.ImportBatch.created_at)
                           .where(db.ImportBatch.status != COMPLETE)
                           .order_by(db.ImportBatch.id)).all()
    session.rollback()
    if silent_since is None:
        return [row[0] for row in rows]
    out = []
    for batch_id, status, heartbeat, created in rows:
        last = as_utc(heartbeat) or as_utc(created)
        if status == DISCARDING or last is None or last < silent_since:
            out.append(batch_id)
    return out

