"""What the readers hand to the import service: one record per measurement.

Every reader (long CSV, parameter CSV, MiniProf + manifest, zip bundles) yields
``ProfileRecord`` or ``ParameterRecord`` objects, each carrying a validated
``MeasurementMeta``. The metadata columns and their rules are those of docs/conventions.md "Long
CSV"
and "Conventions": ``side`` in {left, right} seen in the vehicle's reference running
direction, ``axle`` in {1, 2} counted from the vehicle's reference end, ``running_mode`` in
{lead, mixed}; any other column is kept as a covariate.

The second half of this module validates metadata columnwise on pandas frames whose text
columns are categorical: each distinct value is checked once (not once per row), and the
first offending row is located with numpy, so the readers stay fast on millions of rows.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import date
from typing import Any

import numpy as np
import pandas as pd

from wearcast.physics.vocabulary import RUNNING_MODES, BogieType, RunningMode, Side
from wearcast.service.readers.errors import ImportFileError

REQUIRED_META_COLUMNS: tuple[str, ...] = (
    "wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km")
OPTIONAL_META_COLUMNS: tuple[str, ...] = (
    "measured_on", "route_id", "running_mode", "instrument_id", "load_t", "reference_profile",
    "diameter_mm")
META_COLUMNS: tuple[str, ...] = REQUIRED_META_COLUMNS + OPTIONAL_META_COLUMNS
PROFILE_COLUMNS: tuple[str, ...] = ("y_mm", "z_mm")
PARAMETER_COLUMNS: tuple[str, ...] = ("sd_mm", "sh_mm", "qr_mm")
DEFAULT_REFERENCE_PROFILE = "S1002"


@dataclass(frozen=True)
class MeasurementMeta:
    """Who was measured, where and when — one measurement's metadata.

    ``mileage_km`` [km] is finite and >= 0; ``load_t`` [t] is the vehicle's load when given;
    ``diameter_mm`` [mm] the wheel's measured running (tape-circle) diameter when given;
    ``covariates`` holds every extra column (numbers as float, text as str).
    ``source_file``/``source_line`` say where the measurement came from (the first row of a
    long-CSV measurement, the manifest row for a MiniProf file).
    """

    wheel_id: str
    vehicle_id: str
    bogie_type: BogieType
    axle: int
    side: Side
    mileage_km: float
    measured_on: date | None = None
    route_id: str | None = None
    running_mode: RunningMode | None = None
    instrument_id: str | None = None
    load_t: float | None = None
    reference_profile: str = DEFAULT_REFERENCE_PROFILE
    covariates: dict[str, str | float] = field(default_factory=dict)
    diameter_mm: float | None = None
    source_file: str = ""
    source_line: int | None = None


#: A manifest row is a measurement's metadata without its points (same type, by design).
MeasurementMetaWithoutPoints = MeasurementMeta


@dataclass(frozen=True)
class ProfileRecord:
    """A measured wheel profile in the wheel frame of docs/conventions.md.

    ``y_mm`` [mm] lateral from the tape circle, negative towards the flange; ``z_mm`` [mm]
    radius increase over the tape circle (up). Points in measurement order.
    ``instrument_parameters`` holds the instrument's own Sd/Sh/qR [mm] (keys ``sd_mm``,
    ``sh_mm``, ``qr_mm``) when the file carried real values, else ``None``.
    """

    meta: MeasurementMeta
    y_mm: np.ndarray
    z_mm: np.ndarray
    instrument_parameters: dict[str, float] | None = None
    #: Sd/Sh/qR [mm] as printed in the file's header, even template placeholders (keys
    #: ``sd_mm, sh_mm, qr_mm`` and ``placeholder``: True for the old-style template's values)
    header_parameters: dict[str, float | bool] | None = None
    #: The points are in the instrument's own datum frame (back face, tape circle): placed by
    #: it, never by a free fit (MiniProf files)
    instrument_datum: bool = False
    #: Line of the manifest row that described this file (MiniProf), for warnings
    manifest_line: int | None = None
    #: The instrument's datum entries of the header as printed (MiniProf ``Xoffset``,
    #: ``Yoffset``, ``RefPoint1``…), reported with the placement
    datum_header: dict[str, str] | None = None


@dataclass(frozen=True)
class ParameterRecord:
    """A measurement that recorded only the profile parameters Sd, Sh, qR [mm]."""

    meta: MeasurementMeta
    sd_mm: float
    sh_mm: float
    qr_mm: float


# --------------------------------------------------------------------------- validation


class BadValue(Exception):
    """Raised by a value converter; ``reason`` becomes the ImportFileError's reason."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def _text(value: str) -> str:
    out = value.strip()
    if not out:
        raise BadValue("is empty")
    return out


def _enum(*allowed: str) -> Callable[[str], str]:
    def convert(value: str) -> str:
        out = value.strip().lower()
        if out not in allowed:
            raise BadValue(f"{value!r} is not one of {', '.join(allowed)}")
        return out
    return convert


