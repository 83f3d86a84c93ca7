"""Reference profiles in the service: the built-in S1002 family, user-given ones, and a
wheel's own first measurement as its baseline.

A measurement's ``reference_profile`` names one of:

* a built-in (:mod:`wearcast.physics.profiles.references`): ``S1002`` and its EN 13715
  flange-thickness variants ``S1002/31.5`` … ``S1002/28.5`` (usual spellings accepted);
* a profile uploaded with ``POST /v1/reference-profiles`` (points of a drawing or of a
  measured new wheel), by its name;
* ``own`` (also ``first-measurement``, ``baseline``): the wheel's own first profile
  measurement (lowest mileage) — the measurement after its last turning, when a wheel's
  series starts there.

``ReferenceSpec`` is the small, picklable description that import worker processes turn
into a height function (:func:`height_of`, cached).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.physics.profiles.references import (
    HeightFunction,
    builtin_reference,
    builtin_references,
    canonical_s1002_name,
    points_height,
)
from wearcast.service import models_db as db
from wearcast.service.errors import Unprocessable
from wearcast.service.float32_blobs import f32, floats_of
from wearcast.service.id_text import decimal_id
from wearcast.service.import_worker import finite_or_none

#: Names that mean "the wheel's own first measurement".
OWN_BASELINE_NAMES = ("own", "first-measurement", "first_measurement", "baseline")
#: Canonical name stored for the own-baseline reference.
OWN_BASELINE = "own"


@dataclass(frozen=True)
class ReferenceSpec:
    """A resolved reference: ``name`` (canonical), ``kind`` (``builtin`` | ``points``) and,
    for points, the points [mm] as tuples (sorted by y, distinct)."""

    name: str
    kind: str
    y_mm: tuple[float, ...] = ()
    z_mm: tuple[float, ...] = ()


@lru_cache(maxsize=64)
def height_of(spec: ReferenceSpec) -> HeightFunction:
    """The height function z(y) [mm] of a resolved reference (the same object per spec)."""
    if spec.kind == "builtin":
        ref = builtin_reference(spec.name)
        assert ref is not None
        return ref.height_mm
    return points_height(np.asarray(spec.y_mm), np.asarray(spec.z_mm))


def _from_blobs(y: bytes, z: bytes) -> tuple[tuple[float, ...], tuple[float, ...]]:
    return tuple(floats_of(y).tolist()), tuple(floats_of(z).tolist())


def is_own_baseline(name: str) -> bool:
    return name.strip().lower() in OWN_BASELINE_NAMES


def resolve_reference(session: Session, name: str, field: str = "reference_profile"
                      ) -> ReferenceSpec:
    """The reference ``name`` names (not the own baseline: see :func:`own_baseline_spec`).

    Raises Unprocessable naming ``field`` when the name is unknown.
    """
    try:
        canonical = canonical_s1002_name(name)
        if canonical is not None:
            builtin_reference(canonical)
            return ReferenceSpec(canonical, "builtin")
    except ValueError as exc:
        raise Unprocessable(field, str(exc)) from None
    row = session.scalar(select(db.ReferenceProfile).where(db.ReferenceProfile.name == name))
    if row is None:
        known = ", ".join(r.name for r in builtin_references())
        raise Unprocessable(field, f"reference profile {name!r} is not in the catalogue "
                            f"(built in: {known}; or one uploaded at POST "
                            "/v1/reference-profiles; or 'own' for the wheel's first "
                            "measurement)")
    y, z = _from_blobs(row.y_mm, row.z_mm)
    return ReferenceSpec(row.name, "points", y, z)


def own_baseline_spec(session: Session, wheel_id: str) -> tuple[ReferenceSpec, int] | None:
    """The wheel's first profile measurement (lowest mileage) as a reference, and its id;
    None when the wheel has no stored profile."""
    row = session.execute(
        select(db.Measurement.id, db.Measurement.y_mm, db.Measurement.z_mm)
        .where(db.Measurement.wheel_id == wheel_id, db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km, db.Measurement.id).limit(1)).first()
    if row is None or row[1] is None or row[2] is None:
        return None
    return _measurement_spec(row[0], row[1], row[2]), row[0]


def _measurement_spec(measurement_id: int, y_blob: bytes, z_blob: bytes) -> ReferenceSpec:
    from wearcast.statistics.cleaning import clean_profile

    cleaned = clean_profile(floats_of(y_blob), floats_of(z_blob))
    return ReferenceSpec(f"own:{measurement_id}", "points", tuple(cleaned.y_mm.tolist()),
                         tuple(cleaned.z_mm.tolist()))


def stored_reference_spec(session: Session, name: str) -> ReferenceSpec:
    """The reference a stored measurement names: a catalogue name, an uploaded one, or
    ``own:<measurement id>`` (a wheel's own baseline)."""
    if name.startswith("own:") and decimal_id(name[4:]) is not None:
        row = session.get(db.Measurement, decimal_id(name[4:]))
        if row is None or row.y_mm is None or row.z_mm is None:
            raise Unprocessable("reference_profile", f"baseline measurement {name[4:]} is "
                                "gone")
        return _measurement_spec(row.id, row.y_mm, row.z_mm)
    return resolve_reference(session, name)


# ----------------------------------------------------------------------- user references


def create_reference(session: Session, name: str, y_mm: list[float], z_mm: list[float],
                     description: str | None, source: str | None) -> dict[str, Any]:
    """Store a user reference from points [mm] in the wheel frame (cleaned, checked)."""
    from wearcast.physics.profiles.parameters import flange_parameters
    from wearcast.statistics.cleaning import clean_profile

    name = name.strip()
    if not name:
        raise Unprocessable("name", "is empty")
    if canonical_s1002_name(name) is not None or is_own_baseline(name):
        raise Unprocessable("name", f"{name!r} is a built-in reference name; choose another")
    if len(y_mm) != len(z_mm):
        raise Unprocessable("z_mm", f"has {len(z_mm)} values, y_mm has {len(y_mm)}")
    try:
        cleaned = clean_profile(np.asarray(y_mm, float), np.asarray(z_mm, float))
    except ValueError as exc:
        raise Unprocessable("y_mm", f"points are not a usable wheel profile: {exc}") from None
    if session.scalar(select(db.ReferenceProfile.id)
                      .where(db.ReferenceProfile.name == name)) is not None:
        raise Unprocessable("name", f"a reference profile named {name!r} exists already")
    params = flange_parameters(cleaned.y_mm, cleaned.z_mm)
    row = db.ReferenceProfile(
        name=name, description=description, source=source, n_points=int(cleaned.y_mm.size),
        y_mm=f32(cleaned.y_mm), z_mm=f32(cleaned.z_mm),
        sd_mm=finite_or_none(params.sd_mm), sh_mm=finite_or_none(params.sh_mm),
        qr_mm=finite_or_none(params.qr_mm))
    session.add(row)
    session.commit()
    return reference_out(row)


def reference_out(row: db.ReferenceProfile) -> dict[str, Any]:
    return {"name": row.name, "kind": "points", "description": row.description,
            "source": row.source, "n_points": row.n_points, "sd_mm": row.sd_mm,
            "sh_mm": row.sh_mm, "qr_mm": row.qr_mm,
            "checksum": hashlib.sha256(row.y_mm + row.z_mm).hexdigest()[:16]}


def list_references(session: Session) -> list[dict[str, Any]]:
    """The catalogue: built-ins first, then the stored ones by name."""
    out: list[dict[str, Any]] = []
    for ref in builtin_references():
        p = ref.parameters
        out.append({"name": ref.name, "kind": "builtin", "description": ref.description,
                    "source": "EN 13715", "n_points": None, "sd_mm": round(p.sd_mm, 3),
                    "sh_mm": round(p.sh_mm, 3), "qr_mm": round(p.qr_mm, 3), "checksum": None})
    for row in session.scalars(select(db.ReferenceProfile).order_by(db.ReferenceProfile.name)):
        out.append(reference_out(row))
    return out
