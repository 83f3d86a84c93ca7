"""Streaming reader for the long profile CSV: one row per profile point (docs/conventions.md "Long
CSV").

Required columns ``wheel_id, vehicle_id, bogie_type, axle, side, mileage_km, y_mm, z_mm``
(``y_mm``/``z_mm`` [mm] in the wheel frame: y from the tape circle, negative towards the
flange; z up); optional ``measured_on, route_id, running_mode, instrument_id, load_t,
reference_profile, diameter_mm`` (measured tape-circle diameter [mm]); any other column is a
covariate.

Rules the reader enforces:

* one measurement per (``wheel_id``, ``mileage_km``), and **its rows must be contiguous**: a
  measurement that reappears after other rows is refused, naming the line where it reappears
  and where it started (the reader streams, so it cannot regroup a shuffled file);
* every metadata value is valid and constant within a measurement;
* ``y_mm``, ``z_mm`` and ``mileage_km`` are finite numbers; a profile spans at least
  ``MIN_LATERAL_EXTENT_MM`` laterally, holds ``MIN_POINTS`` points, is not in metres and
  not in MiniProf instrument coordinates.

Line numbers are 1-based file lines with the header on line 1; blank lines are skipped but
counted; quoted fields must not contain line breaks (the line count would drift).

Memory: the file is read ``chunk_rows`` rows at a time (pandas ``read_csv`` with
``chunksize``); text columns are read as categoricals and validated once per distinct value;
the measurement cut by a chunk boundary is carried into the next chunk. Peak memory depends
on ``chunk_rows``, not on the file's length (apart from one small key per measurement kept to
detect non-contiguous measurements).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import IO, Literal, cast

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.records import (
    META_COLUMNS,
    PARAMETER_COLUMNS,
    PROFILE_COLUMNS,
    REQUIRED_META_COLUMNS,
    CodedColumn,
    MeasurementMeta,
    ProfileRecord,
    build_metas,
    check_header,
    code_meta_columns,
    numeric_column,
)

MIN_POINTS = 5
MIN_LATERAL_EXTENT_MM = 1.0
#: Largest |y| [mm] of a wheel-frame profile (tape circle to the field-side face is ~75 mm).
MAX_ABS_Y_MM = 100.0

_UTF8_BOM = b"\xef\xbb\xbf"
_PANDAS_LINE = re.compile(r"line (\d+)")


def sniff_kind(header_columns: Sequence[str]) -> Literal["profile", "parameter"]:
    """``'profile'`` for a long CSV with ``y_mm, z_mm``; ``'parameter'`` for ``sd_mm, sh_mm,
    qr_mm``. Raises ValueError when the header has neither (or both)."""
    columns = {c.strip() for c in header_columns}
    is_profile = bool(columns & set(PROFILE_COLUMNS))
    is_parameter = bool(columns & set(PARAMETER_COLUMNS))
    if is_profile and not is_parameter:
        return "profile"
    if is_parameter and not is_profile:
        return "parameter"
    if is_profile:
        raise ValueError("header has both profile points (y_mm, z_mm) and parameters "
                         "(sd_mm, sh_mm, qr_mm); put them in separate files")
    raise ValueError("header has neither profile points (y_mm, z_mm) nor parameters "
                     "(sd_mm, sh_mm, qr_mm)")


def read_header(stream: IO[bytes], file_name: str, delimiter: str = ",") -> list[str]:
    """Consume and parse the header line of a CSV stream (names stripped, BOM removed)."""
    raw = stream.readline()
    if raw.startswith(_UTF8_BOM):
        raw = raw[len(_UTF8_BOM):]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ImportFileError(file_name, "header is not UTF-8 text", line=1) from None
    if not text.strip():
        raise ImportFileError(file_name, "file is empty (no header line)", line=1)
    return [name.strip() for name in next(csv.reader([text], delimiter=delimiter))]


def read_chunks(stream: IO[bytes], file_name: str, columns: Sequence[str],
                text_columns: Sequence[str], chunk_rows: int, *, delimiter: str = ",",
                decimal: str = ".", first_line: int = 2
                ) -> Iterator[tuple[pd.DataFrame, np.ndarray]]:
    """Chunks of the CSV body (after the header) with each row's 1-based file line.

    Text columns are categorical; other columns are left to pandas' type inference (the
    numeric validation turns bad tokens into errors naming the line). Blank rows are dropped.
    ``first_line`` is the file line of the stream's first row (2: right after the header).
    """
    reader = pd.read_csv(
        stream, header=None, names=list(columns), index_col=False,
        dtype={name: "category" for name in text_columns}, keep_default_na=False,
        na_values=[""], skip_blank_lines=False, chunksize=chunk_rows, encoding="utf-8",
        engine="c", sep=delimiter, decimal=decimal)
    next_line = first_line
    try:
        with reader:
            for chunk in reader:
                n = len(chunk)
                lines = np.arange(next_line, next_line + n, dtype=np.int64)
                next_line += n
                blank = cast(NDArray[np.bool_], chunk.isna().to_numpy().all(axis=1))
                if blank.any():
                    chunk = chunk.loc[~blank]
                    lines = lines[~blank]
                if len(chunk):
                    yield chunk, lines
    except pd.errors.ParserError as exc:
        message = str(exc).strip().splitlines()[-1]
        found = _PANDAS_LINE.search(message)
        line = int(found.group(1)) + first_line - 1 if found else None
        reason = re.sub(r"^Error tokenizing data\. C error: ", "", message)
        raise ImportFileError(file_name, reason, line=line) from None
    except UnicodeDecodeError:
        raise ImportFileError(file_name, "file is not UTF-8 text") from None


def split_columns(columns: Sequence[str], data_columns: Sequence[str]
                  ) -> tuple[list[str], list[str]]:
    """(text columns to read as categoricals, covariate columns) of a header."""
    covariates = [c for c in columns if c not in META_COLUMNS and c not in data_columns]
    text = [c for c in columns if c not in ("mileage_km", *data_columns)]
    return text, covariates


def describe(meta: MeasurementMeta) -> str:
    """``measurement (wheel_id 'W1', mileage_km 12000)`` for error messages."""
    return f"measurement (wheel_id {meta.wheel_id!r}, mileage_km {meta.mileage_km:g})"


@dataclass
class _Pending:
    """The chunk's last measurement, which may continue in the next chunk."""

    meta: MeasurementMeta
    key: tuple[str, float]
    values: tuple[object, ...]
    y_parts: list[np.ndarray]
    z_parts: list[np.ndarray]