#: Usual spellings of side and bogie type (English, German, French, Italian, Spanish,
#: abbreviations), compared after lower-casing and dropping dots, spaces, '-' and '_'.
SPELLINGS: dict[str, dict[str, str]] = {
    "side": {s: "left" for s in ("l", "left", "lh", "links", "li", "lft", "gauche", "g",
                                 "sinistra", "sx", "izquierda", "izq", "leftwheel")}
    | {s: "right" for s in ("r", "right", "rh", "rechts", "re", "rgt", "droite", "d",
                            "destra", "dx", "derecha", "der", "rightwheel")},
    "bogie_type": {s: "motor" for s in ("motor", "m", "mot", "motorbogie", "motored",
                                        "motorised", "motorized", "powered", "power",
                                        "driven", "trieb", "triebdrehgestell", "tdg",
                                        "motrice", "moteur")}
    | {s: "trailer" for s in ("trailer", "t", "trail", "trailerbogie", "unpowered",
                              "nonpowered", "carrying", "lauf", "laufdrehgestell", "ldg",
                              "porteur", "portante", "remorque")},
}


def _spelled(name: str) -> Callable[[str], str]:
    """Converter accepting the usual spellings of ``name`` (``SPELLINGS``)."""
    table = SPELLINGS[name]
    allowed = sorted(set(table.values()))

    def convert(value: str) -> str:
        key = "".join(ch for ch in value.strip().lower() if ch not in " .-_")
        if key not in table:
            raise BadValue(f"{value!r} is not one of {', '.join(allowed)} (or a usual "
                           f"spelling such as {', '.join(k for k in table if len(k) <= 6)})")
        return table[key]
    return convert


def _axle(value: str) -> int:
    try:
        number = float(value)
    except ValueError:
        raise BadValue(f"{value!r} is not one of 1, 2") from None
    if number not in (1.0, 2.0):
        raise BadValue(f"{value!r} is not one of 1, 2")
    return int(number)


def _iso_date(value: str) -> date:
    text = value.strip()
    if len(text) > 10 and text[10] in "T ":
        text = text[:10]
    try:
        return date.fromisoformat(text)
    except ValueError:
        raise BadValue(f"{value!r} is not an ISO date (YYYY-MM-DD)") from None


def _positive_float(value: str) -> float:
    text = value.strip()
    if text.count(",") == 1 and "." not in text:  # decimal comma (';'-separated files)
        text = text.replace(",", ".")
    try:
        number = float(text)
    except ValueError:
        raise BadValue(f"{value!r} is not a number") from None
    if not math.isfinite(number) or number <= 0:
        raise BadValue(f"{value!r} must be a finite number > 0")
    return number


def _covariate(value: str) -> str | float:
    text = value.strip()
    try:
        number = float(text)
    except ValueError:
        return text
    return number if math.isfinite(number) else text


#: Converter of each text metadata column (a covariate uses ``_covariate``).
CONVERTERS: dict[str, Callable[[str], object]] = {
    "wheel_id": _text,
    "vehicle_id": _text,
    "bogie_type": _spelled("bogie_type"),
    "axle": _axle,
    "side": _spelled("side"),
    "measured_on": _iso_date,
    "route_id": _text,
    "running_mode": _enum(*RUNNING_MODES),
    "instrument_id": _text,
    "load_t": _positive_float,
    "reference_profile": _text,
    "diameter_mm": _positive_float,
}
#: Text columns that must hold a value on every row.
REQUIRED_TEXT_COLUMNS = ("wheel_id", "vehicle_id", "bogie_type", "axle", "side")


def check_header(columns: Sequence[str], file_name: str, required: Sequence[str]) -> None:
    """Refuse a header with empty or repeated names or without a required column (line 1)."""
    seen: set[str] = set()
    for position, name in enumerate(columns, start=1):
        if not name:
            raise ImportFileError(file_name, f"column {position} of the header has no name",
                                  line=1)
        if name in seen:
            raise ImportFileError(file_name, "column appears twice in the header", line=1,
                                  field=name)
        seen.add(name)
    for name in required:
        if name not in seen:
            raise ImportFileError(file_name, "required column is missing from the header",
                                  line=1, field=name)


@dataclass(frozen=True)
class CodedColumn:
    """A validated categorical column: ``values[codes[i]]`` is row i's value.

    ``codes`` [row] index ``values``; the last entry of ``values`` is ``None`` (missing), and
    ``canon`` [row] is an integer per distinct *converted* value (so ' left' and 'left' agree).
    """

    name: str
    codes: np.ndarray
    values: np.ndarray
    canon: np.ndarray


def _first_line(mask: np.ndarray, lines: np.ndarray) -> int | None:
    if not mask.any():
        return None
    return int(lines[int(np.argmax(mask))])


