"""Measurements of a pending import batch are invisible to every read.

An import inserts its measurements chunk by chunk, each chunk its own short write transaction,
under a batch whose ``status`` is ``pending``, and flips the batch to ``complete`` in one last
short transaction (:mod:`wearcast.service.importing`). So that no half-written batch is ever
seen, every ORM ``SELECT`` a :class:`~sqlalchemy.orm.Session` runs that touches
``measurements`` (listings, counts, joins, ``Session.get``) is given the criterion

    ``batch_id IS NULL OR batch_id NOT IN``
    ``(SELECT id FROM import_batches WHERE status <> 'complete')``

(and wheels and vehicles the same on the batch that registered them, ``registered_batch_id``,
so the new wheels and vehicles of a pending import are invisible too) with SQLAlchemy's
:func:`~sqlalchemy.orm.with_loader_criteria` from a ``do_orm_execute``
event on every session (SQLAlchemy's documented pattern for global visibility rules), so a
read added later is covered without remembering to filter. The set of pending batches is
tiny (the imports running now), so the criterion costs one small subquery. A batch being
discarded (``discarding``) is as invisible as a pending one.

The import itself and the recovery after a crash must see their own pending rows (duplicate
checks, the own-baseline re-reference of a wheel, deleting an interrupted batch): they run
their statements with ``execution_options(include_pending_batches=True)``
(:data:`INCLUDE_PENDING`), or within :func:`seeing_pending` (the whole session).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from sqlalchemy import ColumnElement, event, or_, select
from sqlalchemy.orm import ORMExecuteState, Session, with_loader_criteria

from wearcast.service import models_db as db

PENDING = "pending"
COMPLETE = "complete"
#: A failed or abandoned batch being removed: as invisible as a pending one.
DISCARDING = "discarding"
#: Execution option: this statement sees the measurements of pending batches too.
INCLUDE_PENDING = "include_pending_batches"
#: Session ``info`` key: every statement of this session sees pending batches.
_SESSION_KEY = "wearcast_include_pending_batches"


def _not_incomplete(batch_id: Any) -> ColumnElement[bool]:
    incomplete = select(db.ImportBatch.id).where(db.ImportBatch.status != COMPLETE)
    return or_(batch_id.is_(None), batch_id.not_in(incomplete))


def visible(measurement: Any = db.Measurement) -> ColumnElement[bool]:
    """True for a measurement that is not part of an incomplete (pending or discarding)
    import batch."""
    return _not_incomplete(measurement.batch_id)


def registered_visible(entity: Any) -> ColumnElement[bool]:
    """True for a wheel or vehicle not registered by an incomplete import batch."""
    return _not_incomplete(entity.registered_batch_id)


@contextmanager
def seeing_pending(session: Session) -> Iterator[Session]:
    """Within the block every statement of ``session`` sees pending batches (import,
    recovery)."""
    before = session.info.get(_SESSION_KEY, False)
    session.info[_SESSION_KEY] = True
    try:
        yield session
    finally:
        session.info[_SESSION_KEY] = before


@event.listens_for(Session, "do_orm_execute")
def _hide_pending_batches(state: ORMExecuteState) -> None:
    if (not state.is_select or state.is_column_load or state.is_relationship_load
            or state.execution_options.get(INCLUDE_PENDING, False)
            or state.session.info.get(_SESSION_KEY, False)):
        return
    state.statement = state.statement.options(
        with_loader_criteria(db.Measurement, lambda cls: visible(cls), include_aliases=True),
        with_loader_criteria(db.Wheel, lambda cls: registered_visible(cls),
                             include_aliases=True),
        with_loader_criteria(db.Vehicle, lambda cls: registered_visible(cls),
                             include_aliases=True))
