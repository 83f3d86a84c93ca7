"""MiniProf rail files: ``.ban`` and the rail-shaped parts of multi-part ``.mpt`` files.

The bytes are parsed by :func:`wearcast.service.readers.miniprof.parse_miniprof` (the same
low-level reader as wheel files); this module decides, per profile, what it is and how it is
oriented, and keeps the points exactly as the file gives them:

* **kind** from the data: a wheel (it passes the wheel reader's flange and taperline checks),
  a rail head (``physics.profiles.measured_rail.RailShapeFacts.is_rail_head``), a **roller**
  (rail-shaped, and the file name or comment says roller: a roller of a roller rig standing
  in for the rail), or ``other`` (e.g. a 34 mm wide head beside a rail in a switch drawing),
  with the reasons;
* **which way Y runs** (MiniProf rail files differ: the flanks below the crown tell);
* **which side is the gauge side**: the request's ``gauge_side`` if given, else a point note
  that names the gauge face, else the side measured clearly deeper (the instrument measures
  the gauge face down to the gauge point, the field side often less), else an assumption
  (negative X), always stated;
* **notes on points**: a data line with words after its numbers (``" zig-zag pattern``,
  ``add point to extend gauge face``) is kept with its line number; a note saying a point was
  ADDED marks a point that was not measured: it is stored but left out of the profile used
  for wear measures and contact.

Quoted header lines (``"ColumnDef=X,Y,A"``) are comments, as MiniProf writes them: a later
unquoted line of the same key wins. Nothing here moves, smooths or drops a measured point.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from datetime import date
from typing import Literal

import numpy as np

from wearcast.physics.profiles.measured_rail import (
    DEPTH_EVIDENCE_MM,
    RailKind,
    RailShapeFacts,
    orient,
    shape_facts,
    side_depths,
    vertical_sense,
)
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.miniprof import (
    MiniProfFile,
    _decode,
    _key_value,
    _numbers,
    _parse_date,
    declared_count_differs,
    parse_miniprof,
    to_wheel_frame,
)

RAIL_FILE_EXTENSIONS = (".ban", ".mpt")
GaugeSide = Literal["negative_x", "positive_x"]
#: What a profile of a rail file is: a rail head (``MeasuredRail``'s kinds) or not one.
NotRailKind = Literal["wheel", "other"]
PartKind = RailKind | NotRailKind
_ADDED = re.compile(r"\badd(ed|ing)?\b|\bby hand\b|\bmanual", re.IGNORECASE)


@dataclass(frozen=True)
class PointNote:
    """Words written after a point's numbers: 0-based point ``index``, file ``line``, the
    ``text``, and whether it says the point was added (not measured)."""

    index: int
    line: int
    text: str
    added: bool


@dataclass(frozen=True)
class RailPart:
    """One profile of a rail file, points as the file gives them.

    ``number`` the ``.mpt`` part (None for single-profile files); ``label`` file[#part];
    ``x_mm``/``y_mm`` instrument X, Y [mm] in file order; ``kind`` and ``kind_reason``;
    ``y_down`` and ``gauge_at_positive_x`` the orientation with their evidence and
    ``gauge_side_source`` (``request``, ``point note``, ``depth``, ``assumed``); ``notes`` on
    points; ``measured`` (bool per point) False for points a note says were added;
    ``facts`` of the oriented measured points (None when there is no head to describe).
    """

    number: int | None
    label: str
    header: dict[str, str]
    x_mm: np.ndarray
    y_mm: np.ndarray
    kind: PartKind
    kind_reason: str
    y_down: bool
    y_sense_evidence: str
    gauge_at_positive_x: bool
    gauge_side_source: str
    gauge_side_evidence: str
    notes: tuple[PointNote, ...]
    measured: np.ndarray
    facts: RailShapeFacts | None
    measured_on: date | None
    instrument_serial: str | None
    origin: str
    warnings: tuple[str, ...]

    @property
    def gauge_side(self) -> GaugeSide:
        return "positive_x" if self.gauge_at_positive_x else "negative_x"

    def rail_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Measured points (added ones left out) in the rail frame of
        ``physics.profiles.measured_rail`` (mirrored / sign-fixed only), gauge side first."""
        return orient(self.x_mm[self.measured], self.y_mm[self.measured],
                      self.gauge_at_positive_x, self.y_down)


def instrument_wear(header: dict[str, str]) -> dict[str, float]:
    """The instrument's own head wear values W1, W2, W3 [mm] where the header holds numbers
    (MiniProf rail files; empty in many files)."""
    out = {}
    for key in ("W1", "W2", "W3"):
        try:
            value = float(header.get(key, "").strip())
        except ValueError:
            continue
        if np.isfinite(value):
            out[key] = value
    return out


@dataclass(frozen=True)
class RailFile:
    """A parsed rail file: its layout, file-level header and profiles."""

    file_name: str
    layout: str
    header: dict[str, str]
    parts: tuple[RailPart, ...]


def _header_without_quoted(text: str) -> dict[str, str]:
    """Header of a regular layout with quoted lines treated as comments (later wins)."""
    header: dict[str, str] = {}
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped:
            if header:
                break
            continue
        if stripped.startswith('"'):
            continue
        pair = _key_value(stripped)
        if pair is None:
            if len(_numbers(stripped)) >= 2:
                break
            continue
        header[pair[0]] = pair[1]
    return header


def _point_notes(text: str, n_points: int) -> tuple[tuple[PointNote, ...], str | None]:
    """Notes after the numbers of data lines (regular and old layouts); (notes, warning)."""
    lines = text.splitlines()
    data: list[tuple[int, str]] = []
    started = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        if not started:
            if stripped and _key_value(stripped) is None and not stripped.startswith('"') \
                    and len(_numbers(stripped)) >= 2:
                started = True
            else:
                continue
        if stripped:
            data.append((i + 1, stripped))
    if len(data) != n_points:
        return (), (f"could not match the {len(data)} data lines with the {n_points} points "
                    "read: notes after points are not reported")
    notes = []
    for index, (number, stripped) in enumerate(data):
        tokens = re.split(r"[,;\s]+", stripped)
        values = _numbers(stripped)
        rest = stripped
        for _ in values:  # cut the leading numbers off, keep the words
            rest = rest.lstrip(" ,;\t")
            rest = re.sub(r"^[^\s,;]+", "", rest, count=1)
        rest = rest.strip(" ,;\t").lstrip('"').strip()
        if rest and len(tokens) > len(values):
            notes.append(PointNote(index, number, rest, bool(_ADDED.search(rest))))
    return tuple(notes), None


def _is_wheel(mp: MiniProfFile, part: int | None) -> bool:
    try:
        to_wheel_frame(dataclasses.replace(mp, is_rail=False), part)
    except ImportFileError:
        return False
    return True


def _gauge_side(x: np.ndarray, height: np.ndarray, measured: np.ndarray,
                notes: tuple[PointNote, ...], request: GaugeSide | None
                ) -> tuple[bool, str, str]:
    """(gauge at positive X, source, evidence); depths from the measured points only."""
    x_top, _, d_neg, d_pos = side_depths(x[measured], height[measured])
    if request is not None:
        return request == "positive_x", "request", f"gauge_side={request} given with the import"
    for note in notes:
        if "gauge" in note.text.lower() and note.index < len(x):
            positive = bool(x[note.index] > x_top)
            return positive, "point note", (
                f"line {note.line} says {note.text!r} at X = {x[note.index]:g} mm, "
                f"{'right' if positive else 'left'} of the top (X = {x_top:g} mm)")
    if abs(d_pos - d_neg) >= DEPTH_EVIDENCE_MM:
        positive = d_pos > d_neg
        return positive, "depth", (
            f"the {'positive' if positive else 'negative'}-X side is measured "
            f"{max(d_pos, d_neg):.1f} mm below the top, the other {min(d_pos, d_neg):.1f} mm: "
            "the deeper side is taken as the gauge face (measured down to the gauge point)")
    return False, "assumed", (
        f"both sides are measured about as deep ({d_neg:.1f} and {d_pos:.1f} mm) and no note "
        "names the gauge face: the gauge side is ASSUMED at negative X (give gauge_side to "
        "say otherwise)")


def _part(mp: MiniProfFile, number: int | None, header: dict[str, str], x: np.ndarray,
          y: np.ndarray, notes: tuple[PointNote, ...], file_warnings: list[str],
          gauge_request: GaugeSide | None) -> RailPart:
    label = mp.file_name if number is None else f"{mp.file_name}#{number}"
    warnings = list(file_warnings)
    measured = np.ones(x.size, dtype=bool)
    for note in notes:
        if note.added:
            measured[note.index] = False
            warnings.append(f"line {note.line}: point ({x[note.index]:g}, {y[note.index]:g}) "
                            f"is noted {note.text!r}: added by hand, not measured; stored, "
                            "left out of the wear measures and the contact")
        else:
            warnings.append(f"line {note.line}: point note {note.text!r} (point kept)")
    xm, ym = x[measured], y[measured]
    y_down, y_evidence = vertical_sense(xm, ym)
    gauge_positive, source, evidence = _gauge_side(x, -y if y_down else y, measured, notes,
                                                   gauge_request)
    if source == "assumed":
        warnings.append(evidence)
    facts: RailShapeFacts | None = None
    program = header.get("ProgramName", "").strip()
    origin = "drawing" if program.lower().startswith("autocad") else "instrument"
    if origin == "drawing":
        warnings.append(f"{label}: made by {program} {header.get('ProgramVer', '')}".rstrip()
                        + ": a drawing, not an instrument measurement")
    serial = (header.get("MPSerNo") or "").strip() or None
    if serial == "0":
        serial = None
    if serial is None and origin == "instrument":
        warnings.append(f"{label}: no instrument serial (MPSerNo empty or 0): where the points "
                        "come from is not recorded")
    gauge_depth = header.get("RailGaugePoint", "").strip()
    try:
        if gauge_depth and abs(float(gauge_depth) - 14.0) > 1e-6:
            warnings.append(f"{label}: the instrument's gauge point is RailGaugePoint="
                            f"{gauge_depth} mm below the top; wearcast takes it 14 mm below "
                            "(EN 13848-1)")
    except ValueError:
        warnings.append(f"{label}: RailGaugePoint={gauge_depth!r} is not a number (ignored)")
    if _is_wheel(mp, number):
        kind: PartKind = "wheel"
        reason = ("a wheel: it has a flange and a taperline where the wheel reader looks for "
                  "them; import it through POST /v1/measurements/import")
    else:
        yr, zr = orient(xm, ym, gauge_positive, y_down)
        facts = shape_facts(yr, zr)
        is_head, why = facts.is_rail_head()
        name_words = f"{mp.file_name} {header.get('Comment', '')}".lower()
        if not is_head:
            kind, reason = "other", f"not a rail head: {why}"
        elif "roller" in name_words:
            kind, reason = "roller", (
                "a roller (the file name or comment says so) with a rail-shaped head: "
                f"{why}; it stands in for a rail, its rolling-direction curvature is not "
                "modelled")
        else:
            kind, reason = "rail", f"a rail head: {why}"
    return RailPart(
        number=number, label=label, header=header, x_mm=x, y_mm=y, kind=kind,
        kind_reason=reason, y_down=y_down, y_sense_evidence=y_evidence,
        gauge_at_positive_x=gauge_positive, gauge_side_source=source,
        gauge_side_evidence=evidence, notes=notes, measured=measured, facts=facts,
        measured_on=_parse_date(header.get("Date")) or mp.measured_on,
        instrument_serial=serial, origin=origin, warnings=tuple(warnings))


def read_rail_file(data: bytes, file_name: str,
                   gauge_side: GaugeSide | None = None) -> RailFile:
    """Parse a MiniProf rail file (``.ban``, or ``.mpt`` whose parts may be rails).

    Every profile is returned with its kind; callers import the ``rail``/``roller`` ones and
    report the others with their ``kind_reason``. Raises ImportFileError (file, line, field)
    for a file that cannot be read.
    """
    if file_name.lower().endswith(".whl"):
        raise ImportFileError(file_name, "a MiniProf wheel file (.whl): import it through "
                              "POST /v1/measurements/import", field="file")
    if not file_name.lower().endswith(RAIL_FILE_EXTENSIONS):
        raise ImportFileError(file_name, "expected a MiniProf rail file (.ban, or .mpt with "
                              "rail profiles)", field="file")
    mp = parse_miniprof(data, file_name)
    text = _decode(data)
    parts: list[RailPart] = []
    if mp.layout == "mpt":
        file_header = {k: v for k, v in mp.header.items()
                       if k not in mp.parts[0].header}
        for p in mp.parts:
            file_warnings = []
            declared = p.header.get("XYPoints", "").strip()
            if declared_count_differs(declared, p.x_mm.size):
                file_warnings.append(f"{file_name}#{p.number}: header says XYPoints="
                                     f"{declared}, {p.x_mm.size} points read")
            parts.append(_part(mp, p.number, p.header, p.x_mm, p.y_mm, (), file_warnings,
                               gauge_side))
        return RailFile(file_name, mp.layout, file_header, tuple(parts))
    header = _header_without_quoted(text) if mp.layout == "regular" else dict(mp.header)
    notes, note_warning = _point_notes(text, mp.x_mm.size)
    file_warnings = [note_warning] if note_warning else []
    declared = header.get("XYPoints", "").strip()
    if declared_count_differs(declared, mp.x_mm.size):
        added = sum(n.added for n in notes)
        file_warnings.append(f"header says XYPoints={declared}, {mp.x_mm.size} points read"
                             + (f" ({added} noted as added by hand)" if added else ""))
    parts.append(_part(mp, None, header, mp.x_mm, mp.y_mm, notes, file_warnings, gauge_side))
    return RailFile(file_name, mp.layout, header, tuple(parts))