def code_column(series: pd.Series, name: str, converter: Callable[[str], object],
                required: bool, lines: np.ndarray, file_name: str) -> CodedColumn:
    """Convert and validate one text column once per distinct value.

    ``series`` is categorical (read with ``dtype='category'``) or anything pandas can make
    categorical; ``lines`` [row] are the rows' 1-based file lines, used in the error.
    """
    if not isinstance(series.dtype, pd.CategoricalDtype):
        series = series.astype("category")
    categories = series.cat.categories
    codes = series.cat.codes.to_numpy().astype(np.int64)
    n_cat = len(categories)
    values = np.empty(n_cat + 1, dtype=object)
    bad = np.zeros(n_cat + 1, dtype=bool)
    reasons: dict[int, str] = {}
    canon_of = np.empty(n_cat + 1, dtype=np.int64)
    canon_ids: dict[object, int] = {}
    for i, raw in enumerate(categories):
        try:
            value = converter(str(raw))
        except BadValue as exc:
            bad[i] = True
            reasons[i] = exc.reason
            value = None
        values[i] = value
        canon_of[i] = canon_ids.setdefault(value, len(canon_ids))
    values[n_cat] = None
    bad[n_cat] = required
    reasons[n_cat] = "value is missing"
    canon_of[n_cat] = canon_ids.setdefault(None, len(canon_ids))
    codes[codes < 0] = n_cat
    row_bad = bad[codes]
    line = _first_line(row_bad, lines)
    if line is not None:
        raise ImportFileError(file_name, reasons[int(codes[int(np.argmax(row_bad))])],
                              line=line, field=name)
    return CodedColumn(name, codes, values, canon_of[codes])


def numeric_column(series: pd.Series, name: str, lines: np.ndarray, file_name: str, *,
                   minimum: float | None = None) -> np.ndarray:
    """A required numeric column as float64 [row]; refuses text, blanks, NaN and inf.

    ``minimum`` (inclusive) is checked when given.
    """
    if pd.api.types.is_numeric_dtype(series.dtype) and not pd.api.types.is_bool_dtype(
            series.dtype):
        values = series.to_numpy(dtype=np.float64, na_value=np.nan)
    else:
        converted = pd.to_numeric(series, errors="coerce")
        values = converted.to_numpy(dtype=np.float64, na_value=np.nan)
        unparsed = np.isnan(values) & series.notna().to_numpy()
        line = _first_line(unparsed, lines)
        if line is not None:
            raw = series.iloc[int(np.argmax(unparsed))]
            raise ImportFileError(file_name, f"{raw!r} is not a number", line=line, field=name)
    missing = np.isnan(values)
    line = _first_line(missing, lines)
    if line is not None:
        raise ImportFileError(file_name, "value is missing", line=line, field=name)
    infinite = np.isinf(values)
    line = _first_line(infinite, lines)
    if line is not None:
        raise ImportFileError(file_name, f"{values[int(np.argmax(infinite))]!r} is not finite",
                              line=line, field=name)
    if minimum is not None:
        low = values < minimum
        line = _first_line(low, lines)
        if line is not None:
            raise ImportFileError(file_name, f"{values[int(np.argmax(low))]!r} is below "
                                  f"{minimum:g}", line=line, field=name)
    return values


def code_meta_columns(frame: pd.DataFrame, lines: np.ndarray, file_name: str,
                      covariates: Sequence[str]) -> list[CodedColumn]:
    """Validate every text metadata column present in ``frame`` (plus the covariates)."""
    coded = []
    for name in REQUIRED_TEXT_COLUMNS + OPTIONAL_META_COLUMNS:
        if name in frame.columns:
            coded.append(code_column(frame[name], name, CONVERTERS[name],
                                     name in REQUIRED_TEXT_COLUMNS, lines, file_name))
    for name in covariates:
        coded.append(code_column(frame[name], name, _covariate, False, lines, file_name))
    return coded


def build_metas(coded: Sequence[CodedColumn], rows: np.ndarray, mileage_km: np.ndarray,
                lines: np.ndarray, file_name: str, covariates: Sequence[str]
                ) -> list[MeasurementMeta]:
    """One MeasurementMeta per index in ``rows`` from validated columns.

    ``mileage_km`` [km] and ``lines`` are per row of the frame the columns came from.
    """
    columns: dict[str, list[Any]] = {}
    for column in coded:
        columns[column.name] = column.values[column.codes[rows]].tolist()
    n = len(rows)
    none: list[Any] = [None] * n
    standard = {name: columns.get(name, none) for name in CONVERTERS}
    cov_lists = [(name, columns[name]) for name in covariates]
    mileage = mileage_km[rows].tolist()
    line_list = lines[rows].tolist()
    metas = []
    for i in range(n):
        cov = {name: values[i] for name, values in cov_lists if values[i] is not None}
        reference = standard["reference_profile"][i]
        metas.append(MeasurementMeta(
            wheel_id=standard["wheel_id"][i], vehicle_id=standard["vehicle_id"][i],
            bogie_type=standard["bogie_type"][i], axle=standard["axle"][i],
            side=standard["side"][i], mileage_km=mileage[i],
            measured_on=standard["measured_on"][i], route_id=standard["route_id"][i],
            running_mode=standard["running_mode"][i],
            instrument_id=standard["instrument_id"][i], load_t=standard["load_t"][i],
            reference_profile=DEFAULT_REFERENCE_PROFILE if reference is None else reference,
            covariates=cov, source_file=file_name, source_line=line_list[i],
            diameter_mm=standard["diameter_mm"][i]))
    return metas
