"""Timestamps of the service's rows: aware UTC datetimes.

Rows store UTC; SQLite gives timestamps back without their zone, PostgreSQL with it.
"""

from __future__ import annotations

import datetime as dt


def now_utc() -> dt.datetime:
    """The current time, aware, in UTC."""
    return dt.datetime.now(dt.UTC)


def as_utc(value: dt.datetime | None) -> dt.datetime | None:
    """A stored timestamp as an aware UTC datetime (a naive one was stored in UTC)."""
    if value is None or value.tzinfo is not None:
        return value
    return value.replace(tzinfo=dt.UTC)
