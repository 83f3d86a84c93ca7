"""Reader for the parameter-only CSV: one row per measurement with Sd, Sh, qR [mm].

Same metadata columns as the long profile CSV (docs/conventions.md "Long CSV"), plus ``sd_mm, sh_mm,
qr_mm`` (EN 15313 / MiniProf definitions, docs/conventions.md) instead of points. One
row per (``wheel_id``, ``mileage_km``); a repeated measurement is refused. Streams in chunks
like the long reader; line numbers are 1-based file lines (header = line 1).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import IO

import numpy as np

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import describe, read_chunks, read_header, split_columns
from wearcast.service.readers.records import (
    PARAMETER_COLUMNS,
    REQUIRED_META_COLUMNS,
    ParameterRecord,
    build_metas,
    check_header,
    code_meta_columns,
    numeric_column,
)

#: Plausible range [mm] of every profile parameter; below 1 the file is probably in metres.
PARAMETER_RANGE_MM = (1.0, 100.0)


def _parameter_column(chunk, name: str, lines: np.ndarray, file_name: str) -> np.ndarray:
    values = numeric_column(chunk[name], name, lines, file_name)
    low, high = PARAMETER_RANGE_MM
    small = values < low
    if small.any():
        i = int(np.argmax(small))
        raise ImportFileError(file_name, f"{values[i]!r} is below {low:g} mm: looks like "
                              "metres, expected mm", line=int(lines[i]), field=name)
    large = values > high
    if large.any():
        i = int(np.argmax(large))
        raise ImportFileError(file_name, f"{values[i]!r} is above {high:g} mm: not a plausible "
                              "profile parameter", line=int(lines[i]), field=name)
    return values


def iter_parameter_records(stream: IO[bytes], file_name: str, *, chunk_rows: int = 200_000
                           ) -> Iterator[ParameterRecord]:
    """Yield one ParameterRecord per row of a parameter-only CSV.

    Raises ImportFileError (file, line, field, reason) on the first problem.
    """
    columns = read_header(stream, file_name)
    check_header(columns, file_name, REQUIRED_META_COLUMNS + PARAMETER_COLUMNS)
    text_columns, covariates = split_columns(columns, PARAMETER_COLUMNS)
    seen: dict[tuple[str, float], int] = {}
    for chunk, lines in read_chunks(stream, file_name, columns, text_columns, chunk_rows):
        sd = _parameter_column(chunk, "sd_mm", lines, file_name)
        sh = _parameter_column(chunk, "sh_mm", lines, file_name)
        qr = _parameter_column(chunk, "qr_mm", lines, file_name)
        mileage = numeric_column(chunk["mileage_km"], "mileage_km", lines, file_name,
                                 minimum=0.0)
        coded = code_meta_columns(chunk, lines, file_name, covariates)
        rows = np.arange(len(lines))
        metas = build_metas(coded, rows, mileage, lines, file_name, covariates)
        for meta, s_d, s_h, q_r in zip(metas, sd.tolist(), sh.tolist(), qr.tolist(),
                                       strict=True):
            key = (meta.wheel_id, meta.mileage_km)
            first = seen.get(key)
            if first is not None:
                raise ImportFileError(file_name, f"{describe(meta)} already given on line "
                                      f"{first}", line=meta.source_line, field="wheel_id")
            seen[key] = meta.source_line or 0
            yield ParameterRecord(meta, s_d, s_h, q_r)
