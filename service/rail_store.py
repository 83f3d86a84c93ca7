"""Measured rails in storage: import MiniProf rail files, read them back with their head wear,
and hand them to the physics (curve-radius tables, simulations) as the rail profile.

Import (:func:`import_rail_file`): the file is read by
:mod:`wearcast.service.readers.miniprof_rail`; every rail or roller profile in it is stored
with the file's own numbers, in one transaction (an error stores nothing); a profile already
stored (same file content and part) is answered as a duplicate and nothing is written; wheel
and other profiles are listed as skipped with the reason; a file with no rail is a 422.

Wear measures are derived on reading (``physics.rail_head_wear``), against the rail's stored
reference or the one asked for (``60E1``, ``UIC60``, ``60E2``, or ``rail:<id>``: another stored
rail, e.g. a measured new rail or a drawing, as uploaded reference).
"""

from __future__ import annotations

import hashlib
import io
import re
from pathlib import Path
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.physics.profiles.measured_rail import (
    NOMINAL_GAUGE_POINT_Y_MM,
    RAIL_KINDS,
    MeasuredRail,
    orient,
    shape_facts,
)
from wearcast.physics.rail_head_wear import (
    REFERENCE_NAMES,
    RailReference,
    rail_head_wear,
    reference_from_points,
)
from wearcast.service import models_db as db
from wearcast.service import rawfiles
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.id_text import decimal_id
from wearcast.service.importing import import_file_error
from wearcast.service.rail_schemas import (
    RailFrameOut,
    RailImportOut,
    RailOut,
    RailSkippedOut,
)
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.miniprof_rail import (
    GaugeSide,
    RailPart,
    instrument_wear,
    read_rail_file,
)

MAX_RAIL_FILE_BYTES = 20 * 1024 * 1024
#: Header W1/W2/W3 and recomputed wear further apart than this are reported [mm].
INSTRUMENT_WEAR_TOLERANCE_MM = 0.3
_REF_RAIL = re.compile(r"rail:([0-9]+)\Z")


def _f8(values: np.ndarray) -> bytes:
    return np.ascontiguousarray(values, dtype="<f8").tobytes()


def _from_f8(blob: bytes) -> np.ndarray:
    return np.frombuffer(blob, dtype="<f8").astype(float)


def parse_inclination(text: str | float | None, field: str = "inclination") -> float | None:
    """A laying inclination as a slope: ``1/40``, ``1:40``, ``0.025`` (None when not given)."""
    if text is None or (isinstance(text, str) and not text.strip()):
        return None
    if isinstance(text, int | float):
        value = float(text)
    else:
        found = re.match(r"^\s*1\s*[:/]\s*(\d+(?:\.\d+)?)\s*$", text)
        try:
            value = 1.0 / float(found.group(1)) if found else float(text)
        except (ValueError, ZeroDivisionError) as exc:
            raise Unprocessable(field, f"{text!r} is not a slope such as 1/40, 1:20 or "
                                "0.025") from exc
    if not 0.0 <= value <= 0.2:
        raise Unprocessable(field, f"{value:g} is not an inclination between 0 and 1/5")
    return value


def check_reference(session: Session, reference: str, field: str = "reference") -> str:
    """A valid reference name (``60E1``, ``UIC60``, ``60E2``, ``rail:<id>`` of a stored rail)."""
    ref = reference.strip()
    if ref.upper() in REFERENCE_NAMES:
        return ref.upper()
    if _REF_RAIL.match(ref):
        _reference_row(session, ref, field)
        return ref
    raise Unprocessable(field, f"unknown reference {reference!r}: give 60E1, UIC60, 60E2 or "
                        "rail:<id> (a stored rail)")


def _reference_row(session: Session, name: str, field: str) -> db.Rail:
    """The stored rail a ``rail:<id>`` reference (matched by ``_REF_RAIL``) names: 404
    naming ``field`` when there is none, an id beyond the 64-bit range of the id column
    included (never looked up: SQLite would overflow, answering for no field)."""
    digits = name.strip().removeprefix("rail:")
    rail_id = decimal_id(digits)
    row = None if rail_id is None else session.get(db.Rail, rail_id)
    if row is None:
        raise NotFound(field, f"no rail with id {digits[:40]} to use as reference")
    return row


def _rail_frame_points(row: db.Rail) -> tuple[np.ndarray, np.ndarray]:
    x, y = _from_f8(row.x_mm), _from_f8(row.y_mm)
    keep = np.ones(x.size, dtype=bool)
    keep[list(row.added_points or [])] = False
    return orient(x[keep], y[keep], row.gauge_side == "positive_x", bool(row.y_down))


