"""Manifest CSV: the wheel metadata of MiniProf files, one row per file.

Column ``file`` names a MiniProf file of the upload (its base name, or its path inside the
zip); for a multi-part ``.mpt`` a row may name one part as ``name.mpt#2`` (1-based, as in
the file's ``[Profile2Points]``). The other columns are the metadata columns of the long CSV
(docs/conventions.md "Long CSV": ``wheel_id, vehicle_id, bogie_type, axle, side, mileage_km``
required,
the optional ones and covariates). ``measured_on`` and ``instrument_id`` may be left empty:
the import then takes them from the MiniProf header.

Fields are separated by ``,`` or, as European spreadsheets write CSV, by ``;`` (then a decimal
comma in numbers is read too); the separator is taken from the header line. ``side`` and
``bogie_type`` accept the usual spellings (``L``/``R``, ``links``/``rechts``, ``M``/``T``,
``Trieb``/``Lauf`` …; ``records.SPELLINGS``).
"""

from __future__ import annotations

import io
from typing import BinaryIO

import numpy as np

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import read_chunks, read_header, split_columns
from wearcast.service.readers.records import (
    REQUIRED_META_COLUMNS,
    BadValue,
    MeasurementMetaWithoutPoints,
    build_metas,
    check_header,
    code_column,
    code_meta_columns,
    numeric_column,
)

MANIFEST_NAME = "manifest.csv"


def _file_key(value: str) -> str:
    text = value.strip().replace("\\", "/")
    if not text:
        raise BadValue("is empty")
    return text


def manifest_key(name: str) -> str:
    """Normalised form of a file name as used for manifest look-ups (``/`` separators)."""
    return name.strip().replace("\\", "/")


def read_manifest(stream: BinaryIO, file_name: str) -> dict[str, MeasurementMetaWithoutPoints]:
    """Map each manifest ``file`` entry to its validated metadata.

    Raises ImportFileError for bad metadata (line and field named) and for a file listed twice.
    ``meta.source_file``/``source_line`` point at the manifest row.
    """
    data = stream.read()
    first = data.split(b"\n", 1)[0]
    delimiter = ";" if first.count(b";") > first.count(b",") else ","
    decimal = "," if delimiter == ";" else "."
    stream = io.BytesIO(data)
    columns = read_header(stream, file_name, delimiter)
    check_header(columns, file_name, ("file", *REQUIRED_META_COLUMNS))
    text_columns, covariates = split_columns(columns, ("file",))
    text_columns = [*text_columns, "file"]
    out: dict[str, MeasurementMetaWithoutPoints] = {}
    lines_of: dict[str, int] = {}
    for chunk, lines in read_chunks(stream, file_name, columns, text_columns, 50_000,
                                    delimiter=delimiter, decimal=decimal):
        files = code_column(chunk["file"], "file", _file_key, True, lines, file_name)
        mileage = numeric_column(chunk["mileage_km"], "mileage_km", lines, file_name,
                                 minimum=0.0)
        coded = code_meta_columns(chunk, lines, file_name, covariates)
        rows = np.arange(len(lines))
        metas = build_metas(coded, rows, mileage, lines, file_name, covariates)
        for key, meta in zip(files.values[files.codes].tolist(), metas, strict=True):
            if key in out:
                raise ImportFileError(file_name, f"file {key!r} is already listed on line "
                                      f"{lines_of[key]}", line=meta.source_line, field="file")
            out[key] = meta
            lines_of[key] = meta.source_line or 0
    if not out:
        raise ImportFileError(file_name, "manifest has no rows", line=2)
    return out
