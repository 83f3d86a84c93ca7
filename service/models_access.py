"""Storage of API keys, the audit trail, idempotency keys and job control (SQLAlchemy).

Kept beside :mod:`wearcast.service.models_db` on the same metadata; the schema is created by
migration ``0003_service``. A key is stored only as the SHA-256 of its secret (keys are 256
random bits, so a plain hash cannot be reversed by search); the audit trail names the key that
created, changed or deleted what, and keeps a deleted row's content (``snapshot``).
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import DateTime, Index, Integer, String, event, func
from sqlalchemy import inspect as sa_inspect
from sqlalchemy.orm import Mapped, mapped_column
from sqlalchemy.orm.attributes import set_committed_value

from wearcast.service.models_db import Base, IdInteger


class ApiKey(Base):
    """An API key: its hash, a display prefix, scopes (``read``, ``write``, ``admin``)."""

    __tablename__ = "api_keys"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    key_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    prefix: Mapped[str] = mapped_column(String(16))
    scopes: Mapped[str] = mapped_column(String(100))
    created_by: Mapped[int | None] = mapped_column(IdInteger)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())
    revoked_at: Mapped[dt.datetime | None] = mapped_column(DateTime(timezone=True))


class AuditRecord(Base):
    """Who did what: one row per accepted write (and per key created or revoked).

    ``action`` is ``create``, ``change``, ``delete`` or ``supersede``; ``entity`` the kind of
    thing (``measurements``, ``routes``, ...), ``entity_id`` its id when known; ``snapshot``
    holds a deleted or superseded row as it was.
    """

    __tablename__ = "audit_records"
    #: The newest removal (``action`` delete or supersede) is looked up by every serving
    #: process once a second (:mod:`wearcast.service.removal_watch`).
    __table_args__ = (Index("ix_audit_records_action_id", "action", "id"),)
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True), server_default=func.now(),
                                            index=True)
    api_key_id: Mapped[int | None] = mapped_column(IdInteger, index=True)
    key_name: Mapped[str | None] = mapped_column(String(200))
    action: Mapped[str] = mapped_column(String(20))
    entity: Mapped[str] = mapped_column(String(100), index=True)
    entity_id: Mapped[str | None] = mapped_column(String(200))
    method: Mapped[str] = mapped_column(String(10))
    path: Mapped[str] = mapped_column(String(500))
    status: Mapped[int] = mapped_column(Integer)
    snapshot: Mapped[dict[str, Any] | None] = mapped_column()


class IdempotencyKey(Base):
    """An ``Idempotency-Key`` seen on a write: the hash of its request, and its outcome.

    ``state`` is ``in_flight`` while the first request runs (a second one gets 409), then
    ``done`` with the answer's ``batch_id``; a different request under the same key gets 422.
    """

    __tablename__ = "idempotency_keys"
    key: Mapped[str] = mapped_column(String(200), primary_key=True)
    request_sha256: Mapped[str] = mapped_column(String(64))
    state: Mapped[str] = mapped_column(String(20))
    batch_id: Mapped[int | None] = mapped_column(IdInteger)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


def _aware_datetimes(target: Any, _context: Any = None) -> None:
    """SQLite gives back ``DateTime(timezone=True)`` columns without their zone; they are
    stored in UTC, so every loaded row gets UTC attached (answers carry an offset, as their
    OpenAPI ``date-time`` format requires)."""
    state = target.__dict__
    for key in _datetime_keys(type(target)):
        value = state.get(key)
        if isinstance(value, dt.datetime) and value.tzinfo is None:
            set_committed_value(target, key, value.replace(tzinfo=dt.UTC))


_DATETIME_KEYS: dict[type, tuple[str, ...]] = {}


def _datetime_keys(cls: type) -> tuple[str, ...]:
    """The attributes of a mapped class that are date-time columns (looked up once per
    class: every loaded row runs :func:`_aware_datetimes`)."""
    keys = _DATETIME_KEYS.get(cls)
    if keys is None:
        mapper: Any = sa_inspect(cls)
        keys = tuple(attr.key for attr in mapper.column_attrs
                     if any(isinstance(column.type, DateTime) for column in attr.columns))
        _DATETIME_KEYS[cls] = keys
    return keys


event.listen(Base, "load", _aware_datetimes, propagate=True)
event.listen(Base, "refresh", lambda target, context, _attrs: _aware_datetimes(target),
             propagate=True)
event.listen(Base, "refresh_flush",
             lambda target, context, _attrs: _aware_datetimes(target), propagate=True)