def _reference(session: Session, name: str) -> RailReference | str:
    if not _REF_RAIL.match(name):
        return name
    ref_row = _reference_row(session, name, "reference")
    y, z = _rail_frame_points(ref_row)
    try:
        return reference_from_points(name, y, z, source=f"stored rail {ref_row.id} "
                                     f"({ref_row.name}, {ref_row.source_file}), its own frame")
    except ValueError as exc:
        raise Unprocessable("reference", str(exc)) from exc


def rail_out(session: Session, row: db.Rail, reference: str | None = None,
             include_points: bool = False) -> RailOut:
    """A stored rail with its frame facts and its head wear against ``reference`` (default:
    the rail's own)."""
    ref_name = check_reference(session, reference) if reference else row.reference
    y, z = _rail_frame_points(row)
    facts = shape_facts(y, z)
    wear = rail_head_wear(y, z, _reference(session, ref_name))
    frame = RailFrameOut(gauge_side=row.gauge_side,  # type: ignore[arg-type]
                         gauge_side_source=row.gauge_side_source, y_down=bool(row.y_down),
                         top_mm=facts.top_mm, gauge_point_mm=facts.gauge_point_mm,
                         head_width_mm=facts.head_width_mm, gauge_depth_mm=facts.gauge_depth_mm,
                         field_depth_mm=facts.field_depth_mm, inclination=row.inclination,
                         contact_shift_mm=None if facts.gauge_point_mm is None else (
                             NOMINAL_GAUGE_POINT_Y_MM - facts.gauge_point_mm[0],
                             -facts.top_mm[1]))
    out = RailOut(id=row.id, name=row.name, source_file=row.source_file,
                  part=row.part or None, kind=row.kind,  # type: ignore[arg-type]
                  origin=row.origin, layout=row.layout,  # type: ignore[arg-type]
                  measured_on=row.measured_on, instrument_serial=row.instrument_serial,
                  n_points=row.n_points, added_points=list(row.added_points or []),
                  point_notes=list(row.point_notes or []), header=dict(row.header or {}),
                  frame=frame, wear=wear,
                  warnings=list(row.warnings or []),
                  instrument_wear_mm=instrument_wear(dict(row.header or {})),
                  raw_path=row.raw_path,
                  created_at=row.created_at)
    if include_points:
        out.x_mm = _from_f8(row.x_mm).tolist()
        out.y_mm = _from_f8(row.y_mm).tolist()
        out.rail_y_mm, out.rail_z_mm = y.tolist(), z.tolist()
    return out


def _row(part: RailPart, file_name: str, layout: str, sha256: str, name: str | None,
         inclination: float | None, reference: str) -> db.Rail:
    label = part.label
    return db.Rail(
        name=name if name and part.number is None else (f"{name} #{part.number}" if name
                                                         else label),
        source_file=file_name, part=part.number or 0, sha256=sha256, kind=part.kind,
        layout=layout, origin=part.origin, header=dict(part.header),
        measured_on=part.measured_on, instrument_serial=part.instrument_serial,
        n_points=int(part.x_mm.size), x_mm=_f8(part.x_mm), y_mm=_f8(part.y_mm),
        added_points=[int(i) for i in np.nonzero(~part.measured)[0]],
        point_notes=[{"index": n.index, "line": n.line, "text": n.text, "added": n.added}
                     for n in part.notes],
        gauge_side=part.gauge_side, gauge_side_source=part.gauge_side_source,
        y_down=part.y_down, inclination=inclination, reference=reference,
        warnings=list(part.warnings) + [f"gauge side: {part.gauge_side_evidence}",
                                        f"which way Y runs: {part.y_sense_evidence}",
                                        f"kind: {part.kind_reason}"])