def _meta_values(meta: MeasurementMeta) -> tuple[object, ...]:
    return (meta.vehicle_id, meta.bogie_type, meta.axle, meta.side, meta.measured_on,
            meta.route_id, meta.running_mode, meta.instrument_id, meta.load_t,
            meta.reference_profile, tuple(sorted(meta.covariates.items())), meta.diameter_mm)


def _profile_problems(count: np.ndarray, y_min: np.ndarray, y_max: np.ndarray,
                      y_abs: np.ndarray, z_abs: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Index of the first failed check per group (-1 = fine) and the checks' reasons."""
    reasons = [
        f"profile has fewer than {MIN_POINTS} points",
        f"lateral extent of y_mm is below {MIN_LATERAL_EXTENT_MM:g} mm: looks like metres, "
        "expected mm",
        "all |y_mm| and |z_mm| are below 1: looks like metres, expected mm",
        f"y_mm reaches beyond ±{MAX_ABS_Y_MM:g} mm: looks like MiniProf X from the back face; "
        "expected y = X - 70 (wheel frame)",
    ]
    checks = np.stack([
        count < MIN_POINTS,
        (y_max - y_min) < MIN_LATERAL_EXTENT_MM,
        (y_abs < 1.0) & (z_abs < 1.0),
        y_abs > MAX_ABS_Y_MM,
    ])
    first = np.where(checks.any(axis=0), np.argmax(checks, axis=0), -1)
    return first, reasons


def _check_single(y: np.ndarray, z: np.ndarray, meta: MeasurementMeta, file_name: str) -> None:
    first, reasons = _profile_problems(
        np.array([y.size]), np.array([y.min()]), np.array([y.max()]),
        np.array([np.abs(y).max()]), np.array([np.abs(z).max()]))
    if first[0] >= 0:
        raise ImportFileError(file_name, f"{describe(meta)}: {reasons[first[0]]}",
                              line=meta.source_line, field="y_mm")


def _check_consistency(coded: Sequence[CodedColumn], starts_mask: np.ndarray,
                       lines: np.ndarray, file_name: str, wheel: np.ndarray) -> None:
    """Every metadata column must be constant within each measurement of the chunk."""
    inside = ~starts_mask[1:]
    worst: tuple[int, str, str] | None = None
    for column in coded:
        if column.name == "wheel_id":
            continue
        differs = (column.canon[1:] != column.canon[:-1]) & inside
        if differs.any():
            i = int(np.argmax(differs)) + 1
            if worst is None or lines[i] < worst[0]:
                start = int(np.flatnonzero(starts_mask[: i + 1])[-1])
                now = column.values[column.codes[i]]
                before = column.values[column.codes[start]]
                reason = (f"{now!r} differs from {before!r} on line {int(lines[start])}, "
                          f"the first row of measurement (wheel_id "
                          f"{wheel[i]!r}); metadata must be constant within a measurement")
                worst = (int(lines[i]), column.name, reason)
    if worst is not None:
        raise ImportFileError(file_name, worst[2], line=worst[0], field=worst[1])


def reappeared(file_name: str, meta: MeasurementMeta, first: int) -> ImportFileError:
    """The error of a measurement whose rows reappear after other rows (first row ``first``)."""
    return ImportFileError(
        file_name, f"{describe(meta)} appears again; it started on line {first} and its rows "
        "must be contiguous", line=meta.source_line, field="wheel_id")


def iter_profile_records(stream: IO[bytes], file_name: str, *, chunk_rows: int = 200_000,
                         columns: Sequence[str] | None = None, first_line: int = 2
                         ) -> Iterator[ProfileRecord]:
    """Yield one ProfileRecord per measurement of a long profile CSV, streaming.

    Parameters
    ----------
    stream : binary file object positioned at the start of the CSV (UTF-8, optional BOM)
    file_name : the name used in errors and in ``meta.source_file``
    chunk_rows : rows parsed per pandas chunk (bounds the memory used)
    columns : the header's column names when the header was read (and checked) already;
        the stream then holds body lines only, the first of them file line ``first_line``
        (a block of a file, :func:`parse_block`)

    Raises ImportFileError on the first problem (file, line, field and reason).
    """
    if chunk_rows < 1:
        raise ValueError("chunk_rows must be >= 1")
    if columns is None:
        columns = read_header(stream, file_name)
        check_header(columns, file_name, REQUIRED_META_COLUMNS + PROFILE_COLUMNS)
        first_line = 2
    text_columns, covariates = split_columns(columns, PROFILE_COLUMNS)
    pending: _Pending | None = None
    seen: dict[tuple[str, float], int] = {}

    def finish(p: _Pending) -> ProfileRecord:
        y = p.y_parts[0] if len(p.y_parts) == 1 else np.concatenate(p.y_parts)
        z = p.z_parts[0] if len(p.z_parts) == 1 else np.concatenate(p.z_parts)
        _check_single(y, z, p.meta, file_name)
        _claim(p.key, p.meta)
        return ProfileRecord(p.meta, y, z, None)

    def _claim(key: tuple[str, float], meta: MeasurementMeta) -> None:
        first = seen.get(key)
        if first is not None:
            raise reappeared(file_name, meta, first)
        seen[key] = meta.source_line or 0

    for chunk, lines in read_chunks(stream, file_name, columns, text_columns, chunk_rows,
                                    first_line=first_line):
        y = numeric_column(chunk["y_mm"], "y_mm", lines, file_name)
        z = numeric_column(chunk["z_mm"], "z_mm", lines, file_name)
        mileage = numeric_column(chunk["mileage_km"], "mileage_km", lines, file_name,
                                 minimum=0.0)
        coded = code_meta_columns(chunk, lines, file_name, covariates)
        wheel_col = next(c for c in coded if c.name == "wheel_id")
        wheel_canon = wheel_col.canon
        n = len(y)
        starts_mask = np.empty(n, dtype=bool)
        starts_mask[0] = True
        np.logical_or(wheel_canon[1:] != wheel_canon[:-1], mileage[1:] != mileage[:-1],
                      out=starts_mask[1:])
        wheel_values = wheel_col.values[wheel_col.codes]
        _check_consistency(coded, starts_mask, lines, file_name, wheel_values)
        starts = np.flatnonzero(starts_mask)
        ends = np.append(starts[1:], n)
        metas = build_metas(coded, starts, mileage, lines, file_name, covariates)
        first_problem, reasons = _profile_problems(
            ends - starts, np.minimum.reduceat(y, starts), np.maximum.reduceat(y, starts),
            np.maximum.reduceat(np.abs(y), starts), np.maximum.reduceat(np.abs(z), starts))
        last = len(starts) - 1
        for g, meta in enumerate(metas):
            a, b = int(starts[g]), int(ends[g])
            key = (meta.wheel_id, meta.mileage_km)
            if g == 0 and pending is not None:
                if pending.key == key:
                    if _meta_values(meta) != pending.values:
                        raise ImportFileError(
                            file_name, f"metadata of {describe(meta)} differs from its first "
                            f"row on line {pending.meta.source_line}", line=meta.source_line)
                    pending.y_parts.append(y[a:b].copy())
                    pending.z_parts.append(z[a:b].copy())
                    if g == last:
                        continue
                    yield finish(pending)
                    pending = None
                    continue
                yield finish(pending)
                pending = None
            if g == last:
                pending = _Pending(meta, key, _meta_values(meta), [y[a:b].copy()],
                                   [z[a:b].copy()])
                continue
            problem = int(first_problem[g])
            if problem >= 0:
                raise ImportFileError(file_name, f"{describe(meta)}: {reasons[problem]}",
                                      line=meta.source_line, field="y_mm")
            _claim(key, meta)
            yield ProfileRecord(meta, y[a:b].copy(), z[a:b].copy(), None)
    if pending is not None:
        yield finish(pending)


#: What :func:`parse_block` returns: the block's records and, when the block holds a problem,
#: the ImportFileError's (file, reason, line, field) after the records before it.
BlockRecords = tuple[list[ProfileRecord], tuple[str, str, int | None, str | None] | None]


def parse_block(file_name: str, columns: Sequence[str], first_line: int, data: bytes,
                more: bytes = b"", more_end: int = 0) -> BlockRecords:
    """The records of a block of whole body lines of a long profile CSV whose header
    ``columns`` were read and checked already; ``first_line`` is the file line of the block's
    first line. The block is ``data`` followed by ``more[:more_end]`` (a caller's two reads,
    joined here so that the caller copies neither). Runs in import worker processes too, so
    the first problem comes back as plain values (:data:`BlockRecords`) rather than raised.
    Contiguity is checked within the block only: across blocks it is the caller's
    (:func:`reappeared`)."""
    import io

    if more_end:
        data = data + more[:more_end]
    records: list[ProfileRecord] = []
    try:
        for record in iter_profile_records(io.BytesIO(data), file_name, columns=columns,
                                           first_line=first_line):
            records.append(record)
    except ImportFileError as exc:
        return records, (exc.file, exc.reason, exc.line, exc.field)
    return records, None
