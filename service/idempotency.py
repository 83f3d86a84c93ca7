"""``Idempotency-Key`` on imports, after the IETF httpapi idempotency-key draft: the same key
with the same request answers the first result (``duplicate: true``); with a different
request it is refused (422); while the first request under the key is still running, a second
one is refused (409, retry later).

The key is claimed in its own short transaction (an ``idempotency_keys`` row in state
``in_flight`` with the hash of the request), so other processes see it at once; it becomes
``done`` with the batch id when the import commits, and is released when the import fails (a
corrected request may reuse it). Claims left ``in_flight`` by a killed process are released
at the next start (:func:`release_stale`) and, while the service keeps running (a killed worker
of ``serve --workers N``), by its periodic sweep once no pending batch under the key has been
written for ``pending_batches.STALE_S`` (:func:`release_abandoned`).
"""

from __future__ import annotations

import datetime as dt

from sqlalchemy import delete, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.errors import ApiError, Conflict, Unprocessable
from wearcast.service.models_access import IdempotencyKey
from wearcast.service.utc_time import as_utc, now_utc

FIELD = "Idempotency-Key"
#: An in-flight claim older than this [s] belongs to a dead request and is taken over.
STALE_S = 3600.0


def _own_session(session: Session) -> Session:
    return Session(bind=session.get_bind(), expire_on_commit=False)


def claim(session: Session, key: str, request_sha256: str) -> int | None:
    """Claim ``key`` for a request; the batch id when the same request already completed
    (answer it again), None when claimed now. 422 for another request under the key, 409
    while the first one runs."""
    with _own_session(session) as own:
        own.add(IdempotencyKey(key=key, request_sha256=request_sha256, state="in_flight"))
        try:
            own.commit()
            return None
        except IntegrityError:
            own.rollback()
        row = own.get(IdempotencyKey, key)
        if row is None:  # released meanwhile: claim again
            own.add(IdempotencyKey(key=key, request_sha256=request_sha256, state="in_flight"))
            own.commit()
            return None
        if row.request_sha256 != request_sha256:
            raise Unprocessable(FIELD, "this key was used for a different request (another "
                                "file or manifest); use a new key for new content")
        if row.state == "in_flight":
            created = as_utc(row.created_at)
            age = (now_utc() - created).total_seconds() if created else 0.0
            if age < STALE_S:
                error: ApiError = Conflict(FIELD, "the first request with this key is still "
                                           "running; retry when it has finished")
                error.headers = {"Retry-After": "5"}
                raise error
            own.execute(update(IdempotencyKey).where(IdempotencyKey.key == key)
                        .values(created_at=dt.datetime.now(dt.UTC)))
            own.commit()
            return None
        return row.batch_id


def complete(session: Session, key: str, batch_id: int) -> None:
    with _own_session(session) as own:
        own.execute(update(IdempotencyKey).where(IdempotencyKey.key == key)
                    .values(state="done", batch_id=batch_id))
        own.commit()


def release(session: Session, key: str) -> None:
    with _own_session(session) as own:
        own.execute(delete(IdempotencyKey).where(IdempotencyKey.key == key,
                                                 IdempotencyKey.state == "in_flight"))
        own.commit()


def release_stale(session: Session) -> int:
    """Forget every in-flight claim (at start, when no request of this service runs)."""
    done = session.execute(delete(IdempotencyKey).where(IdempotencyKey.state == "in_flight"))
    session.commit()
    return int(done.rowcount or 0)  # type: ignore[attr-defined]


def release_abandoned(session: Session, silent_since: dt.datetime) -> int:
    """Forget the in-flight claims whose request died while the service kept running: claimed
    before ``silent_since`` and with no batch under the key (the import died before opening
    it, or its pending batch was discarded). A claim whose batch is still pending is kept: the
    batch's heartbeat decides, and its sweep discards it first. Returns how many."""
    stale = select(IdempotencyKey.key).where(IdempotencyKey.state == "in_flight",
                                             IdempotencyKey.created_at < silent_since)
    with_batch = select(db.ImportBatch.idempotency_key).where(
        db.ImportBatch.idempotency_key.is_not(None))
    keys = list(session.scalars(stale.where(IdempotencyKey.key.not_in(with_batch))))
    if keys:
        session.execute(delete(IdempotencyKey).where(IdempotencyKey.key.in_(keys),
                                                     IdempotencyKey.state == "in_flight"))
    session.commit()
    return len(keys)