def import_rail_file(session: Session, data: bytes, file_name: str, *,
                     name: str | None = None, gauge_side: GaugeSide | None = None,
                     inclination: float | None = None, reference: str = "60E1",
                     raw_dir: Path | None = None) -> RailImportOut:
    """Import the rail profiles of one MiniProf file (module docstring); with ``raw_dir`` the
    file itself is kept there, content-addressed (``service.rawfiles``)."""
    if not data.strip():
        raise Unprocessable("file", f"{file_name} is empty")
    if len(data) > MAX_RAIL_FILE_BYTES:
        raise Unprocessable("file", f"{file_name} is larger than {MAX_RAIL_FILE_BYTES} bytes")
    reference = check_reference(session, reference)
    try:
        parsed = read_rail_file(data, file_name, gauge_side)
    except ImportFileError as exc:
        raise import_file_error(exc) from exc
    sha256 = hashlib.sha256(data).hexdigest()
    skipped = [RailSkippedOut(part=p.number, kind=p.kind, reason=p.kind_reason)  # type: ignore[arg-type]
               for p in parsed.parts if p.kind not in RAIL_KINDS]
    wanted = [p for p in parsed.parts if p.kind in RAIL_KINDS]
    if not wanted:
        raise Unprocessable("file", f"{file_name} holds no rail profile: " + "; ".join(
            (f"part {s.part}: " if s.part is not None else "") + s.reason for s in skipped))
    warnings: list[str] = []
    created: list[db.Rail] = []
    duplicates: list[db.Rail] = []
    for p in wanted:
        existing = session.scalar(select(db.Rail).where(db.Rail.sha256 == sha256,
                                                        db.Rail.part == (p.number or 0)))
        if existing is not None:
            duplicates.append(existing)
            given = {"gauge_side": gauge_side, "inclination": inclination}
            differs = [k for k, v in given.items()
                       if v is not None and v != getattr(existing, k)]
            if reference != existing.reference:
                differs.append("reference")
            if differs:
                warnings.append(f"{p.label}: already stored as rail {existing.id}; this "
                                f"import's {', '.join(differs)} differ(s) from the stored "
                                "one and were not applied (nothing new was written)")
            continue
        row = _row(p, file_name, parsed.layout, sha256, name, inclination, reference)
        session.add(row)
        created.append(row)
        warnings.extend(f"{p.label}: {w}" if not w.startswith(p.label) else w
                        for w in p.warnings)
        if p.kind == "roller":
            warnings.append(f"{p.label}: kind: {p.kind_reason}")
        if p.gauge_side_source != "assumed":
            warnings.append(f"{p.label}: gauge side {p.gauge_side} from the "
                            f"{p.gauge_side_source}: {p.gauge_side_evidence}")
    for s in skipped:
        part = f"{file_name}#{s.part}" if s.part is not None else file_name
        warnings.append(f"{part}: not imported: {s.reason}")
    if created:
        session.flush()
        for row in created:  # check that the physics can use every stored head
            y, z = _rail_frame_points(row)
            try:
                MeasuredRail(row.name, y, z, kind=row.kind)
            except ValueError as exc:
                session.rollback()
                raise Unprocessable("file", f"{row.name}: {exc}") from exc
        stored = rawfiles.store(raw_dir, io.BytesIO(data), sha256) if raw_dir else None
        for row in created:
            row.raw_path = stored.relative_path if stored else None
        try:
            session.commit()
        except IntegrityError:
            # the same file was imported concurrently: answer as a repeated import
            session.rollback()
            return import_rail_file(session, data, file_name, name=name,
                                    gauge_side=gauge_side, inclination=inclination,
                                    reference=reference, raw_dir=raw_dir)
        except Exception:
            session.rollback()
            if stored is not None and stored.created:
                (raw_dir / stored.relative_path).unlink(missing_ok=True)  # type: ignore[operator]
            raise
    created_out = [rail_out(session, r) for r in created]
    for out in created_out:
        if not out.wear.reference_fits:
            warnings.append(f"{out.name}: does not fit its reference {out.wear.reference} ("
                            + "; ".join(out.wear.mismatch) + "): its head wear measures are "
                            "not wear; give another reference (GET /v1/rails/"
                            f"{out.id}?reference=...)")
        elif out.wear.placement.fitted or out.wear.placement.flank_offset_mm is None:
            warnings.append(f"{out.name}: {out.wear.placement.method}")
        ours = {"W1": out.wear.vertical.value_mm, "W2": out.wear.lateral.value_mm,
                "W3": out.wear.corner_45.value_mm}
        for key, theirs in out.instrument_wear_mm.items():
            mine = ours[key]
            if mine is None or abs(mine - theirs) > INSTRUMENT_WEAR_TOLERANCE_MM:
                warnings.append(
                    f"{out.name}: header {key}={theirs:g} mm, recomputed against "
                    f"{out.wear.reference}: " + ("not measurable" if mine is None else
                                                 f"{mine:.2f} mm") + " (beyond "
                    f"{INSTRUMENT_WEAR_TOLERANCE_MM:g} mm: another reference, datum or "
                    "definition; both are kept)")
    return RailImportOut(file_name=file_name, sha256=sha256,
                         created=created_out,
                         duplicates=[rail_out(session, r) for r in duplicates],
                         skipped=skipped, warnings=warnings)


