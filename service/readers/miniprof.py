"""Greenwood MiniProf measurement files: wheels (``.whl``), rails (``.ban``), multi-part (``.mpt``).

Three text layouts, as the instrument's files come:

* **regular** — ``Key=Value`` header lines (``ColumnDef=X,Y``, ``XYPoints``, ``Date``
  dd/mm/yyyy, ``Side=%L``, ``MPSerNo``, ``Sd=``/``Sh=``/``qR=`` …), then the points, one per
  line, separated by spaces or commas (usually after a blank line, not always);
* **old** — first line ``#MINIWHEELPROF`` or ``MINIPROF …``, dotted labels
  (``Stock.......:``) and a ``(Sd/Sh/qR)`` line whose values are template placeholders in
  every file seen: they are kept in ``header`` but never reported as instrument parameters;
  ``MINIPROF <type> <serial> <yyyy> <m> <d>`` carries the instrument serial and the date;
* **mpt** — ``[FileInfo]``, ``[Profile1Info]``, ``[Profile1Points]``, … one part per
  profile (the ``MPDn=`` drawing entries of an Info section are skipped).

Raw points are returned in file order in instrument coordinates: X [mm] from the wheel's
back face (0) to the field side (~140), Y [mm] up with 0 at the taperline (X = 70).
``to_wheel_frame`` converts to the wheel frame of docs/conventions.md (y = X - 70, z = Y), undoing
the sign and order differences between files and refusing data that is not a wheel.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from datetime import date
from typing import Literal

import numpy as np

from wearcast.physics.vocabulary import Side
from wearcast.service.readers.errors import ImportFileError

TAPE_CIRCLE_X_MM = 70.0
#: Sd/Sh/qR printed by the old-style template in every file seen; never real values.
OLD_STYLE_PLACEHOLDERS = (32.58, 37.11, 14.71)
WHEEL_EXTENSIONS = (".whl", ".mpt")
RAIL_EXTENSIONS = (".ban",)
#: Wheel-frame window [mm] that must hold the flange of any wheel (S1002 tip at y = -55).
FLANGE_WINDOW_MM = (-62.0, -45.0)
#: Plausible flange height [mm] above the tape circle (new S1002: 28; limit Sh <= 36).
FLANGE_HEIGHT_RANGE_MM = (15.0, 45.0)
#: Largest |z| [mm] allowed at the tape circle (Y is zeroed at the taperline).
TAPE_CIRCLE_TOLERANCE_MM = 3.0

_SPLIT = re.compile(r"[,;\s]+")
_SECTION = re.compile(r"^\[([^\]]+)\]\s*$")
_MPD_KEY = re.compile(r"^MPD\d+$")


@dataclass(frozen=True)
class MiniProfPart:
    """One profile of a multi-part ``.mpt`` file: ``name`` ('Profile1', …), its header and
    raw points X, Y [mm] in file order."""

    number: int
    name: str
    header: dict[str, str]
    x_mm: np.ndarray
    y_mm: np.ndarray


@dataclass(frozen=True)
class MiniProfFile:
    """A parsed MiniProf file, points as measured (instrument X, Y [mm], file order).

    For ``.mpt`` files ``x_mm``/``y_mm``/``header`` are those of the first part and ``parts``
    lists every part; for the other layouts ``parts`` is empty.
    ``instrument_parameters`` (``sd_mm, sh_mm, qr_mm``) [mm] only when the header holds real
    values (regular layout); ``is_rail`` for rail profiles (``.ban`` or a rail header).
    """

    file_name: str
    layout: Literal["regular", "old", "mpt"]
    header: dict[str, str]
    x_mm: np.ndarray
    y_mm: np.ndarray
    measured_on: date | None
    side_hint: Side | None
    instrument_serial: str | None
    instrument_parameters: dict[str, float] | None
    parts: tuple[MiniProfPart, ...] = ()
    is_rail: bool = False
    #: Sd/Sh/qR [mm] as printed in the header, placeholders included (``placeholder`` True
    #: for the old-style template's values), None when the header has none
    header_parameters: dict[str, float | bool] | None = None


def _decode(data: bytes) -> str:
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace")


def _numbers(line: str) -> list[float]:
    """Leading numeric tokens of a data line (trailing words are a comment)."""
    out = []
    for token in _SPLIT.split(line.strip()):
        if not token:
            continue
        try:
            out.append(float(token))
        except ValueError:
            break
    return out


def _is_data_line(line: str) -> bool:
    return len(_numbers(line)) >= 2


def _parse_points(lines: list[tuple[int, str]], file_name: str, header: dict[str, str],
                  section: str = "", check_count: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """X, Y [mm] from numbered data lines, using ``ColumnDef`` to find the columns."""
    columns = [c.strip().upper() for c in header.get("ColumnDef", "X,Y").split(",") if c.strip()]
    if "X" not in columns or "Y" not in columns:
        raise ImportFileError(file_name, f"ColumnDef {header.get('ColumnDef')!r} has no X and "
                              "Y column", field="ColumnDef")
    ix, iy = columns.index("X"), columns.index("Y")
    need = max(ix, iy) + 1
    rows: list[list[float]] = []
    width = None
    for number, text in lines:
        if not text.strip():
            continue
        values = _numbers(text)
        if len(values) < need:
            raise ImportFileError(file_name, f"expected at least {need} numbers (columns "
                                  f"{','.join(columns)}), read {text.strip()!r}", line=number)
        if width is None:
            width = len(values)
        elif len(values) != width:
            raise ImportFileError(file_name, f"expected {width} numbers as on the first data "
                                  f"line, read {len(values)} in {text.strip()!r}", line=number)
        if not (math.isfinite(values[ix]) and math.isfinite(values[iy])):
            raise ImportFileError(file_name, f"point {text.strip()!r} is not finite",
                                  line=number)
        rows.append([values[ix], values[iy]])
    where = f" in [{section}]" if section else ""
    if len(rows) < 2:
        raise ImportFileError(file_name, f"no profile points found{where}")
    declared = header.get("XYPoints", "").strip()
    if check_count and declared_count_differs(declared, len(rows)):
        raise ImportFileError(file_name, f"header says XYPoints={declared} but {len(rows)} "
                              f"points were read{where} (truncated file?)", field="XYPoints")
    points = np.asarray(rows, dtype=np.float64)
    return points[:, 0].copy(), points[:, 1].copy()


def _key_value(line: str) -> tuple[str, str] | None:
    text = line.strip().strip('"')
    if "=" not in text:
        return None
    key, value = text.split("=", 1)
    key = key.strip()
    return (key, value.strip()) if key else None


def _parse_date(text: str | None) -> date | None:
    if not text:
        return None
    found = re.match(r"^\s*(\d{1,2})[/.](\d{1,2})[/.](\d{4})\s*$", text)
    if not found:
        return None
    day, month, year = (int(g) for g in found.groups())
    try:
        return date(year, month, day)
    except ValueError:
        return None


def _side(text: str | None) -> Side | None:
    value = (text or "").strip().lstrip("%").strip().lower()
    if value in ("l", "left"):
        return "left"
    if value in ("r", "right"):
        return "right"
    return None


def _serial(text: str | None) -> str | None:
    value = (text or "").strip()
    return None if value in ("", "0") else value


def _instrument_parameters(header: dict[str, str]) -> dict[str, float] | None:
    values = []
    for key in ("Sd", "Sh", "qR"):
        try:
            value = float(header.get(key, ""))
        except ValueError:
            return None
        if not math.isfinite(value) or value <= 0:
            return None
        values.append(value)
    if tuple(round(v, 2) for v in values) == OLD_STYLE_PLACEHOLDERS:
        return None
    return dict(zip(("sd_mm", "sh_mm", "qr_mm"), values, strict=True))


def _printed_parameters(header: dict[str, str], layout: str) -> dict[str, float | bool] | None:
    """Sd/Sh/qR as printed: ``Sd=``/``Sh=``/``qR=`` lines, or the old ``(Sd/Sh/qR)`` line."""
    if layout == "old":
        texts = _SPLIT.split(header.get("Sd/Sh/qR", "").strip())
    else:
        texts = [header.get(key, "") for key in ("Sd", "Sh", "qR")]
    try:
        values = [float(t) for t in texts if t]
    except ValueError:
        return None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        return None
    out: dict[str, float | bool] = dict(zip(("sd_mm", "sh_mm", "qr_mm"), values, strict=True))
    out["placeholder"] = tuple(round(v, 2) for v in values) == OLD_STYLE_PLACEHOLDERS
    return out


def _regular(lines: list[str], file_name: str, check_count: bool
             ) -> tuple[dict[str, str], np.ndarray, np.ndarray]:
    header: dict[str, str] = {}
    start = len(lines)
    for i, line in enumerate(lines):
        if not line.strip():
            if header:
                start = i + 1
                break
            continue
        pair = _key_value(line)
        if pair is not None:
            header.setdefault(pair[0], pair[1])
        elif _is_data_line(line):
            start = i
            break
    numbered = [(i + 1, lines[i]) for i in range(start, len(lines))]
    x, y = _parse_points(numbered, file_name, header, check_count=check_count)
    return header, x, y


def _old(lines: list[str], file_name: str) -> tuple[dict[str, str], np.ndarray, np.ndarray]:
    header: dict[str, str] = {}
    marker = next((i for i, line in enumerate(lines) if "(Sd/Sh/qR)" in line), None)
    if marker is None:
        blank = next((i for i, line in enumerate(lines) if not line.strip()), None)
        if blank is None:
            raise ImportFileError(file_name, "old-style MiniProf file without a (Sd/Sh/qR) "
                                  "line or a blank line before the points")
        header_end, start = blank, blank + 1
    else:
        header_end, start = marker + 1, marker + 1
        values = lines[marker].replace("(Sd/Sh/qR)", "").strip().strip('"').strip()
        if not values and marker > 0:
            values = lines[marker - 1].strip().strip('"').strip()
        header["Sd/Sh/qR"] = values
    for i, line in enumerate(lines[:header_end]):
        text = line.strip().strip('"').strip()
        if not text or "(Sd/Sh/qR)" in text or (marker is not None and i == marker - 1
                                                and text == header.get("Sd/Sh/qR")):
            continue
        upper = text.upper()
        if i == 0 and upper.startswith("#MINI"):
            header["Format"] = text.lstrip("#")
        elif upper.startswith("MINIPROF"):
            header["MINIPROF"] = text[len("MINIPROF"):].strip()
        elif ":" in text and re.match(r"^[^:]*\.\.", text):
            label, value = text.split(":", 1)
            header[label.rstrip(". ").strip()] = value.strip()
        else:
            header.setdefault("Name", text)
    numbered = [(i + 1, lines[i]) for i in range(start, len(lines))]
    x, y = _parse_points(numbered, file_name, {})
    return header, x, y


def declared_count_differs(declared: str, count: int) -> bool:
    """Whether a header count (``XYPoints``) is a number of ASCII digits other than ``count``;
    compared as text, so a count of thousands of digits or in superscripts cannot fail."""
    if not (declared.isascii() and declared.isdigit()):
        return False
    return declared.lstrip("0") != str(count).lstrip("0")


def _old_instrument(header: dict[str, str]) -> tuple[str | None, date | None]:
    """Serial and date from ``MINIPROF <type> <serial> <yyyy> <m> <d>``."""
    tokens = header.get("MINIPROF", "").split()
    if len(tokens) != 5 or not all(t.isdigit() for t in tokens):
        return None, None
    _, serial, year, month, day = tokens
    try:
        measured = date(int(year), int(month), int(day))
    except ValueError:
        measured = None
    return _serial(serial), measured


def _mpt(lines: list[str], file_name: str, check_count: bool
         ) -> tuple[dict[str, str], tuple[MiniProfPart, ...]]:
    sections: dict[str, list[tuple[int, str]]] = {}
    order: list[str] = []
    current: str | None = None
    for i, line in enumerate(lines):
        found = _SECTION.match(line.strip())
        if found:
            current = found.group(1).strip()
            if current in sections:
                raise ImportFileError(file_name, f"section [{current}] appears twice",
                                      line=i + 1)
            sections[current] = []
            order.append(current)
        elif current is not None:
            sections[current].append((i + 1, line))
        elif line.strip():
            raise ImportFileError(file_name, "text before the first [section]", line=i + 1)

    def kv(name: str) -> dict[str, str]:
        out: dict[str, str] = {}
        for _, line in sections.get(name, []):
            pair = _key_value(line)
            if pair is not None and not _MPD_KEY.match(pair[0]):
                out.setdefault(pair[0], pair[1])
        return out

    parts = []
    for name in order:
        found = re.match(r"^Profile(\d+)Points$", name)
        if not found:
            continue
        number = int(found.group(1))
        header = kv(f"Profile{number}Info")
        x, y = _parse_points(sections[name], file_name, header, section=name,
                             check_count=check_count)
        parts.append(MiniProfPart(number, f"Profile{number}", header, x, y))
    if not parts:
        raise ImportFileError(file_name, "multi-part file has no [ProfileNPoints] section")
    return kv("FileInfo"), tuple(parts)


def _looks_like_rail(file_name: str, header: dict[str, str], first_line: str) -> bool:
    if file_name.lower().endswith(RAIL_EXTENSIONS):
        return True
    if "RAIL" in first_line.upper():
        return True
    return any(key in header for key in ("Rail", "RailGaugePoint", "Gauge"))


def parse_miniprof(data: bytes, file_name: str) -> MiniProfFile:
    """Parse a MiniProf file (any of the three layouts) from its bytes.

    Raises ImportFileError naming the file and line of anything malformed.
    """
    text = _decode(data)
    lines = text.splitlines()
    first = next((line.strip() for line in lines if line.strip()), "")
    if not first:
        raise ImportFileError(file_name, "file is empty")
    upper = first.upper()
    parts: tuple[MiniProfPart, ...] = ()
    # Rail files are parsed only to be recognised and refused; a hand-added point (seen in
    # a real .ban file) must not hide that behind a point-count error.
    check_count = not file_name.lower().endswith(RAIL_EXTENSIONS)
    if _SECTION.match(first):
        layout: Literal["regular", "old", "mpt"] = "mpt"
        file_header, parts = _mpt(lines, file_name, check_count)
        header = {**file_header, **parts[0].header}
        x, y = parts[0].x_mm, parts[0].y_mm
    elif upper.startswith("#MINI") or upper.startswith("MINIPROF"):
        layout = "old"
        header, x, y = _old(lines, file_name)
    elif _key_value(first) is not None:
        layout = "regular"
        header, x, y = _regular(lines, file_name, check_count)
    else:
        raise ImportFileError(file_name, "not a MiniProf file (expected Key=Value header lines, "
                              "#MINIWHEELPROF / MINIPROF, or [FileInfo])", line=1)
    if layout == "old":
        serial, measured_on = _old_instrument(header)
        parameters = None
    else:
        serial = _serial(header.get("MPSerNo"))
        measured_on = _parse_date(header.get("Date"))
        parameters = _instrument_parameters(header) if layout == "regular" else None
    return MiniProfFile(
        file_name=file_name, layout=layout, header=header, x_mm=x, y_mm=y,
        measured_on=measured_on, side_hint=_side(header.get("Side")),
        instrument_serial=serial, instrument_parameters=parameters, parts=parts,
        is_rail=_looks_like_rail(file_name, header, first),
        header_parameters=_printed_parameters(header, layout))


def to_wheel_frame(mp: MiniProfFile, part: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Points of a MiniProf wheel file in the wheel frame (docs/conventions.md).

    Parameters
    ----------
    mp : a parsed MiniProf file
    part : for ``.mpt`` files, the 1-based part number (required when it has several parts)

    Returns
    -------
    (y_mm, z_mm) [mm]: y = X - 70 (from the tape circle, negative towards the flange),
    z = Y (up), ordered from the flange back (back face) to the field side. Files whose Y
    runs downwards (flange below the taperline) are flipped so that the flange tip is the
    maximum of z near y = -55. Points are otherwise raw (no cleaning of zig-zags).

    Raises ImportFileError for rail files and for data that is not a plausible wheel: no
    points in the flange window ``FLANGE_WINDOW_MM``, a flange height outside
    ``FLANGE_HEIGHT_RANGE_MM``, or no point at the tape circle with |z| <= 3 mm.
    """
    name = mp.file_name
    if mp.is_rail:
        raise ImportFileError(name, "rail profile (.ban / rail header): only wheel profiles "
                              "(.whl, .mpt) can be imported as wheel measurements")
    if mp.parts:
        chosen: MiniProfPart | None
        if part is None:
            if len(mp.parts) > 1:
                raise ImportFileError(name, f"file has {len(mp.parts)} profile parts; name "
                                      "one (e.g. 'file.mpt#2' in the manifest)")
            chosen = mp.parts[0]
        else:
            chosen = next((p for p in mp.parts if p.number == part), None)
            if chosen is None:
                raise ImportFileError(name, f"file has no profile part {part} (parts: "
                                      f"{', '.join(str(p.number) for p in mp.parts)})")
        x, yy = chosen.x_mm, chosen.y_mm
        name = f"{name}#{chosen.number}"
    else:
        if part not in (None, 1):
            raise ImportFileError(name, f"file has a single profile; part {part} does not exist")
        x, yy = mp.x_mm, mp.y_mm
    y_mm = x - TAPE_CIRCLE_X_MM
    z_mm = yy.copy()
    lo, hi = FLANGE_WINDOW_MM
    flange = (y_mm >= lo) & (y_mm <= hi)
    if flange.sum() < 3:
        raise ImportFileError(name, f"not a wheel profile: no points at y between {lo:g} and "
                              f"{hi:g} mm (X {lo + 70:g}…{hi + 70:g} mm from the back face), "
                              "where the flange must be")
    if np.median(z_mm[flange]) < 0:
        z_mm = -z_mm
    tip = float(z_mm[flange].max())
    h_lo, h_hi = FLANGE_HEIGHT_RANGE_MM
    if not h_lo <= tip <= h_hi:
        raise ImportFileError(name, f"not a plausible wheel profile: flange height {tip:.2f} mm "
                              f"above the taperline is outside {h_lo:g}…{h_hi:g} mm")
    tape = np.abs(y_mm) <= 2.0
    if not tape.any() or np.abs(z_mm[tape]).min() > TAPE_CIRCLE_TOLERANCE_MM:
        raise ImportFileError(name, "not a plausible wheel profile: no point within "
                              f"{TAPE_CIRCLE_TOLERANCE_MM:g} mm of the taperline at X = 70 mm")
    if y_mm[0] > y_mm[-1]:
        y_mm, z_mm = y_mm[::-1].copy(), z_mm[::-1].copy()
    return y_mm, z_mm
