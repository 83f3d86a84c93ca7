"""Curve-radius wear tables in storage: upload (CSV), read back as rows or a compiled table.

Validation is :func:`wearcast.statistics.wear_tables.validate_wear_table` (columns, enums,
finite values, a tangent row for every key...); its ``"field: reason"`` errors become 422s.
"""

from __future__ import annotations

import hashlib
import io
import math
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

import pandas as pd
from sqlalchemy import insert, select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.service.schemas import WearTableOut, WearTableRowOut
from wearcast.statistics import wear_tables

MAX_TABLE_BYTES = 20 * 1024 * 1024
#: Compiled tables kept in process (each is a few hundred rows: well under 1 MB).
COMPILED_TABLE_CACHE_SIZE = 16

V = TypeVar("V")


class LruCache(Generic[V]):
    """A small thread-safe least-recently-used cache for immutable values.

    Only for values that can never change under their key (content hashes, or ids of rows
    that are never updated together with their creation time). ``get_or_create`` builds a
    missing value outside the lock, so two threads may build the same value once each; the
    first one stored wins and both get an equal value.
    """

    def __init__(self, maxsize: int) -> None:
        if maxsize < 1:
            raise ValueError("maxsize: must be >= 1")
        self.maxsize = maxsize
        self._data: OrderedDict[Hashable, V] = OrderedDict()
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get_or_create(self, key: Hashable, create: Callable[[], V]) -> V:
        with self._lock:
            if key in self._data:
                self._data.move_to_end(key)
                self.hits += 1
                return self._data[key]
            self.misses += 1
        value = create()
        with self._lock:
            stored = self._data.setdefault(key, value)
            self._data.move_to_end(key)
            while len(self._data) > self.maxsize:
                self._data.popitem(last=False)
        return stored

    def clear(self) -> None:
        with self._lock:
            self._data.clear()
            self.hits = self.misses = 0

    def __len__(self) -> int:
        return len(self._data)


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
                      sha256: str) -> db.WearTable:
    """Store a validated table and its rows in one transaction."""
    row = db.WearTable(name=name, source=source, sha256=sha256, n_rows=len(frame))
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
                        n_rows=row.n_rows, rows=rows)