def get_rail_row(session: Session, rail_id: int, field: str = "rail_id") -> db.Rail:
    row = session.get(db.Rail, rail_id)
    if row is None:
        raise NotFound(field, f"no rail with id {rail_id}")
    return row


def list_rails(session: Session, limit: int = 100, offset: int = 0,
               reference: str | None = None) -> list[RailOut]:
    rows = session.scalars(select(db.Rail).order_by(db.Rail.id).limit(limit).offset(offset))
    return [rail_out(session, r, reference) for r in rows]


def rail_spec(session: Session, rail_id: int, field: str = "rail_id") -> dict[str, Any]:
    """What a job needs of a stored rail to run without the database: its rail-frame points
    (added points left out), kind, name and stated inclination."""
    row = get_rail_row(session, rail_id, field)
    y, z = _rail_frame_points(row)
    return {"rail_id": row.id, "name": row.name, "kind": row.kind,
            "inclination": row.inclination, "y_mm": y.tolist(), "z_mm": z.tolist(),
            "placement": "gauge point (14 mm below its top) at the track gauge"}


def measured_rail_from_spec(spec: dict[str, Any]) -> MeasuredRail:
    """The physics rail of :func:`rail_spec` (raises ValueError phrased ``rail_id: ...``)."""
    try:
        return MeasuredRail(f"{spec['name']} (rail {spec['rail_id']})",
                            np.asarray(spec["y_mm"], float), np.asarray(spec["z_mm"], float),
                            kind=spec.get("kind", "rail"), inclination=spec.get("inclination"))
    except ValueError as exc:
        raise ValueError(f"rail_id: {exc}") from exc


def measured_rail(session: Session, rail_id: int, field: str = "rail_id") -> MeasuredRail:
    """A stored rail as the physics' rail profile (404 naming ``field`` when absent)."""
    try:
        return measured_rail_from_spec(rail_spec(session, rail_id, field))
    except ValueError as exc:
        raise Unprocessable(field, str(exc).removeprefix("rail_id: ")) from exc


#: The request fields that name a stored rail, in the order of :func:`with_rails`' rails.
RAIL_FIELDS = ("rail_id", "high_rail_id", "low_rail_id")


def requested_rails(session: Session, body: Any
                    ) -> tuple[MeasuredRail | None, MeasuredRail | None, MeasuredRail | None]:
    """The stored rails a physics request names (``rail_id``, ``high_rail_id``,
    ``low_rail_id``; None where not given): 404 naming the field for an unknown id, 422 when
    two of them state different laying inclinations (a track has one)."""
    rails = tuple(None if getattr(body, f) is None else measured_rail(session, getattr(body, f), f)
                  for f in RAIL_FIELDS)
    stated = [(f, r.inclination) for f, r in zip(RAIL_FIELDS, rails, strict=True)
              if r is not None and r.inclination is not None]
    for field, inclination in stated[1:]:
        first_field, first = stated[0]
        if abs(inclination - first) > 1e-9:
            raise Unprocessable(field, f"the rail states inclination {inclination:g} where "
                                f"{first_field}'s states {first:g}: the rails of one track are "
                                "laid at one inclination")
    return rails[0], rails[1], rails[2]


def with_rails(vehicle: Any, rail: MeasuredRail | None, high: MeasuredRail | None = None,
               low: MeasuredRail | None = None) -> Any:
    """The vehicle on measured rails: ``rail`` as its rail profile (tangent track, and curves
    where no high or low rail is given), ``high`` / ``low`` as the outer / inner rail of every
    curve (``BogieVehicle.high_rail_profile`` / ``low_rail_profile``), laid at the inclination
    they state (:func:`requested_rails` checked that they agree)."""
    changes: dict[str, Any] = {}
    for key, given in (("rail_profile", rail), ("high_rail_profile", high),
                       ("low_rail_profile", low)):
        if given is not None:
            changes[key] = given
            if given.inclination is not None:
                changes["rail_inclination"] = given.inclination
    return vehicle.with_(**changes) if changes else vehicle


def with_rail(vehicle: Any, rail: MeasuredRail | None) -> Any:
    """The vehicle with the measured rail as its rail profile (and the rail's stated
    inclination, when it has one)."""
    return with_rails(vehicle, rail)
