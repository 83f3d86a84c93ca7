"""A stored wheel measurement as the physics' wheel profile (curve-radius tables, simulations).

The stored points are read, placed in the wheel frame as their wear was (by the instrument's
datum where the import found one, else by the free fit to the reference, which the answer
says) and handed to the physics as a ``MeasuredWheel``; the measurement itself is not changed.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.physics.profiles.measured_wheel import MeasuredWheel
from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.float32_blobs import floats_of


def processed_measurement(session: Session, measurement_id: int,
                          field: str = "measurement_id") -> tuple[db.Measurement, Any, Any]:
    """(the stored row, its profile processed again against its stored reference, that
    reference's height function): placed by the instrument's datum where the import found one.

    404 naming ``field`` when there is no such measurement; 422 when it has no profile or the
    profile cannot be processed.
    """
    from wearcast.service.reference_store import height_of, stored_reference_spec
    from wearcast.statistics.processing import process_profile

    m = session.get(db.Measurement, measurement_id)
    if m is None:
        raise NotFound(field, f"no measurement {measurement_id}")
    if m.kind != "profile" or m.y_mm is None or m.z_mm is None:
        raise Unprocessable(field, f"measurement {measurement_id} has no profile points "
                                   f"(kind {m.kind!r})")
    y, z = floats_of(m.y_mm), floats_of(m.z_mm)
    datum = (m.placement or {}).get("alignment") == "datum"
    height = height_of(stored_reference_spec(session, m.reference_profile))
    try:
        p = process_profile(y, z, reference_height=height,
                            alignment="datum" if datum else "free")
    except ValueError as exc:
        raise Unprocessable(field, f"measurement {measurement_id}: profile cannot be "
                                   f"processed: {exc}") from None
    return m, p, height


def measured_wheel(session: Session, measurement_id: int, field: str = "measurement_id"
                   ) -> tuple[MeasuredWheel, dict[str, Any]]:
    """(the wheel, what it was taken from) for a stored profile measurement (404 / 422 naming
    ``field``, also when the profile cannot serve as a wheel)."""
    m, p, _ = processed_measurement(session, measurement_id, field)
    datum = (m.placement or {}).get("alignment") == "datum"
    try:
        wheel = MeasuredWheel(f"{m.wheel_id} at {m.mileage_km:,.0f} km (measurement "
                              f"{measurement_id})", p.y_aligned_mm, p.z_aligned_mm)
    except ValueError as exc:
        raise Unprocessable(field, f"measurement {measurement_id}: {exc}") from None
    info = {"measurement_id": measurement_id, "wheel_id": m.wheel_id,
            "mileage_km": m.mileage_km, "source_file": m.source_file,
            "reference_profile": m.reference_profile,
            "placement": ("instrument datum (vertical shift only)" if datum else
                          "free fit to the reference (no datum found at import)"),
            "y_range_mm": [float(wheel.y_mm[0]), float(wheel.y_mm[-1])],
            "on": "every wheel of every wheelset"}
    return wheel, info


def latest_profile_id(session: Session, wheel_id: str, field: str = "wheel_id") -> int:
    """The id of a wheel's latest profile measurement (404 / 422 naming ``field``)."""
    if session.get(db.Wheel, wheel_id) is None:
        raise NotFound(field, f"no wheel {wheel_id!r}")
    found = session.scalar(
        select(db.Measurement.id).where(db.Measurement.wheel_id == wheel_id,
                                        db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km.desc(), db.Measurement.id.desc()).limit(1))
    if found is None:
        raise Unprocessable(field, f"wheel {wheel_id!r} has no measured profile")
    return int(found)


def uploaded_wheel(y_mm: list[float], z_mm: list[float], reference_profile: str,
                   field: str = "profile") -> tuple[MeasuredWheel, dict[str, Any]]:
    """A wheel profile sent with the request (wheel frame, placed by its own datum)."""
    from wearcast.physics.profiles.references import canonical_s1002_name
    from wearcast.service.reference_store import ReferenceSpec, height_of
    from wearcast.statistics.processing import process_profile

    if len(y_mm) != len(z_mm):
        raise Unprocessable(f"{field}.z_mm", f"has {len(z_mm)} values, y_mm {len(y_mm)}")
    name = canonical_s1002_name(reference_profile)
    if name is None:
        raise Unprocessable(f"{field}.reference_profile", "only the built-in S1002 family is "
                            "accepted here; store the profile to use an uploaded reference")
    try:
        p = process_profile(np.asarray(y_mm, float), np.asarray(z_mm, float),
                            reference_height=height_of(ReferenceSpec(name, "builtin")),
                            alignment="datum")
        wheel = MeasuredWheel("uploaded profile", p.y_aligned_mm, p.z_aligned_mm)
    except ValueError as exc:
        raise Unprocessable(f"{field}.y_mm", f"not a usable wheel profile: {exc}") from None
    return wheel, {"measurement_id": None, "wheel_id": None, "source_file": None,
                   "reference_profile": name, "placement": "instrument datum (uploaded)",
                   "y_range_mm": [float(wheel.y_mm[0]), float(wheel.y_mm[-1])],
                   "on": "every wheel of every wheelset"}


def requested_wheel(session: Session, body: Any) -> tuple[MeasuredWheel, dict[str, Any]] | None:
    """The measured wheel a request names (``wheel_id``, ``measurement_id`` or ``profile``,
    at most one, checked by the schema), or None for the preset's S1002."""
    if body.profile is not None:
        return uploaded_wheel(body.profile.y_mm, body.profile.z_mm,
                              body.profile.reference_profile)
    if body.wheel_id is not None:
        return measured_wheel(session, latest_profile_id(session, body.wheel_id), "wheel_id")
    if body.measurement_id is not None:
        return measured_wheel(session, body.measurement_id)
    return None
